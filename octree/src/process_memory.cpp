// The process's peak memory, for the reports of long jobs (conversion, HDR expansion).
#include "nestlight/octree/process_memory.h"

#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace nestlight {

// VmHWM, the high-water mark of this address space: getrusage's ru_maxrss would do for a process
// that was never exec'd, but Linux carries the pre-exec mark across execve, so a child that
// `bench hdr` or `bench convert` spawns would report its parent's memory as its own.
uint64_t peakRssBytes() {
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    uint64_t kb = 0;
    bool found = false;
    while (std::fgets(line, sizeof line, f))
      if (std::strncmp(line, "VmHWM:", 6) == 0)
        kb = std::strtoull(line + 6, nullptr, 10), found = true;
    std::fclose(f);
    if (found) return kb * 1024;
  }
  struct rusage ru {};
  ::getrusage(RUSAGE_SELF, &ru);
  return static_cast<uint64_t>(ru.ru_maxrss) * 1024;
}

}  // namespace nestlight
