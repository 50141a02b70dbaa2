// Point attributes: everything a point carries besides its position.
//
// A scan stores only the attributes it has (DESIGN.md: a scene pays only for what it needs). The
// layout is an ordered list of named, typed attributes packed without padding; the same layout
// describes a chunk record, a decoded node and the metadata's attribute list.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nestlight {

enum class ScalarType : uint8_t { U8, I8, U16, I16, U32, I32, U64, I64, F32, F64 };

size_t scalarSize(ScalarType t);
const char* scalarName(ScalarType t);  // "uint8", "int16", "float", "double", ...
std::optional<ScalarType> parseScalarName(std::string_view name);
bool isFloat(ScalarType t);
bool isSigned(ScalarType t);

// Reads/writes one component as double; `p` need not be aligned.
double loadAsDouble(ScalarType t, const uint8_t* p);
// Converts with rounding and clamping to the type's range (NaN becomes 0 for integers).
void storeFromDouble(ScalarType t, double v, uint8_t* p);

// Names with a fixed meaning; other attributes keep the name the source gave them.
namespace attr {
inline constexpr std::string_view kRgb = "rgb";              // uint16 x3, full 16-bit range
inline constexpr std::string_view kNormal = "normal";        // float x3, unit length
inline constexpr std::string_view kIntensity = "intensity";  // uint16
inline constexpr std::string_view kClassification = "classification";  // uint8
}  // namespace attr

struct Attribute {
  std::string name;
  ScalarType type = ScalarType::U8;
  uint32_t components = 1;
  std::string description;

  size_t byteSize() const { return scalarSize(type) * components; }
  bool operator==(const Attribute& o) const {
    return name == o.name && type == o.type && components == o.components;
  }
};

class PointLayout {
 public:
  PointLayout() = default;
  explicit PointLayout(std::vector<Attribute> attributes);

  // Appends an attribute; returns its index. A name already present is an error (NL_CHECK).
  size_t add(Attribute a);
  // Index of the attribute named `name`, or -1.
  int find(std::string_view name) const;
  bool has(std::string_view name) const { return find(name) >= 0; }

  const std::vector<Attribute>& attributes() const { return attributes_; }
  size_t size() const { return attributes_.size(); }
  const Attribute& operator[](size_t i) const { return attributes_[i]; }
  size_t offset(size_t i) const { return offsets_[i]; }
  // Bytes of attributes per point (positions are not part of the layout).
  size_t stride() const { return stride_; }
  bool operator==(const PointLayout& o) const { return attributes_ == o.attributes_; }

 private:
  std::vector<Attribute> attributes_;
  std::vector<size_t> offsets_;
  size_t stride_ = 0;
};

}  // namespace nestlight
