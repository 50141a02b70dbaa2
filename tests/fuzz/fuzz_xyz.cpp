// libFuzzer target for the XYZ/PTS/TXT reader: any input either reads or throws nestlight::Error;
// it never reads out of bounds, aborts, leaks or allocates what the input cannot hold.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Guessed and named columns (a skipped one, every known kind and a free-named float), each
  // strict and lenient.
  for (const char* columns : {"", "x,_,y,z,r,g,b,intensity,classification,nx,ny,nz,extra"}) {
    for (bool lenient : {false, true}) {
      try {
        nestlight::ReadOptions options;
        options.lenient = lenient;
        options.columns = columns;
        auto reader =
            nestlight::openXyz(nestlight::borrowedSource("fuzz.xyz", data, size), options);
        (void)reader->header().details.dump();
        nestlight::fuzz::readEverything(*reader);
      } catch (const nestlight::Error&) {
      }
    }
  }
  return 0;
}
