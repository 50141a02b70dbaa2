// XYZ / PTS / TXT / CSV reader: one point per line, numbers separated by whitespace or commas.
//
// Text files do not say what their columns are. They come from ReadOptions::columns, or are
// guessed from how many numbers the first line holds, after the conventions of CloudCompare's
// ASCII export and Leica's PTS (whose first line is the point count, and whose 7 columns are
// x y z intensity r g b). A guess that the first line contradicts (a "colour" of 0.37) is an
// error that asks for the columns, rather than a silently wrong cloud.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/text.h"

namespace nestlight {
namespace {

inline bool isSeparator(char c) {
  return c == ',' || text::isBlank(c);
}

std::vector<std::string_view> tokens(std::string_view line) {
  return text::splitBy(line, [](char c) { return isSeparator(c); });
}

bool isNumber(std::string_view t) {
  double v;
  return text::parseDouble(t.data(), t.data() + t.size(), v);
}

enum class Col : uint8_t { Skip, X, Y, Z, Rgb8, Rgb16, Intensity, Normal, Classification, Float };

struct Column {
  Col kind = Col::Skip;
  uint8_t comp = 0;  // x/y/z, r/g/b, nx/ny/nz
  uint32_t dst = 0;  // byte offset in the point's attributes
  std::string name;  // as given, for messages
  double max = 0;    // integer columns: the largest value kept
  uint64_t clamped = 0;
};

class XyzReader final : public PointReader {
 public:
  XyzReader(std::shared_ptr<ByteSource> src, const ReadOptions& options)
      : src_(std::move(src)), options_(options) {
    const std::string& file = src_->name();
    if (src_->size() == 0) throw Error(file, Error::atByte(0), "empty file");
    const char* d = reinterpret_cast<const char*>(src_->data());
    size_t pos = 0;
    uint64_t line = 0;
    std::string_view text;
    nlohmann::json details = nlohmann::json::object();

    // A first line that is a single integer is a PTS point count.
    bool have = nextLine(d, pos, line, text);
    if (have) {
      auto t = tokens(text);
      uint64_t count;
      if (t.size() == 1 && text::parseInteger(t[0].data(), t[0].data() + t[0].size(), count)) {
        header_.declaredPoints = count;
        countLine_ = line;
        details["ptsCount"] = count;
        have = nextLine(d, pos, line, text);
      }
    }
    // A first line of words is a column header (CSV): kept in the details, not read.
    if (have) {
      auto t = tokens(text);
      if (!t.empty() && !isNumber(t[0])) {
        details["headerLine"] = text::validUtf8(text::trim(text));
        have = nextLine(d, pos, line, text);
      }
    }
    dataStart_ = have ? size_t(text.data() - d) : pos;
    dataLine_ = have ? line - 1 : line;

    std::vector<std::string> names;
    if (!options_.columns.empty()) {
      std::string_view spec = options_.columns;
      while (true) {
        size_t comma = spec.find(',');
        names.push_back(text::validUtf8(text::trim(spec.substr(0, comma))));
        if (comma == std::string_view::npos) break;
        spec.remove_prefix(comma + 1);
      }
      details["columnsFrom"] = "options";
    } else if (have) {
      names = guess(tokens(text), line);
      details["columnsFrom"] = "guessed";
    } else if (header_.declaredPoints == uint64_t(0)) {
      names = {"x", "y", "z"};
    } else {
      throw Error(file, Error::atLine(line),
                  "no points to read, and no columns given to read them with");
    }
    plan(names);

    std::string joined;
    for (auto& n : names) joined += (joined.empty() ? "" : ",") + n;
    details["columns"] = joined;
    details["separator"] =
        have && text.find(',') != std::string_view::npos ? "comma" : "whitespace";
    header_.path = file;
    header_.format = "xyz";
    header_.details = std::move(details);
    rewind();
  }

  const SourceHeader& header() const override { return header_; }
  uint64_t bytesConsumed() const override { return pos_; }
  uint64_t bytesTotal() const override { return src_->size(); }

  std::vector<std::string> warnings() const override {
    auto w = warnings_;
    for (const auto& c : columns_)
      if (c.clamped > 0)
        w.push_back(std::to_string(c.clamped) + " values of column '" + c.name +
                    "' were outside 0.." + std::to_string(uint64_t(c.max)) +
                    " (or not numbers) and were clamped");
    return w;
  }

  void rewind() override {
    pos_ = dataStart_;
    line_ = dataLine_;
    points_ = 0;
    ended_ = false;
    warnings_.clear();
    for (auto& c : columns_) c.clamped = 0;
    src_->releaseBefore(pos_);
  }

  bool read(PointBatch& batch, size_t maxPoints) override {
    // Resized rather than cleared, so that a reused batch is not zero-filled again.
    if (ended_) {
      batch.clear();
      return false;
    }
    const char* d = reinterpret_cast<const char*>(src_->data());
    const size_t stride = header_.layout.stride();
    // A point takes at least a digit and a separator per column: a header that claims more, or
    // a huge maxPoints, allocates no more than the rest of the file could hold.
    const size_t fit = (src_->size() - pos_) / (2 * columns_.size()) + 1;
    const size_t cap = std::min(maxPoints, fit);
    batch.xyz.resize(cap * 3);
    batch.attrs.resize(cap * stride);
    size_t n = 0;
    std::string_view text;
    while (n < cap) {
      if (!nextLine(d, pos_, line_, text)) {
        ended_ = true;
        atEnd();
        break;
      }
      if (header_.declaredPoints && points_ == *header_.declaredPoints && !options_.lenient)
        throw Error(src_->name(), Error::atLine(line_),
                    "more points than the " + std::to_string(*header_.declaredPoints) +
                        " that line " + std::to_string(countLine_) +
                        " declares (lenient mode keeps them all)");
      if (!parseLine(text, &batch.xyz[3 * n], batch.attrs.data() + n * stride)) {
        ended_ = true;
        atEnd();
        break;
      }
      ++n;
      ++points_;
    }
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * stride);
    src_->releaseBefore(pos_);
    return n > 0;
  }

 private:
  // The next line with something other than blanks and comments; `line` counts every line.
  bool nextLine(const char* d, size_t& pos, uint64_t& line, std::string_view& out) const {
    const size_t size = src_->size();
    std::string_view l;
    while (text::takeLine(d, size, pos, l)) {
      ++line;
      size_t i = 0;
      while (i < l.size() && text::isBlank(l[i])) ++i;
      if (i == l.size() || l[i] == '#' || (l[i] == '/' && i + 1 < l.size() && l[i + 1] == '/'))
        continue;
      out = l;
      return true;
    }
    return false;
  }

  std::vector<std::string> guess(const std::vector<std::string_view>& t, uint64_t line) const {
    std::vector<std::string> names;
    int rgbAt = -1;
    switch (t.size()) {
      case 3:
        names = {"x", "y", "z"};
        break;
      case 4:
        names = {"x", "y", "z", "i"};
        break;
      case 6:
        names = {"x", "y", "z", "r", "g", "b"};
        rgbAt = 3;
        break;
      case 7:
        names = {"x", "y", "z", "i", "r", "g", "b"};
        rgbAt = 4;
        break;
      case 9:
        names = {"x", "y", "z", "r", "g", "b", "nx", "ny", "nz"};
        rgbAt = 3;
        break;
      case 10:
        names = {"x", "y", "z", "i", "r", "g", "b", "nx", "ny", "nz"};
        rgbAt = 4;
        break;
      default:
        throw Error(src_->name(), Error::atLine(line),
                    "cannot guess what " + std::to_string(t.size()) +
                        " columns are (3, 4, 6, 7, 9 and 10 have conventions); name them with "
                        "--columns, e.g. --columns x,y,z,_,intensity");
    }
    if (rgbAt >= 0)
      for (int c = 0; c < 3; ++c) {
        double v;
        std::string_view s = t[rgbAt + c];
        if (!text::parseDouble(s.data(), s.data() + s.size(), v) || !(v >= 0 && v <= 255) ||
            v != std::floor(v))
          throw Error(src_->name(), Error::atLine(line),
                      "guessed column " + std::to_string(rgbAt + c + 1) +
                          " to be a 0-255 colour, but it holds " + text::quote(s) +
                          "; name the columns with --columns (e.g. x,y,z,nx,ny,nz)");
      }
    return names;
  }

  void plan(const std::vector<std::string>& names) {
    const std::string& file = src_->name();
    auto bad = [&](const std::string& why) {
      return Error(file, "", "columns '" + options_.columns + "': " + why);
    };
    PointLayout layout;
    int seen[3] = {0, 0, 0};
    int rgb8 = 0, rgb16 = 0, normals = 0;
    for (const auto& name : names) {
      Column c;
      c.name = name;
      if (name.empty()) throw bad("an empty column name");
      auto group = [&](Col kind, std::string_view attrName, ScalarType t, int comp, double max) {
        c.kind = kind;
        c.comp = uint8_t(comp);
        c.max = max;
        int a = layout.find(attrName);
        if (a < 0)
          a = int(layout.add({std::string(attrName), t, comp >= 0 ? 3u : 1u, "text column"}));
        c.dst = uint32_t(layout.offset(a) + (comp > 0 ? comp * scalarSize(t) : 0));
      };
      if (name == "x" || name == "y" || name == "z") {
        c.kind = name == "x" ? Col::X : name == "y" ? Col::Y : Col::Z;
        c.comp = uint8_t(name[0] - 'x');
        if (seen[c.comp]++) throw bad("'" + name + "' twice");
      } else if (name == "r" || name == "g" || name == "b") {
        ++rgb8;
        group(Col::Rgb8, attr::kRgb, ScalarType::U16, name == "r" ? 0 : name == "g" ? 1 : 2, 255);
      } else if (name == "R" || name == "G" || name == "B") {
        ++rgb16;
        group(Col::Rgb16, attr::kRgb, ScalarType::U16,
              name == "R"   ? 0
              : name == "G" ? 1
                            : 2,
              65535);
      } else if (name == "nx" || name == "ny" || name == "nz") {
        ++normals;
        group(Col::Normal, attr::kNormal, ScalarType::F32, name[1] - 'x', 0);
      } else if (name == "i" || name == "intensity") {
        if (layout.has(attr::kIntensity)) throw bad("intensity twice");
        group(Col::Intensity, attr::kIntensity, ScalarType::U16, -1, 65535);
      } else if (name == "classification") {
        if (layout.has(attr::kClassification)) throw bad("classification twice");
        group(Col::Classification, attr::kClassification, ScalarType::U8, -1, 255);
      } else if (name == "_") {
        c.kind = Col::Skip;
      } else {
        if (name == attr::kRgb || name == attr::kNormal)
          throw bad("'" + name + "' is reserved; use r,g,b (or R,G,B) and nx,ny,nz");
        if (layout.has(name)) throw bad("'" + name + "' twice");
        c.kind = Col::Float;
        c.dst = uint32_t(layout.offset(layout.add({name, ScalarType::F32, 1, "text column"})));
      }
      columns_.push_back(std::move(c));
    }
    if (!seen[0] || !seen[1] || !seen[2]) throw bad("x, y and z are required");
    if (rgb8 && rgb16) throw bad("r,g,b (0-255) and R,G,B (0-65535) cannot be mixed");
    if ((rgb8 && rgb8 != 3) || (rgb16 && rgb16 != 3)) throw bad("colour needs all of r, g and b");
    if (normals && normals != 3) throw bad("normals need all of nx, ny and nz");
    // Each colour or normal component once: three names, three distinct components.
    for (Col kind : {Col::Rgb8, Col::Rgb16, Col::Normal}) {
      int mask = 0;
      for (auto& c : columns_)
        if (c.kind == kind) {
          if (mask & (1 << c.comp)) throw bad("'" + c.name + "' twice");
          mask |= 1 << c.comp;
        }
    }
    header_.rgbBits = rgb8 ? 8 : rgb16 ? 16 : 0;
    header_.layout = std::move(layout);
  }

  // Integer columns: rounded, and clamped to [0, max] with a count for the warnings.
  template <typename T>
  void storeClamped(Column& c, double v, double scale, uint8_t* dst) {
    if (!(v >= 0 && v <= c.max)) {
      ++c.clamped;
      v = v > c.max ? c.max : 0;
    }
    T out = T(std::nearbyint(v) * scale);
    std::memcpy(dst, &out, sizeof out);
  }

  // False when the line is the incomplete last line of the file and lenient mode drops it.
  bool parseLine(std::string_view text, double* xyz, uint8_t* attrs) {
    const char* p = text.data();
    const char* e = p + text.size();
    for (size_t j = 0; j < columns_.size(); ++j) {
      while (p < e && isSeparator(*p)) ++p;
      if (p == e) return wrongCount(text);
      const char* tb = p;
      while (p < e && !isSeparator(*p)) ++p;
      Column& c = columns_[j];
      if (c.kind == Col::Skip) continue;
      if (c.kind == Col::Normal || c.kind == Col::Float) {
        float f;
        if (!text::parseFloat(tb, p, f)) badNumber(tb, p, j);
        std::memcpy(attrs + c.dst, &f, 4);
        continue;
      }
      double v;
      int64_t iv;
      if (c.kind != Col::X && c.kind != Col::Y && c.kind != Col::Z && text::parseInteger(tb, p, iv))
        v = double(iv);
      else if (!text::parseDouble(tb, p, v))
        badNumber(tb, p, j);
      switch (c.kind) {
        case Col::X:
        case Col::Y:
        case Col::Z:
          xyz[c.comp] = v;
          break;
        case Col::Rgb8:
          storeClamped<uint16_t>(c, v, 257, attrs + c.dst);
          break;
        case Col::Rgb16:
        case Col::Intensity:
          storeClamped<uint16_t>(c, v, 1, attrs + c.dst);
          break;
        case Col::Classification:
          storeClamped<uint8_t>(c, v, 1, attrs + c.dst);
          break;
        default:
          break;
      }
    }
    while (p < e && isSeparator(*p)) ++p;
    if (p != e) return wrongCount(text);
    return true;
  }

  bool wrongCount(std::string_view text) {
    const size_t found = tokens(text).size();
    // The last line of a cut file: lenient mode keeps the points before it.
    size_t after = pos_;
    uint64_t line = line_;
    std::string_view more;
    const bool last = !nextLine(reinterpret_cast<const char*>(src_->data()), after, line, more);
    if (last && found < columns_.size() && options_.lenient) {
      warnings_.push_back(Error::atLine(line_) +
                          ": dropped the incomplete "
                          "last line (" +
                          std::to_string(found) + " of " + std::to_string(columns_.size()) +
                          " values)");
      return false;
    }
    throw Error(src_->name(), Error::atLine(line_),
                "expected " + std::to_string(columns_.size()) + " values (columns " +
                    header_.details.value("columns", std::string()) + "), found " +
                    std::to_string(found) + (last ? "; the file may be truncated" : ""));
  }

  [[noreturn]] void badNumber(const char* b, const char* e, size_t column) const {
    throw Error(src_->name(), Error::atLine(line_),
                "cannot read " + text::quote(std::string_view(b, size_t(e - b))) +
                    " as a number (column " + std::to_string(column + 1) + ", '" +
                    columns_[column].name + "')");
  }

  // The PTS count against the points found.
  void atEnd() {
    if (!header_.declaredPoints || *header_.declaredPoints == points_) return;
    const std::string msg = "line " + std::to_string(countLine_) + " declares " +
                            std::to_string(*header_.declaredPoints) +
                            " points but the file holds " + std::to_string(points_);
    if (!options_.lenient)
      throw Error(src_->name(), Error::atLine(line_),
                  msg + " (lenient mode keeps the points that are there)");
    warnings_.push_back(msg);
  }

  std::shared_ptr<ByteSource> src_;
  ReadOptions options_;
  SourceHeader header_;
  std::vector<Column> columns_;
  uint64_t countLine_ = 0;
  size_t dataStart_ = 0;
  uint64_t dataLine_ = 0;

  size_t pos_ = 0;
  uint64_t line_ = 0;
  uint64_t points_ = 0;
  bool ended_ = false;
  std::vector<std::string> warnings_;
};

}  // namespace

std::unique_ptr<PointReader> openXyz(std::shared_ptr<ByteSource> src, const ReadOptions& o) {
  return std::make_unique<XyzReader>(std::move(src), o);
}

}  // namespace nestlight
