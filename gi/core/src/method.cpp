#include "nestlight/gi/method.h"

namespace nestlight::gi {

const std::vector<std::string>& methodNames() {
  static const std::vector<std::string> names = {"reference", "direct", "raster",
                                                 "vpl",       "pbgi",   "ibl"};
  return names;
}

}  // namespace nestlight::gi
