// Payload and hierarchy checksums: XXH3-64 (libxxhash), fast enough to check every read.
#pragma once

#include <cstddef>
#include <cstdint>

namespace nestlight {
uint64_t checksum64(const void* data, size_t size);
}
