// PCD (Point Cloud Library) reader: PCL parses the header and the binary bodies.
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
// ascii bodies are parsed here, not by PCL: PCL 1.13's ascii parser reads a malformed value, or
// a line with too few or too many values, as zeros without reporting anything, and a reader must
// not invent points. The result is the same PCLPointCloud2 record layout PCL would produce.
//
// No fuzz target: header and binary parsing are PCL's (upstream) code; our code interprets the
// field table PCL returns, copies bytes within the bounds of PCL's buffer, and tokenises ascii
// lines (bounds-checked string_view code). If PCL is ever replaced, the new parser needs one.
#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

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

    checkDeclaredSize(path);

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

    // The header text, for what PCL does not report: the VERSION line as written (PCL infers
    // 0.6 or 0.7 from the presence of VIEWPOINT) and line numbers for ascii errors.
    const std::string headerText = readBytes(path, 0, dataIdx_);
    std::string versionText;
    for (size_t pos = 0; pos < headerText.size();) {
      size_t eol = headerText.find('\n', pos);
      if (eol == std::string::npos) eol = headerText.size();
      const std::string_view line(headerText.data() + pos, eol - pos);
      if (line.substr(0, 8) == "VERSION ") versionText = std::string(trim(line.substr(8)));
      pos = eol + 1;
    }

    std::vector<std::string> fieldNames;
    for (const auto& f : cloud_.fields) fieldNames.push_back(f.name);
    const uint64_t step = cloud_.point_step;
    if (dataType == 0) {
      // PCL's ascii parser turns a malformed value into 0 and a line with too many or too few
      // values into zeros, without an error; the body is parsed here instead, strictly, into the
      // same PCLPointCloud2 record layout that PCL would have produced.
      const uint64_t firstLine = 1 + std::count(headerText.begin(), headerText.end(), '\n');
      readAscii(path, firstLine, options.lenient);
    } else if (dataType == 1 && fileSize_ < dataIdx_ + total_ * step) {
      // Checked before PCL, which only says "failed", and so that lenient mode can keep the
      // complete records.
      const uint64_t complete =
          step ? (fileSize_ - std::min<uint64_t>(fileSize_, dataIdx_)) / step : 0;
      const std::string what =
          "data is truncated: the header declares " + std::to_string(total_) + " points of " +
          std::to_string(step) + " bytes from byte " + std::to_string(dataIdx_) + " (" +
          std::to_string(dataIdx_ + total_ * step) + " bytes), the file has " +
          std::to_string(fileSize_) + " bytes (" + std::to_string(complete) + " complete points)";
      if (!options.lenient) throw Error(path, Error::atByte(dataIdx_ + complete * step), what);
      warnings_.push_back(path + ": " + what + "; kept the complete points");
      // Binary PCD is the raw row-major record array that PCL would copy.
      const std::string bytes = readBytes(path, dataIdx_, complete * step);
      cloud_.data.assign(bytes.begin(), bytes.end());
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
    d["version"] = versionText;
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

  // PCL's readHeader allocates (and zero-fills) WIDTH * HEIGHT * point_step bytes before looking
  // at the body, so a damaged or hostile header could ask for terabytes. The header is scanned
  // here first: no PCD body holds more than ~100 times its size in points (LZF, which
  // binary_compressed uses, expands at most ~90x; ascii and binary far less).
  void checkDeclaredSize(const std::string& path) const {
    const std::string text = readBytes(path, 0, std::min<uint64_t>(fileSize_, 1 << 20));
    uint64_t width = 0, height = 1, points = 0, step = 0;
    std::vector<uint64_t> sizes, counts;
    size_t pos = 0;
    while (pos < text.size()) {
      size_t eol = text.find('\n', pos);
      if (eol == std::string::npos) eol = text.size();
      std::string_view line(text.data() + pos, eol - pos);
      pos = eol + 1;
      std::vector<uint64_t> values;
      const size_t sp = line.find(' ');
      const std::string_view key = line.substr(0, sp);
      for (size_t i = sp; i != std::string_view::npos && i < line.size();) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        uint64_t v = 0;
        auto r = std::from_chars(line.data() + i, line.data() + line.size(), v);
        if (r.ec != std::errc()) break;
        values.push_back(v);
        i = size_t(r.ptr - line.data());
      }
      if (key == "WIDTH" && !values.empty()) width = values[0];
      if (key == "HEIGHT" && !values.empty()) height = values[0];
      if (key == "POINTS" && !values.empty()) points = values[0];
      if (key == "SIZE") sizes = values;
      if (key == "COUNT") counts = values;
      if (key == "DATA") break;
    }
    for (size_t i = 0; i < sizes.size(); ++i)
      step += std::min<uint64_t>(sizes[i], 8) *
              (i < counts.size() ? std::min<uint64_t>(counts[i], 1 << 20) : 1);
    const double declared =
        double(std::max(points, width * std::min<uint64_t>(height, 1ull << 32))) * double(step);
    if (declared > 128.0 * double(fileSize_) + double(1 << 20))
      throw Error(path, "header",
                  "the header declares " + std::to_string(std::max(points, width * height)) +
                      " points of " + std::to_string(step) + " bytes, implausible for a file of " +
                      std::to_string(fileSize_) + " bytes");
  }

  static std::string readBytes(const std::string& path, uint64_t offset, uint64_t size) {
    std::ifstream in(path, std::ios::binary);
    std::string out(size, '\0');
    in.seekg(static_cast<std::streamoff>(offset));
    if (!in.read(out.data(), static_cast<std::streamsize>(size)))
      throw Error(path, Error::atByte(offset), "cannot read " + std::to_string(size) + " bytes");
    return out;
  }

  // One ascii value into the record. Integers are parsed as integers (a uint64 label survives),
  // floats as their own type (a float parses exactly as PCL's would).
  static bool parseValue(std::string_view tok, ScalarType t, uint8_t* dst) {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    const char* b = tok.data();
    const char* e = b + tok.size();
    auto whole = [&](std::from_chars_result r) { return r.ec == std::errc() && r.ptr == e; };
    switch (t) {
      case ScalarType::F32: {
        float v;
        if (!whole(std::from_chars(b, e, v))) return false;
        std::memcpy(dst, &v, 4);
        return true;
      }
      case ScalarType::F64: {
        double v;
        if (!whole(std::from_chars(b, e, v))) return false;
        std::memcpy(dst, &v, 8);
        return true;
      }
      case ScalarType::U64: {
        uint64_t v;
        if (!whole(std::from_chars(b, e, v))) return false;
        std::memcpy(dst, &v, 8);
        return true;
      }
      default: {
        int64_t v;
        if (!whole(std::from_chars(b, e, v))) return false;
        const double d = double(v);
        uint8_t tmp[8];
        storeFromDouble(t, d, tmp);  // clamps; a value out of range is an error instead
        if (loadAsDouble(t, tmp) != d) return false;
        std::memcpy(dst, tmp, scalarSize(t));
        return true;
      }
    }
  }

  void readAscii(const std::string& path, uint64_t firstLine, bool lenient) {
    const std::string body = readBytes(path, dataIdx_, fileSize_ - std::min(fileSize_, dataIdx_));
    struct Slot {
      const pcl::PCLPointField* field;
      ScalarType type;
      size_t offset;
    };
    std::vector<Slot> slots;  // one per value on a line
    for (const auto& f : cloud_.fields) {
      const ScalarType t = *scalarFromPcl(f.datatype);  // checked by planLayout
      for (uint32_t c = 0; c < f.count; ++c) slots.push_back({&f, t, f.offset + c * scalarSize(t)});
    }
    const size_t step = cloud_.point_step;
    cloud_.data.assign(total_ * step, 0);
    uint64_t record = 0, line = firstLine;
    std::vector<std::string_view> tokens;
    for (size_t pos = 0; pos < body.size(); ++line) {
      size_t eol = body.find('\n', pos);
      if (eol == std::string::npos) eol = body.size();
      const std::string_view text(body.data() + pos, eol - pos);
      pos = eol + 1;
      tokens.clear();
      for (size_t i = 0; i < text.size();) {
        while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r')) ++i;
        size_t j = i;
        while (j < text.size() && text[j] != ' ' && text[j] != '\t' && text[j] != '\r') ++j;
        if (j > i) tokens.emplace_back(text.substr(i, j - i));
        i = j;
      }
      if (tokens.empty()) continue;  // PCL skips empty lines too
      if (record == total_) {
        const std::string what =
            "more data lines than the " + std::to_string(total_) + " points the header declares";
        if (!lenient) throw Error(path, Error::atLine(line), what);
        warnings_.push_back(path + ": line " + std::to_string(line) + ": " + what +
                            "; ignored the rest");
        break;
      }
      if (tokens.size() != slots.size())
        throw Error(path, Error::atLine(line),
                    "expected " + std::to_string(slots.size()) + " values, found " +
                        std::to_string(tokens.size()));
      uint8_t* rec = cloud_.data.data() + record * step;
      for (size_t k = 0; k < slots.size(); ++k)
        if (!parseValue(tokens[k], slots[k].type, rec + slots[k].offset))
          throw Error(path, Error::atLine(line),
                      "value '" + std::string(tokens[k]) + "' of field '" + slots[k].field->name +
                          "' is not a valid " + scalarName(slots[k].type));
      ++record;
    }
    if (record < total_) {
      const std::string what = "data is truncated: " + std::to_string(record) + " of the " +
                               std::to_string(total_) + " points the header declares";
      if (!lenient) throw Error(path, Error::atLine(line), what);
      warnings_.push_back(path + ": " + what + "; kept them");
      cloud_.data.resize(record * step);
    }
  }

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
