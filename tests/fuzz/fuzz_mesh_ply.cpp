// libFuzzer target for the PLY mesh reader: any input either reads into a valid mesh or throws
// nestlight::Error; it never reads out of bounds, aborts, leaks or allocates what the input
// cannot hold (a header may declare 2^40 vertices).
#include <cstddef>
#include <cstdint>

#include "fuzz_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nestlight::fuzz::readMeshChecked("fuzz.ply", data, size);
  return 0;
}
