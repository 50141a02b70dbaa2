#include "nestlight/octree/error.h"

#include <cstdio>
#include <cstdlib>

namespace nestlight {

void checkFailed(const char* expr, const char* file, int line, const std::string& msg) {
  std::fprintf(stderr, "nestlight: internal check failed at %s:%d: %s%s%s\n", file, line, expr,
               msg.empty() ? "" : ": ", msg.c_str());
  std::abort();
}

}  // namespace nestlight
