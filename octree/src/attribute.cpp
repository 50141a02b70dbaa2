#include "nestlight/octree/attribute.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "nestlight/octree/error.h"

namespace nestlight {

size_t scalarSize(ScalarType t) {
  switch (t) {
    case ScalarType::U8:
    case ScalarType::I8:
      return 1;
    case ScalarType::U16:
    case ScalarType::I16:
      return 2;
    case ScalarType::U32:
    case ScalarType::I32:
    case ScalarType::F32:
      return 4;
    case ScalarType::U64:
    case ScalarType::I64:
    case ScalarType::F64:
      return 8;
  }
  return 0;
}

const char* scalarName(ScalarType t) {
  switch (t) {
    case ScalarType::U8:
      return "uint8";
    case ScalarType::I8:
      return "int8";
    case ScalarType::U16:
      return "uint16";
    case ScalarType::I16:
      return "int16";
    case ScalarType::U32:
      return "uint32";
    case ScalarType::I32:
      return "int32";
    case ScalarType::U64:
      return "uint64";
    case ScalarType::I64:
      return "int64";
    case ScalarType::F32:
      return "float";
    case ScalarType::F64:
      return "double";
  }
  return "?";
}

std::optional<ScalarType> parseScalarName(std::string_view n) {
  // Accepts our names and the PLY/PCD spellings.
  if (n == "uint8" || n == "uchar") return ScalarType::U8;
  if (n == "int8" || n == "char") return ScalarType::I8;
  if (n == "uint16" || n == "ushort") return ScalarType::U16;
  if (n == "int16" || n == "short") return ScalarType::I16;
  if (n == "uint32" || n == "uint") return ScalarType::U32;
  if (n == "int32" || n == "int") return ScalarType::I32;
  if (n == "uint64") return ScalarType::U64;
  if (n == "int64") return ScalarType::I64;
  if (n == "float" || n == "float32") return ScalarType::F32;
  if (n == "double" || n == "float64") return ScalarType::F64;
  return std::nullopt;
}

bool isFloat(ScalarType t) {
  return t == ScalarType::F32 || t == ScalarType::F64;
}
bool isSigned(ScalarType t) {
  return t == ScalarType::I8 || t == ScalarType::I16 || t == ScalarType::I32 ||
         t == ScalarType::I64 || isFloat(t);
}

namespace {
template <typename T>
T loadRaw(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <typename T>
void storeInt(double v, uint8_t* p) {
  T out;
  if (std::isnan(v)) {
    out = 0;
  } else {
    double r = std::nearbyint(v);
    double lo = static_cast<double>(std::numeric_limits<T>::lowest());
    double hi = static_cast<double>(std::numeric_limits<T>::max());
    if (r <= lo)
      out = std::numeric_limits<T>::lowest();
    else if (r >= hi)
      out = std::numeric_limits<T>::max();
    else
      out = static_cast<T>(r);
  }
  std::memcpy(p, &out, sizeof(T));
}
}  // namespace

double loadAsDouble(ScalarType t, const uint8_t* p) {
  switch (t) {
    case ScalarType::U8:
      return loadRaw<uint8_t>(p);
    case ScalarType::I8:
      return loadRaw<int8_t>(p);
    case ScalarType::U16:
      return loadRaw<uint16_t>(p);
    case ScalarType::I16:
      return loadRaw<int16_t>(p);
    case ScalarType::U32:
      return loadRaw<uint32_t>(p);
    case ScalarType::I32:
      return loadRaw<int32_t>(p);
    case ScalarType::U64:
      return static_cast<double>(loadRaw<uint64_t>(p));
    case ScalarType::I64:
      return static_cast<double>(loadRaw<int64_t>(p));
    case ScalarType::F32:
      return loadRaw<float>(p);
    case ScalarType::F64:
      return loadRaw<double>(p);
  }
  return 0;
}

void storeFromDouble(ScalarType t, double v, uint8_t* p) {
  switch (t) {
    case ScalarType::U8:
      return storeInt<uint8_t>(v, p);
    case ScalarType::I8:
      return storeInt<int8_t>(v, p);
    case ScalarType::U16:
      return storeInt<uint16_t>(v, p);
    case ScalarType::I16:
      return storeInt<int16_t>(v, p);
    case ScalarType::U32:
      return storeInt<uint32_t>(v, p);
    case ScalarType::I32:
      return storeInt<int32_t>(v, p);
    case ScalarType::U64:
      return storeInt<uint64_t>(v, p);
    case ScalarType::I64:
      return storeInt<int64_t>(v, p);
    case ScalarType::F32: {
      float f = static_cast<float>(v);
      std::memcpy(p, &f, 4);
      return;
    }
    case ScalarType::F64:
      std::memcpy(p, &v, 8);
      return;
  }
}

PointLayout::PointLayout(std::vector<Attribute> attributes) {
  for (auto& a : attributes) add(std::move(a));
}

size_t PointLayout::add(Attribute a) {
  NL_CHECK_MSG(find(a.name) < 0, "duplicate attribute " + a.name);
  NL_CHECK(a.components >= 1);
  offsets_.push_back(stride_);
  stride_ += a.byteSize();
  attributes_.push_back(std::move(a));
  return attributes_.size() - 1;
}

int PointLayout::find(std::string_view name) const {
  for (size_t i = 0; i < attributes_.size(); ++i)
    if (attributes_[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace nestlight
