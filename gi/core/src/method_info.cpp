#include "nestlight/gi/method_info.h"

namespace nestlight::gi {

void setParameter(GiSettings& g, const std::string& name, const nlohmann::json& value) {
  if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
  g.parameters[name] = value;
}

}  // namespace nestlight::gi
