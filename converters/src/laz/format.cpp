// The LASzip VLR (LASzip reference implementation, laszip.cpp: the "laszip encoded" record
// 22204): compressor u16, coder u16, version u8 u8 u16, options u32, chunk size u32, number and
// offset of special EVLRs i64 i64, item count u16, then per item type u16, size u16, version u16.
#include "laz/format.h"

#include <cstring>

#include "laz/common.h"

namespace nestlight::laz {

namespace {

// The items LASzip writes for each point format, before any extra bytes (Byte / Byte14).
bool expectedItems(int pf, std::vector<ItemType>& out) {
  switch (pf) {
    case 0:
      out = {ItemType::Point10};
      return true;
    case 1:
      out = {ItemType::Point10, ItemType::GpsTime11};
      return true;
    case 2:
      out = {ItemType::Point10, ItemType::Rgb12};
      return true;
    case 3:
      out = {ItemType::Point10, ItemType::GpsTime11, ItemType::Rgb12};
      return true;
    case 4:
      out = {ItemType::Point10, ItemType::GpsTime11, ItemType::WavePacket13};
      return true;
    case 5:
      out = {ItemType::Point10, ItemType::GpsTime11, ItemType::Rgb12, ItemType::WavePacket13};
      return true;
    case 6:
      out = {ItemType::Point14};
      return true;
    case 7:
      out = {ItemType::Point14, ItemType::Rgb14};
      return true;
    case 8:
      out = {ItemType::Point14, ItemType::RgbNir14};
      return true;
    case 9:
      out = {ItemType::Point14, ItemType::WavePacket14};
      return true;
    case 10:
      out = {ItemType::Point14, ItemType::RgbNir14, ItemType::WavePacket14};
      return true;
    default:
      return false;
  }
}

size_t fixedSize(ItemType t) {
  switch (t) {
    case ItemType::Point10:
      return 20;
    case ItemType::GpsTime11:
      return 8;
    case ItemType::Rgb12:
      return 6;
    case ItemType::WavePacket13:
      return 29;
    case ItemType::Point14:
      return 30;
    case ItemType::Rgb14:
      return 6;
    case ItemType::RgbNir14:
      return 8;
    case ItemType::WavePacket14:
      return 29;
    default:
      return 0;  // Byte, Byte14: any size
  }
}
}  // namespace

std::vector<Item> itemsFor(int pf, size_t extraBytes, uint16_t version) {
  std::vector<ItemType> types;
  if (!expectedItems(pf, types)) return {};
  std::vector<Item> items;
  for (ItemType t : types) items.push_back({t, uint16_t(fixedSize(t)), version});
  if (extraBytes)
    items.push_back({pf <= 5 ? ItemType::Byte : ItemType::Byte14, uint16_t(extraBytes), version});
  return items;
}

std::string itemName(ItemType t) {
  switch (t) {
    case ItemType::Byte:
      return "BYTE";
    case ItemType::Short:
      return "SHORT";
    case ItemType::Int:
      return "INT";
    case ItemType::Long:
      return "LONG";
    case ItemType::Float:
      return "FLOAT";
    case ItemType::Double:
      return "DOUBLE";
    case ItemType::Point10:
      return "POINT10";
    case ItemType::GpsTime11:
      return "GPSTIME11";
    case ItemType::Rgb12:
      return "RGB12";
    case ItemType::WavePacket13:
      return "WAVEPACKET13";
    case ItemType::Point14:
      return "POINT14";
    case ItemType::Rgb14:
      return "RGB14";
    case ItemType::RgbNir14:
      return "RGBNIR14";
    case ItemType::WavePacket14:
      return "WAVEPACKET14";
    case ItemType::Byte14:
      return "BYTE14";
  }
  return "item type " + std::to_string(static_cast<unsigned>(t));
}

std::string parseLaszipVlr(const uint8_t* d, size_t length, int pf, size_t recordLength,
                           LaszipInfo& out) {
  if (length < 34)
    return "LASzip record is " + std::to_string(length) + " bytes, shorter than the 34 it needs";
  const uint16_t compressor = get<uint16_t>(d);
  if (compressor > 3)
    return "LASzip record names the unknown compressor " + std::to_string(compressor) +
           " (known: 0 none, 1 pointwise, 2 pointwise chunked, 3 layered chunked)";
  out.compressor = static_cast<Compressor>(compressor);
  out.coder = get<uint16_t>(d + 2);
  if (out.coder != 0)
    return "LASzip record names the unknown coder " + std::to_string(out.coder) +
           " (known: 0 arithmetic)";
  out.versionMajor = d[4];
  out.versionMinor = d[5];
  out.versionRevision = get<uint16_t>(d + 6);
  out.options = get<uint32_t>(d + 8);
  out.chunkSize = get<uint32_t>(d + 12);
  const uint16_t numItems = get<uint16_t>(d + 32);
  if (length - 34 < size_t(numItems) * 6)
    return "LASzip record lists " + std::to_string(numItems) + " items but holds only " +
           std::to_string((length - 34) / 6);
  if (numItems == 0) return "LASzip record lists no items";
  out.items.clear();
  for (uint16_t i = 0; i < numItems; ++i) {
    const uint8_t* p = d + 34 + 6 * size_t(i);
    const uint16_t type = get<uint16_t>(p);
    if (type > static_cast<uint16_t>(ItemType::Byte14))
      return "LASzip record item " + std::to_string(i + 1) + " has the unknown type " +
             std::to_string(type);
    out.items.push_back({static_cast<ItemType>(type), get<uint16_t>(p + 2), get<uint16_t>(p + 4)});
  }

  if (out.compressor == Compressor::None)
    return "LASzip record says the points are not compressed, but the point format byte says "
           "they are";
  if (out.compressor != Compressor::PointwiseChunked && out.compressor != Compressor::Pointwise &&
      out.compressor != Compressor::LayeredChunked)
    return "unsupported LASzip compressor";
  if (out.chunkSize == 0 && out.compressor != Compressor::Pointwise)
    return "LASzip record gives a chunk size of 0 points";

  std::vector<ItemType> expected;
  if (!expectedItems(pf, expected))
    return "point format " + std::to_string(pf) + " has no LASzip items";
  const bool layered = pf >= 6;
  if (layered != (out.compressor == Compressor::LayeredChunked))
    return std::string("LASzip record uses the ") +
           (layered ? "pointwise compressor for point format " + std::to_string(pf) +
                          ", which needs the layered one (3)"
                    : "layered compressor for point format " + std::to_string(pf) +
                          ", which needs a pointwise one (1 or 2)");
  for (size_t i = 0; i < out.items.size(); ++i) {
    const Item& it = out.items[i];
    const std::string which = "LASzip item " + std::to_string(i + 1) + " (" + itemName(it.type) +
                              " version " + std::to_string(it.version) + ")";
    if (i < expected.size()) {
      if (it.type != expected[i])
        return which + " does not match point format " + std::to_string(pf) + ", which needs " +
               itemName(expected[i]) + " here";
    } else if (it.type != (layered ? ItemType::Byte14 : ItemType::Byte)) {
      return which + " is not expected after the fields of point format " + std::to_string(pf);
    }
    if (it.type == ItemType::WavePacket13)
      return which + ": waveform packets of point formats 4 and 5 are not supported";
    const size_t fixed = fixedSize(it.type);
    if (fixed ? it.size != fixed : it.size == 0)
      return which + " has size " + std::to_string(it.size) +
             (fixed ? ", not " + std::to_string(fixed) : "");
    // Layered items: LASzip reads version 2 (written by a prototype) as 3; version 4 differs from
    // 3 only in how a scanner-channel switch selects contexts; WAVEPACKET14 exists as 3 only.
    const bool versionOk =
        layered ? (it.type == ItemType::WavePacket14 ? it.version == 3
                                                     : it.version >= 2 && it.version <= 4)
                : (it.version == 1 || it.version == 2);
    if (!versionOk)
      return which + ": version " + std::to_string(it.version) + " is not supported (" +
             (layered ? "formats 6-10 need version 2, 3 or 4" : "formats 0-5 need version 1 or 2") +
             ")";
  }
  if (out.items.size() < expected.size())
    return "LASzip record lists " + std::to_string(out.items.size()) + " items; point format " +
           std::to_string(pf) + " needs at least " + std::to_string(expected.size());
  if (out.recordSize() != recordLength)
    return "LASzip items add up to " + std::to_string(out.recordSize()) +
           " bytes per point, but the header's record length is " + std::to_string(recordLength);
  return {};
}

}  // namespace nestlight::laz
