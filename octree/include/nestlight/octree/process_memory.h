// The process's peak memory, which conversion and HDR expansion report beside their times.
#pragma once

#include <cstdint>

namespace nestlight {

// Peak resident set size of this process so far, in bytes.
uint64_t peakRssBytes();

}  // namespace nestlight
