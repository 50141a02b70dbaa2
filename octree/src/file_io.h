// Whole reads and writes at an offset (pread/pwrite until done, EINTR retried): the octree's
// payload, hierarchy and layer files all go through these. Internal to nestlight_octree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace nestlight::detail {

// Throws nestlight::Error naming `path` and the byte offset on failure.
void pwriteAll(int fd, const void* data, size_t size, uint64_t offset, const std::string& path);
// Also throws when the file ends before `size` bytes ("file ends early").
void preadAll(int fd, void* data, size_t size, uint64_t offset, const std::string& path);

}  // namespace nestlight::detail
