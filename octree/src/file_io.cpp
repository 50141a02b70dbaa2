#include "file_io.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "nestlight/octree/error.h"

namespace nestlight::detail {

void pwriteAll(int fd, const void* data, size_t size, uint64_t offset, const std::string& path) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    const ssize_t w = ::pwrite(fd, p, size, static_cast<off_t>(offset));
    if (w < 0) {
      if (errno == EINTR) continue;
      throw Error(path, Error::atByte(offset),
                  std::string("write failed: ") + std::strerror(errno));
    }
    p += w;
    size -= size_t(w);
    offset += uint64_t(w);
  }
}

void preadAll(int fd, void* data, size_t size, uint64_t offset, const std::string& path) {
  uint8_t* p = static_cast<uint8_t*>(data);
  while (size > 0) {
    const ssize_t r = ::pread(fd, p, size, static_cast<off_t>(offset));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0)
      throw Error(path, Error::atByte(offset),
                  r == 0 ? "file ends early" : std::string("read failed: ") + std::strerror(errno));
    p += r;
    size -= size_t(r);
    offset += uint64_t(r);
  }
}

}  // namespace nestlight::detail
