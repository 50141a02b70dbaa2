// Facts of the LAS format shared by the LAS reader and writer (ASPRS LAS Specification 1.4 R15).
// Private to converters/src.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>

#include "nestlight/octree/attribute.h"

namespace nestlight::las {

// LAS is little-endian; the reader and writer memcpy fields straight into host integers.
static_assert(std::endian::native == std::endian::little, "LAS I/O assumes a little-endian host");

inline constexpr size_t kHeaderSize12 = 227;  // LAS 1.0-1.2
inline constexpr size_t kHeaderSize13 = 235;  // + start of waveform data packet record
inline constexpr size_t kHeaderSize14 = 375;  // + EVLRs and 64-bit point counts
inline constexpr size_t kVlrHeaderSize = 54;
inline constexpr size_t kEvlrHeaderSize = 60;
inline constexpr size_t kExtraBytesDescriptorSize = 192;
inline constexpr size_t kWavePacketBytes =
    29;  // index u8, offset u64, size u32, location f32, xyz f32x3

inline constexpr uint16_t kRecordExtraBytes = 4;  // user "LASF_Spec"
inline constexpr uint16_t kRecordWkt = 2112;      // user "LASF_Projection"
inline constexpr uint16_t kRecordGeoKeys = 34735;
inline constexpr uint16_t kRecordGeoDoubles = 34736;
inline constexpr uint16_t kRecordGeoAscii = 34737;

// Global encoding bits (spec table 5).
inline constexpr uint16_t kEncodingGpsStandard = 1 << 0;
inline constexpr uint16_t kEncodingWaveformInternal = 1 << 1;
inline constexpr uint16_t kEncodingWkt = 1 << 4;

inline constexpr int kMaxPointFormat = 10;
// Bytes of each point data record format before any extra bytes (spec tables 7-17).
inline constexpr size_t kBaseRecordSize[kMaxPointFormat + 1] = {20, 28, 26, 34, 57, 63,
                                                                30, 36, 38, 59, 67};

constexpr bool isLegacyFormat(int pf) {
  return pf < 6;
}
constexpr bool hasGps(int pf) {
  return pf != 0 && pf != 2;
}
constexpr bool hasRgb(int pf) {
  return pf == 2 || pf == 3 || pf == 5 || pf == 7 || pf == 8 || pf == 10;
}
constexpr bool hasNir(int pf) {
  return pf == 8 || pf == 10;
}
constexpr bool hasWave(int pf) {
  return pf == 4 || pf == 5 || pf == 9 || pf == 10;
}

// Attribute names of the point record fields.
inline constexpr const char* kIntensity = "intensity";
inline constexpr const char* kReturnNumber = "return_number";
inline constexpr const char* kNumberOfReturns = "number_of_returns";
inline constexpr const char* kScanDirection = "scan_direction_flag";
inline constexpr const char* kEdgeOfFlightLine = "edge_of_flight_line";
inline constexpr const char* kClassification = "classification";
inline constexpr const char* kClassificationFlags = "classification_flags";
inline constexpr const char* kScannerChannel = "scanner_channel";
inline constexpr const char* kScanAngleRank = "scan_angle_rank";
inline constexpr const char* kScanAngle = "scan_angle";
inline constexpr const char* kUserData = "user_data";
inline constexpr const char* kPointSourceId = "point_source_id";
inline constexpr const char* kGpsTime = "gps_time";
inline constexpr const char* kRgb = "rgb";
inline constexpr const char* kNir = "nir";
inline constexpr const char* kWavePacketIndex = "wavepacket_index";
inline constexpr const char* kWavePacketOffset = "wavepacket_offset";
inline constexpr const char* kWavePacketSizeName = "wavepacket_size";
inline constexpr const char* kWaveformLocation = "waveform_location";
inline constexpr const char* kWaveformXyz = "waveform_xyz";
inline constexpr const char* kUndocumentedExtraBytes = "extra_bytes";

// The attributes a point data record format provides, in batch order. The reader's decoders
// write exactly this order; the writer maps attributes of these names and types into records.
inline PointLayout baseLayout(int pf) {
  PointLayout l;
  l.add({kIntensity, ScalarType::U16, 1, ""});
  l.add({kReturnNumber, ScalarType::U8, 1, ""});
  l.add({kNumberOfReturns, ScalarType::U8, 1, ""});
  l.add({kScanDirection, ScalarType::U8, 1, ""});
  l.add({kEdgeOfFlightLine, ScalarType::U8, 1, ""});
  l.add({kClassification, ScalarType::U8, 1, ""});
  l.add({kClassificationFlags, ScalarType::U8, 1,
         "bit 0 synthetic, 1 key-point, 2 withheld, 3 overlap"});
  if (isLegacyFormat(pf)) {
    l.add({kScanAngleRank, ScalarType::I8, 1, "degrees"});
  } else {
    l.add({kScannerChannel, ScalarType::U8, 1, ""});
    l.add({kScanAngle, ScalarType::I16, 1, "0.006 degrees"});
  }
  l.add({kUserData, ScalarType::U8, 1, ""});
  l.add({kPointSourceId, ScalarType::U16, 1, ""});
  if (hasGps(pf)) l.add({kGpsTime, ScalarType::F64, 1, ""});
  if (hasRgb(pf)) l.add({kRgb, ScalarType::U16, 3, ""});
  if (hasNir(pf)) l.add({kNir, ScalarType::U16, 1, ""});
  if (hasWave(pf)) {
    l.add({kWavePacketIndex, ScalarType::U8, 1, "wave packet descriptor index"});
    l.add({kWavePacketOffset, ScalarType::U64, 1, "byte offset to waveform data"});
    l.add({kWavePacketSizeName, ScalarType::U32, 1, "waveform packet size in bytes"});
    l.add({kWaveformLocation, ScalarType::F32, 1, "return point waveform location"});
    l.add({kWaveformXyz, ScalarType::F32, 3, "X(t), Y(t), Z(t)"});
  }
  return l;
}

// Extra Bytes data types 1-10 (spec table 24); 11-30 are the deprecated 2- and 3-element arrays.
inline std::optional<ScalarType> extraBytesScalar(int dataType) {
  static constexpr ScalarType kTypes[10] = {
      ScalarType::U8,  ScalarType::I8,  ScalarType::U16, ScalarType::I16, ScalarType::U32,
      ScalarType::I32, ScalarType::U64, ScalarType::I64, ScalarType::F32, ScalarType::F64};
  if (dataType < 1 || dataType > 30) return std::nullopt;
  return kTypes[(dataType - 1) % 10];
}
inline int extraBytesType(ScalarType t) {
  switch (t) {
    case ScalarType::U8:
      return 1;
    case ScalarType::I8:
      return 2;
    case ScalarType::U16:
      return 3;
    case ScalarType::I16:
      return 4;
    case ScalarType::U32:
      return 5;
    case ScalarType::I32:
      return 6;
    case ScalarType::U64:
      return 7;
    case ScalarType::I64:
      return 8;
    case ScalarType::F32:
      return 9;
    case ScalarType::F64:
      return 10;
  }
  return 0;
}

template <typename T>
inline T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <typename T>
inline void store(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

}  // namespace nestlight::las
