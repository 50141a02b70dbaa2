// libFuzzer target for the PLY reader: any input either reads or throws nestlight::Error; it
// never reads out of bounds, aborts, leaks or allocates what the input cannot hold.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Both modes: lenient reading takes other paths through a lying header.
  for (bool lenient : {false, true}) {
    try {
      nestlight::ReadOptions options;
      options.lenient = lenient;
      auto reader = nestlight::openPly(nestlight::borrowedSource("fuzz.ply", data, size), options);
      // Metadata must be writable as JSON whatever bytes the comments and names came from.
      (void)reader->header().crs.dump();
      (void)reader->header().details.dump();
      nestlight::fuzz::readEverything(*reader);
    } catch (const nestlight::Error&) {
    }
  }
  return 0;
}
