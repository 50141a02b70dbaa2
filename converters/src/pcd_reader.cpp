// PCD (Point Cloud Library) reader, through PCL's own parser.
//
// Sources:
//  - The PCD file format, PCL documentation:
//    https://pcl.readthedocs.io/projects/tutorials/en/latest/pcd_file_format.html
//  - pcl/io/pcd_io.h (PCL 1.13): PCDReader::readHeader / read into a pcl::PCLPointCloud2, which
//    keeps any field set as raw bytes (row-major, point_step bytes per point, little-endian).
//  - pcl/point_types.h: packed colour is one 32-bit word 0xAARRGGBB, stored in a float ("rgb")
//    or a uint32 ("rgba").
//
// PCL reads the whole cloud into memory: PCDReader has no streaming interface, and
// binary_compressed stores each field as one LZF block, so nothing can be read before the whole
// body has been decompressed. This reader is therefore not out-of-core. That is fine in practice:
// PCD files come from depth cameras and PCL pipelines and are megabytes to a few GB, not the
// billion-point scans that LAS/PLY carry; the builder still sees batches.
//
// No fuzz target: parsing is PCL's (upstream) code; our code only interprets the field table
// PCL returns and copies bytes within the bounds of PCL's own buffer.
#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

std::optional<ScalarType> scalarFromPcl(uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::BOOL:  // sizeof(bool) == 1 on every platform PCL supports
    case pcl::PCLPointField::UINT8:
      return ScalarType::U8;
    case pcl::PCLPointField::INT8:
      return ScalarType::I8;
    case pcl::PCLPointField::UINT16:
      return ScalarType::U16;
    case pcl::PCLPointField::INT16:
      return ScalarType::I16;
    case pcl::PCLPointField::UINT32:
      return ScalarType::U32;
    case pcl::PCLPointField::INT32:
      return ScalarType::I32;
    case pcl::PCLPointField::UINT64:
      return ScalarType::U64;
    case pcl::PCLPointField::INT64:
      return ScalarType::I64;
    case pcl::PCLPointField::FLOAT32:
      return ScalarType::F32;
    case pcl::PCLPointField::FLOAT64:
      return ScalarType::F64;
    default:
      return std::nullopt;
  }
}

const char* dataName(int dataType) {
  switch (dataType) {
    case 0:
      return "ascii";
    case 1:
      return "binary";
    case 2:
      return "binary_compressed";
    default:
      return "unknown";
  }
}

// PCL reports parse problems on its console; we report them as nestlight::Error instead, so its
// messages would only duplicate ours (and clutter `nestlight convert` output). The verbosity is
// process-wide; nothing else in Nestlight prints through PCL.
void silencePcl() {
  static std::once_flag once;
  std::call_once(once, [] { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); });
}

// How one attribute of the output layout is made from the PCD record.
struct Plan {
  enum Kind { Copy, PackedRgb, PackedAlpha, SplitRgb, Normal } kind = Copy;
  size_t src[3] = {0, 0, 0};  // byte offsets in the PCD record
  ScalarType srcType[3] = {ScalarType::U8, ScalarType::U8, ScalarType::U8};
  size_t dst = 0;    // byte offset in the output record
  size_t bytes = 0;  // Copy: bytes copied
};

class PcdReader final : public PointReader {
 public:
  PcdReader(const std::string& path, const ReadOptions& options) {
    header_.path = path;
    header_.format = "pcd";
    silencePcl();

    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw Error(path, "",
                  std::filesystem::exists(path, ec) ? "not a regular file" : "no such file");
    fileSize_ = std::filesystem::file_size(path, ec);
    if (ec) throw Error(path, "", "cannot stat: " + ec.message());

    pcl::PCDReader reader;
    Eigen::Vector4f origin = Eigen::Vector4f::Zero();
    Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
    int version = 0, dataType = 0;
    unsigned int dataIdx = 0;
    int rc = -1;
    try {
      rc = reader.readHeader(path, cloud_, origin, orientation, version, dataType, dataIdx);
    } catch (const std::exception& e) {
      throw Error(path, "header", std::string("unreadable PCD header: ") + e.what());
    }
    if (rc < 0)
      throw Error(path, "header",
                  "unreadable PCD header (expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, "
                  "HEIGHT, POINTS and DATA lines with consistent counts)");
    // PCL accepts a file without FIELDS (e.g. not a PCD at all) as a header with no fields.
    if (cloud_.fields.empty() || cloud_.point_step == 0)
      throw Error(path, "header", "unreadable PCD header: no FIELDS/SIZE/TYPE lines");
    dataIdx_ = dataIdx;
    const uint64_t width = cloud_.width, height = cloud_.height;
    total_ = width * height;
    header_.declaredPoints = total_;
    planLayout(path);

    // The body. Binary bodies are checked here first so that a short file gets an exact message
    // (PCL only says "failed"), and so that lenient mode can keep the complete records.
    std::vector<std::string> fieldNames;
    for (const auto& f : cloud_.fields) fieldNames.push_back(f.name);
    const uint64_t step = cloud_.point_step;
    if (dataType == 1 && fileSize_ < dataIdx_ + total_ * step) {
      const uint64_t complete =
          step ? (fileSize_ - std::min<uint64_t>(fileSize_, dataIdx_)) / step : 0;
      const std::string what =
          "data is truncated: the header declares " + std::to_string(total_) + " points of " +
          std::to_string(step) + " bytes from byte " + std::to_string(dataIdx_) + " (" +
          std::to_string(dataIdx_ + total_ * step) + " bytes), the file has " +
          std::to_string(fileSize_) + " bytes (" + std::to_string(complete) + " complete points)";
      if (!options.lenient) throw Error(path, Error::atByte(dataIdx_ + complete * step), what);
      warnings_.push_back(path + ": " + what + "; kept the complete points");
      readBinaryPrefix(path, complete);
    } else {
      if (dataType == 2) checkCompressedSize(path);
      pcl::PCLPointCloud2 full;
      try {
        rc = reader.read(path, full, origin, orientation, version);
      } catch (const std::exception& e) {
        throw Error(path, Error::atByte(dataIdx_), std::string("unreadable PCD data: ") + e.what());
      }
      if (rc < 0 || full.data.size() < total_ * step)
        throw Error(path, Error::atByte(dataIdx_),
                    std::string("unreadable or truncated ") + dataName(dataType) +
                        " data: expected " + std::to_string(total_) + " points");
      cloud_ = std::move(full);
    }
    available_ = step ? std::min<uint64_t>(total_, cloud_.data.size() / step) : 0;
    addAlphaIfUsed();

    // NaN slots are passed through (the builder counts them as rejected); the counts go into
    // the metadata because an organised cloud's NaN slots are expected, not a fault.
    uint64_t finite = 0;
    for (uint64_t i = 0; i < available_; ++i) {
      double p[3];
      position(i, p);
      finite += std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    }

    auto& d = header_.details;
    d["version"] = version == pcl::PCDReader::PCD_V7 ? "0.7" : "0.6";
    d["data"] = dataName(dataType);
    d["width"] = width;
    d["height"] = height;
    d["organized"] = height > 1;
    d["fields"] = fieldNames;
    d["finite_points"] = finite;
    d["nan_points"] = available_ - finite;  // any of x, y, z not finite (NaN, or Inf)
    d["sensor_origin"] = {origin[0], origin[1], origin[2]};
    d["sensor_orientation"] = {orientation.w(), orientation.x(), orientation.y(), orientation.z()};
    if (!alphaNote_.empty()) d["alpha"] = alphaNote_;
  }

  const SourceHeader& header() const override { return header_; }

  bool read(PointBatch& batch, size_t maxPoints) override {
    batch.clear();
    if (cursor_ >= available_ || maxPoints == 0) return false;
    const uint64_t n = std::min<uint64_t>(maxPoints, available_ - cursor_);
    const size_t stride = header_.layout.stride();
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * stride);
    for (uint64_t k = 0; k < n; ++k) {
      position(cursor_ + k, &batch.xyz[k * 3]);
      const uint8_t* rec = cloud_.data.data() + (cursor_ + k) * cloud_.point_step;
      uint8_t* out = batch.attrs.data() + k * stride;
      for (const Plan& p : plans_) apply(p, rec, out);
    }
    cursor_ += n;
    return true;
  }

  void rewind() override { cursor_ = 0; }
  std::vector<std::string> warnings() const override { return warnings_; }
  uint64_t bytesConsumed() const override {
    if (available_ == 0) return fileSize_;
    return dataIdx_ + (fileSize_ - std::min(fileSize_, dataIdx_)) * cursor_ / available_;
  }
  uint64_t bytesTotal() const override { return fileSize_; }

 private:
  const pcl::PCLPointField* field(std::string_view name) const {
    for (const auto& f : cloud_.fields)
      if (f.name == name && f.count > 0) return &f;
    return nullptr;
  }

  std::string fieldList() const {
    std::string s;
    for (const auto& f : cloud_.fields) s += (s.empty() ? "" : " ") + f.name;
    return s;
  }

  void planLayout(const std::string& path) {
    PointLayout layout;
    std::vector<const pcl::PCLPointField*> used;
    auto typeOf = [&](const pcl::PCLPointField& f) {
      auto t = scalarFromPcl(f.datatype);
      if (!t)
        throw Error(
            path, "header",
            "field '" + f.name + "' has an unknown type (" + std::to_string(int(f.datatype)) + ")");
      return *t;
    };
    auto within = [&](const pcl::PCLPointField& f, ScalarType t) {
      if (f.offset + scalarSize(t) * f.count > cloud_.point_step)
        throw Error(path, "header", "field '" + f.name + "' lies outside the point record");
    };

    const char* axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      const pcl::PCLPointField* f = field(axes[a]);
      if (!f)
        throw Error(path, "header",
                    std::string("no '") + axes[a] + "' field; FIELDS are: " + fieldList());
      if (f->count != 1)
        throw Error(path, "header",
                    std::string("field '") + axes[a] + "' has COUNT " + std::to_string(f->count) +
                        "; expected 1");
      posType_[a] = typeOf(*f);
      within(*f, posType_[a]);
      posOff_[a] = f->offset;
      used.push_back(f);
    }

    // Colour: packed 0x00RRGGBB ("rgb", usually stored in a float) or 0xAARRGGBB ("rgba").
    const pcl::PCLPointField* packed = field("rgb");
    if (!packed) packed = field("rgba");
    if (packed && packed->count == 1 && pcl::getFieldSize(packed->datatype) == 4) {
      Plan p;
      p.kind = Plan::PackedRgb;
      p.src[0] = packed->offset;
      within(*packed, ScalarType::U32);
      p.dst = layout.stride();
      layout.add({std::string(attr::kRgb), ScalarType::U16, 3, "PCD packed colour, 8 bits * 257"});
      plans_.push_back(p);
      used.push_back(packed);
      header_.rgbBits = 8;
      packedRgba_ = packed->name == "rgba";
      packedOff_ = packed->offset;
    } else if (const auto* r = field("r"), *g = field("g"), *b = field("b");
               !packed && r && g && b && r->count == 1 && g->count == 1 && b->count == 1 &&
               r->datatype == pcl::PCLPointField::UINT8 &&
               g->datatype == pcl::PCLPointField::UINT8 &&
               b->datatype == pcl::PCLPointField::UINT8) {
      Plan p;
      p.kind = Plan::SplitRgb;
      p.src[0] = r->offset, p.src[1] = g->offset, p.src[2] = b->offset;
      p.dst = layout.stride();
      layout.add({std::string(attr::kRgb), ScalarType::U16, 3, "PCD r g b, 8 bits * 257"});
      plans_.push_back(p);
      used.insert(used.end(), {r, g, b});
      header_.rgbBits = 8;
    }

    const pcl::PCLPointField* n[3] = {field("normal_x"), field("normal_y"), field("normal_z")};
    if (n[0] && n[1] && n[2] && n[0]->count == 1 && n[1]->count == 1 && n[2]->count == 1) {
      Plan p;
      p.kind = Plan::Normal;
      for (int a = 0; a < 3; ++a) {
        p.src[a] = n[a]->offset;
        p.srcType[a] = typeOf(*n[a]);
        within(*n[a], p.srcType[a]);
        used.push_back(n[a]);
      }
      p.dst = layout.stride();
      layout.add({std::string(attr::kNormal), ScalarType::F32, 3, "PCD normal_x/y/z"});
      plans_.push_back(p);
    }

    // Everything else keeps its PCD name, type and count. "_" is PCL's padding.
    for (const auto& f : cloud_.fields) {
      if (f.name == "_" || f.count == 0 || std::find(used.begin(), used.end(), &f) != used.end())
        continue;
      ScalarType t = typeOf(f);
      within(f, t);
      std::string name = f.name;
      // Names with a fixed meaning in Nestlight that this field does not satisfy.
      if (name == attr::kRgb || name == attr::kNormal || name == "alpha") name = "pcd_" + name;
      if (name.empty() || layout.has(name))
        throw Error(path, "header", "duplicate or empty field name '" + f.name + "'");
      Plan p;
      p.kind = Plan::Copy;
      p.src[0] = f.offset;
      p.bytes = scalarSize(t) * f.count;
      p.dst = layout.stride();
      layout.add({name, t, f.count, "PCD field " + f.name});
      plans_.push_back(p);
    }
    header_.layout = std::move(layout);
  }

  // Alpha of an "rgba" field, kept only when it carries something (not all 255 or all 0: PCL
  // writes PointXYZRGBA with alpha 255, and tools that fill "rgb" leave it 0). Needs the body, so
  // it runs after the body is read.
  void addAlphaIfUsed() {
    if (!packedRgba_ || available_ == 0) return;
    const size_t off = packedOff_;
    uint8_t first = cloud_.data[off + 3];
    bool constant = true;
    for (uint64_t i = 1; i < available_ && constant; ++i)
      constant = cloud_.data[i * cloud_.point_step + off + 3] == first;
    if (constant && (first == 255 || first == 0)) {
      alphaNote_ = "constant " + std::to_string(first) + "; not stored";
      return;
    }
    Plan p;
    p.kind = Plan::PackedAlpha;
    p.src[0] = off;
    p.dst = header_.layout.stride();
    std::vector<Attribute> attrs = header_.layout.attributes();
    attrs.push_back({"alpha", ScalarType::U8, 1, "PCD rgba alpha"});
    header_.layout = PointLayout(std::move(attrs));
    plans_.push_back(p);
    alphaNote_ = "stored as 'alpha'";
  }

  void position(uint64_t i, double* p) const {
    const uint8_t* rec = cloud_.data.data() + i * cloud_.point_step;
    for (int a = 0; a < 3; ++a) {
      if (posType_[a] == ScalarType::F32) {
        float v;
        std::memcpy(&v, rec + posOff_[a], 4);
        p[a] = v;
      } else {
        p[a] = loadAsDouble(posType_[a], rec + posOff_[a]);
      }
    }
  }

  static void apply(const Plan& p, const uint8_t* rec, uint8_t* out) {
    switch (p.kind) {
      case Plan::Copy:
        std::memcpy(out + p.dst, rec + p.src[0], p.bytes);
        return;
      case Plan::PackedRgb: {
        uint32_t v;
        std::memcpy(&v, rec + p.src[0], 4);
        const uint16_t c[3] = {uint16_t(((v >> 16) & 0xff) * 257),
                               uint16_t(((v >> 8) & 0xff) * 257), uint16_t((v & 0xff) * 257)};
        std::memcpy(out + p.dst, c, 6);
        return;
      }
      case Plan::PackedAlpha:
        out[p.dst] = rec[p.src[0] + 3];
        return;
      case Plan::SplitRgb: {
        const uint16_t c[3] = {uint16_t(rec[p.src[0]] * 257), uint16_t(rec[p.src[1]] * 257),
                               uint16_t(rec[p.src[2]] * 257)};
        std::memcpy(out + p.dst, c, 6);
        return;
      }
      case Plan::Normal: {
        float nrm[3];
        for (int a = 0; a < 3; ++a)
          nrm[a] = static_cast<float>(loadAsDouble(p.srcType[a], rec + p.src[a]));
        std::memcpy(out + p.dst, nrm, 12);
        return;
      }
    }
  }

  // binary_compressed: the body starts with the compressed and uncompressed sizes (uint32 each);
  // PCL fails on a short body without saying why.
  void checkCompressedSize(const std::string& path) const {
    std::ifstream in(path, std::ios::binary);
    uint32_t sizes[2] = {0, 0};
    in.seekg(static_cast<std::streamoff>(dataIdx_));
    if (!in.read(reinterpret_cast<char*>(sizes), 8))
      throw Error(path, Error::atByte(dataIdx_),
                  "binary_compressed data is truncated: no block sizes after the header");
    if (dataIdx_ + 8 + uint64_t(sizes[0]) > fileSize_)
      throw Error(path, Error::atByte(fileSize_),
                  "binary_compressed data is truncated: the block is " + std::to_string(sizes[0]) +
                      " bytes from byte " + std::to_string(dataIdx_ + 8) + ", the file has " +
                      std::to_string(fileSize_) + " bytes");
  }

  // Lenient mode on a short binary body: the records that are complete, read directly (binary
  // PCD is the raw row-major record array PCL would copy).
  void readBinaryPrefix(const std::string& path, uint64_t complete) {
    std::ifstream in(path, std::ios::binary);
    cloud_.data.assign(complete * cloud_.point_step, 0);
    in.seekg(static_cast<std::streamoff>(dataIdx_));
    if (!in.read(reinterpret_cast<char*>(cloud_.data.data()),
                 static_cast<std::streamsize>(cloud_.data.size())))
      throw Error(path, Error::atByte(dataIdx_), "cannot read the data");
  }

 private:
  SourceHeader header_;
  pcl::PCLPointCloud2 cloud_;  // the whole cloud; see the note at the top of the file
  std::vector<Plan> plans_;
  ScalarType posType_[3] = {ScalarType::F32, ScalarType::F32, ScalarType::F32};
  size_t posOff_[3] = {0, 0, 0};
  bool packedRgba_ = false;
  size_t packedOff_ = 0;
  std::string alphaNote_;
  std::vector<std::string> warnings_;
  uint64_t fileSize_ = 0, dataIdx_ = 0;
  uint64_t total_ = 0;      // width * height, what the header declares
  uint64_t available_ = 0;  // records held (fewer than total_ only in lenient mode)
  uint64_t cursor_ = 0;
};

}  // namespace

std::unique_ptr<PointReader> openPcd(const std::string& path, const ReadOptions& options) {
  return std::make_unique<PcdReader>(path, options);
}

}  // namespace nestlight
