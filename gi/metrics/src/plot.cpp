// SVG and PNG charts. References: W3C SVG 1.1 (Second Edition), 2011, for the format; Okabe and
// Ito, "Color Universal Design" (2008), for a palette that colour-blind readers can tell apart;
// tick steps of 1, 2 and 5 times a power of ten as in Heckbert, "Nice numbers for graph labels",
// Graphics Gems, 1990; point labels placed greedily at the first of a fixed list of candidate
// positions that is free, as in Christensen, Marks and Shieber, "An empirical study of algorithms
// for point-feature label placement", ACM TOG 1995.
#include "nestlight/gi/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/octree/error.h"
#include "plot_font.h"

namespace nestlight::gi {
namespace {

// Blue, vermillion, bluish green, reddish purple, orange, sky blue, black, yellow: Okabe-Ito,
// reordered so that the first series get the colours that read best on white.
constexpr std::array<const char*, 8> kColours = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                 "#E69F00", "#56B4E9", "#000000", "#F0E442"};
// Circle, square, triangle, diamond, down triangle, plus, star, cross: a second cue beside colour.
constexpr int kShapes = 8;

constexpr double kMarginLeft = 80, kMarginTop = 50, kPlotW = 520, kPlotH = 380, kMarginBottom = 60;
constexpr double kLegendGap = 30, kNoteLine = 16, kMarkerR = 4;
constexpr double kFontSize = 12, kLabelFontSize = 10, kTitleFontSize = 15;

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// Width of `text` in DejaVu Sans at `size` pixels, by the glyphs' advances: the label boxes are
// measured with the font the PNG draws and the SVG names first.
double textWidth(const std::string& text, double size) {
  const plotfont::Font& f = size <= 11 ? plotfont::kFont10 : plotfont::kFont12;
  double w = 0;
  for (char ch : text) {
    const unsigned c = static_cast<unsigned char>(ch);
    w += f.glyphs[c >= 32 && c < 127 ? c - 32 : '?' - 32].advance;
  }
  return w * size / f.pixels;
}

struct Tick {
  double at;           // on the axis' own scale (log10 of the value on a log axis)
  std::string text;    // plain text ("10" of 10^3, "0.5")
  std::string raised;  // an exponent drawn raised after it ("3" of 10^3), or ""
  bool major = true;
};

struct Axis {
  bool log = false;
  double lo = 0, hi = 1;  // on the axis' own scale
  std::vector<Tick> ticks;
  double scale(double v) const { return log ? std::log10(v) : v; }
  double fraction(double v) const { return (scale(v) - lo) / (hi - lo); }
};

Tick decadeTick(int k) {
  // 10 with a raised exponent; 1 and 10 themselves read better plain.
  if (k == 0) return {0, "1", "", true};
  if (k == 1) return {1, "10", "", true};
  return {double(k), "10", std::to_string(k), true};
}

Axis logAxis(double minV, double maxV) {
  Axis a;
  a.log = true;
  // The nudge keeps exact decades (log10(1000) may land a hair above 3) from adding a decade.
  double lo = std::floor(std::log10(minV) + 1e-9), hi = std::ceil(std::log10(maxV) - 1e-9);
  if (hi <= lo) lo -= 1, hi += 1;  // one value, exactly a decade: show a decade either side
  const int decades = int(hi - lo);
  const int step = std::max(1, (decades + 7) / 8);  // at most about 8 labelled decades
  hi = lo + std::ceil(double(decades) / step) * step;
  a.lo = lo, a.hi = hi;
  for (double k = lo; k <= hi + 0.5; k += step) {
    a.ticks.push_back(decadeTick(int(k)));
    if (step == 1 && decades <= 6 && k < hi)
      for (int m = 2; m <= 9; ++m) a.ticks.push_back({k + std::log10(double(m)), "", "", false});
  }
  return a;
}
Axis linearAxis(double minV, double maxV) {
  Axis a;
  if (maxV == minV) {
    const double pad = minV == 0 ? 1.0 : std::abs(minV) * 0.5;
    minV -= pad, maxV += pad;
  }
  a.lo = minV, a.hi = maxV;
  const double raw = (maxV - minV) / 6;
  if (!std::isfinite(raw) || !(raw > 0)) return a;  // beyond double's range: frame without ticks
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / mag;
  const double step = (norm < 1.5 ? 1 : norm < 3 ? 2 : norm < 7 ? 5 : 10) * mag;
  if (!std::isfinite(step) || !(step > 0)) return a;
  const double first = std::floor(minV / step), last = std::ceil(maxV / step);
  if (!(last - first <= 50)) return a;
  a.lo = first * step, a.hi = last * step;
  if (!(a.hi > a.lo)) a.lo = minV, a.hi = maxV;
  // An integer count, not `i <= last; ++i` on the doubles: beyond 2^53, ++i would not move.
  const int count = int(last - first);
  for (int n = 0; n <= count; ++n) {
    double v = (first + n) * step;
    if (std::abs(v) < step * 1e-9) v = 0;  // -0 and rounding residue print as 0
    char buf[40];
    std::snprintf(buf, sizeof buf, "%g", v);
    a.ticks.push_back({v, buf, "", true});
  }
  return a;
}

Axis makeAxis(const std::vector<double>& values, bool log) {
  if (values.empty()) return log ? logAxis(1, 10) : linearAxis(0, 1);
  const auto [mn, mx] = std::minmax_element(values.begin(), values.end());
  return log ? logAxis(*mn, *mx) : linearAxis(*mn, *mx);
}

// The outline of marker `shape` of radius r around (x, y); the circle (shape 0) is none.
std::vector<std::pair<double, double>> markerOutline(int shape, double x, double y, double r) {
  std::vector<std::pair<double, double>> p;
  auto star = [&](int spikes, double inner, double turn) {
    for (int i = 0; i < 2 * spikes; ++i) {
      const double a = turn + M_PI * i / spikes, rr = i % 2 ? inner * r : 1.25 * r;
      p.push_back({x + rr * std::sin(a), y - rr * std::cos(a)});
    }
  };
  switch (shape % kShapes) {
    case 0:
      break;
    case 1:
      p = {{x - r, y - r}, {x + r, y - r}, {x + r, y + r}, {x - r, y + r}};
      break;
    case 2:
      p = {{x, y - 1.2 * r}, {x + 1.1 * r, y + 0.8 * r}, {x - 1.1 * r, y + 0.8 * r}};
      break;
    case 3:
      p = {{x, y - 1.3 * r}, {x + 1.3 * r, y}, {x, y + 1.3 * r}, {x - 1.3 * r, y}};
      break;
    case 4:
      p = {{x, y + 1.2 * r}, {x - 1.1 * r, y - 0.8 * r}, {x + 1.1 * r, y - 0.8 * r}};
      break;
    case 5:
    case 7: {  // plus, and the same turned by 45 degrees (a cross)
      const double a = 1.25 * r, b = 0.42 * r, t = shape % kShapes == 7 ? M_PI / 4 : 0;
      const double pts[12][2] = {{-b, -a}, {b, -a}, {b, -b}, {a, -b}, {a, b},   {b, b},
                                 {b, a},   {-b, a}, {-b, b}, {-a, b}, {-a, -b}, {-b, -b}};
      for (const auto& q : pts)
        p.push_back({x + q[0] * std::cos(t) - q[1] * std::sin(t),
                     y + q[0] * std::sin(t) + q[1] * std::cos(t)});
      break;
    }
    default:
      star(5, 0.5, 0);
  }
  return p;
}

std::string markerSvg(int shape, double x, double y, const std::string& attrs) {
  if (shape % kShapes == 0)
    return "<circle " + attrs + " cx=\"" + num(x) + "\" cy=\"" + num(y) + "\" r=\"" +
           num(kMarkerR) + "\"";
  std::string d;
  for (const auto& [px, py] : markerOutline(shape, x, y, kMarkerR))
    d += (d.empty() ? "M" : " L") + num(px) + "," + num(py);
  return "<path " + attrs + " d=\"" + d + " Z\"";
}

std::string plural(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Everything both renderers place: the public layout, the axes, the points in pixels, the notes.
struct Chart {
  PlotLayout layout;
  Axis ax, ay;
  std::vector<std::vector<std::pair<const PlotPoint*, std::pair<double, double>>>> drawn;
  std::vector<std::string> notes;
  double left = kMarginLeft, top = kMarginTop, right = kMarginLeft + kPlotW,
         bottom = kMarginTop + kPlotH, legendX = kMarginLeft + kPlotW + kLegendGap;
  std::string legendText(size_t s, const std::vector<PlotSeries>& series) const {
    return series[s].name + (drawn[s].empty() ? " (nothing drawn)" : "");
  }
};

// One colour per group (in order of first appearance), one marker per series within it.
std::vector<PlotLayout::Style> styles(const std::vector<PlotSeries>& series) {
  std::vector<PlotLayout::Style> out;
  std::vector<std::string> groups;
  std::vector<int> members;
  for (size_t s = 0; s < series.size(); ++s) {
    if (series[s].group.empty()) {
      out.push_back({kColours[s % kColours.size()], int(s % kShapes)});
      continue;
    }
    const auto it = std::find(groups.begin(), groups.end(), series[s].group);
    const size_t g = size_t(it - groups.begin());
    if (it == groups.end()) groups.push_back(series[s].group), members.push_back(0);
    out.push_back({kColours[g % kColours.size()], members[g]++ % kShapes});
  }
  return out;
}

// Greedy placement: each label takes the first candidate position around its marker whose box
// stays inside the plot and touches no marker and no label placed before it.
void placeLabels(Chart& c) {
  std::vector<PlotLayout::Box> taken;
  const double m = kMarkerR + 1.5;
  for (const auto& pts : c.drawn)
    for (const auto& [p, xy] : pts)
      taken.push_back({xy.first - m, xy.second - m, xy.first + m, xy.second + m});
  const double asc = 0.8 * kLabelFontSize, desc = 0.25 * kLabelFontSize;
  for (size_t s = 0; s < c.drawn.size(); ++s)
    for (size_t i = 0; i < c.drawn[s].size(); ++i) {
      const PlotPoint* p = c.drawn[s][i].first;
      if (p->label.empty()) continue;
      const auto [x, y] = c.drawn[s][i].second;
      const double w = textWidth(p->label, kLabelFontSize);
      bool placed = false;
      for (double d : {6.0, 12.0, 20.0}) {
        // Baseline starts: right, left, above, below, then the diagonals.
        const double cand[8][2] = {{x + d, y + asc / 2 - desc / 2},
                                   {x - d - w, y + asc / 2 - desc / 2},
                                   {x - w / 2, y - d},
                                   {x - w / 2, y + d + asc},
                                   {x + d, y - d},
                                   {x - d - w, y - d},
                                   {x + d, y + d + asc},
                                   {x - d - w, y + d + asc}};
        for (const auto& b : cand) {
          const PlotLayout::Box box{b[0] - 1, b[1] - asc - 1, b[0] + w + 1, b[1] + desc + 1};
          if (box.x0 < c.left || box.x1 > c.right || box.y0 < c.top || box.y1 > c.bottom) continue;
          if (std::any_of(taken.begin(), taken.end(),
                          [&](const PlotLayout::Box& t) { return t.overlaps(box); }))
            continue;
          taken.push_back(box);
          c.layout.labels.push_back({s, i, b[0], b[1], box, p->label});
          placed = true;
          break;
        }
        if (placed) break;
      }
      if (!placed) ++c.layout.labelsLeftOut;
    }
}

Chart makeChart(const std::vector<PlotSeries>& series, bool logX, bool logY) {
  Chart c;
  // Sort points into drawable and left out before sizing the axes, which only drawable ones shape.
  size_t skippedLog = 0, skippedNonFinite = 0;
  std::vector<std::vector<const PlotPoint*>> keep(series.size());
  std::vector<double> xs, ys;
  for (size_t s = 0; s < series.size(); ++s)
    for (const PlotPoint& p : series[s].points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        ++skippedNonFinite;
        continue;
      }
      if ((logX && p.x <= 0) || (logY && p.y <= 0)) {
        ++skippedLog;
        continue;
      }
      keep[s].push_back(&p);
      xs.push_back(p.x);
      ys.push_back(p.y);
    }
  c.ax = makeAxis(xs, logX), c.ay = makeAxis(ys, logY);
  c.drawn.resize(series.size());
  for (size_t s = 0; s < series.size(); ++s)
    for (const PlotPoint* p : keep[s])
      c.drawn[s].push_back(
          {p, {c.left + c.ax.fraction(p->x) * kPlotW, c.bottom - c.ay.fraction(p->y) * kPlotH}});
  if (xs.empty()) c.notes.push_back("No point to draw.");
  if (skippedLog)
    c.notes.push_back(plural(skippedLog, "point", "points") +
                      " left out: zero or negative values cannot be drawn on a log axis.");
  if (skippedNonFinite)
    c.notes.push_back(plural(skippedNonFinite, "point", "points") +
                      " left out: not finite (NaN or Inf).");
  c.layout.styles = styles(series);
  placeLabels(c);
  if (c.layout.labelsLeftOut)
    c.notes.push_back(plural(c.layout.labelsLeftOut, "point label", "point labels") +
                      " left out where they would overlap (each marker's tooltip has it).");
  double legendW = 0;
  for (size_t s = 0; s < series.size(); ++s)
    legendW = std::max(legendW, textWidth(c.legendText(s, series), kFontSize));
  c.layout.width = std::max(800.0, std::ceil(c.legendX + 36 + legendW + 20));
  c.layout.height =
      std::ceil(std::max(c.bottom + kMarginBottom + kNoteLine * double(c.notes.size()) + 10,
                         c.top + 22 * double(series.size()) + 20));
  return c;
}

// The centre of a line of text under the plot, moved inward where it would run off the chart.
double centredX(const Chart& c, const std::string& text, double size) {
  const double w = textWidth(text, size), mid = c.left + kPlotW / 2;
  if (mid + w / 2 > c.layout.width - 5) return std::max(c.layout.width - w / 2 - 5, w / 2 + 5);
  return std::max(mid, w / 2 + 5);
}

std::string svgText(double x, double y, const std::string& anchor, const std::string& body,
                    const std::string& attrs = "") {
  return "<text " + attrs + (attrs.empty() ? "" : " ") + "x=\"" + num(x) + "\" y=\"" + num(y) +
         "\"" + (anchor.empty() ? "" : " text-anchor=\"" + anchor + "\"") + ">" + body +
         "</text>\n";
}

std::string tickSvg(const Tick& t) {
  return xmlEscape(t.text) + (t.raised.empty() ? ""
                                               : "<tspan dy=\"-6\" font-size=\"9\">" +
                                                     xmlEscape(t.raised) + "</tspan>");
}

void svgAxes(std::ostringstream& o, const Chart& c) {
  o << "<g class=\"axes\" stroke-width=\"1\">\n";
  for (const Tick& t : c.ax.ticks) {
    const double x = c.left + (t.at - c.ax.lo) / (c.ax.hi - c.ax.lo) * kPlotW;
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(c.top) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(c.bottom) << "\" stroke=\"" << (t.major ? "#dddddd" : "#f0f0f0") << "\"/>\n";
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(c.bottom) << "\" x2=\"" << num(x)
      << "\" y2=\"" << num(c.bottom + (t.major ? 5 : 3)) << "\" stroke=\"black\"/>\n";
    if (t.major) o << svgText(x, c.bottom + 20, "middle", tickSvg(t), "class=\"tick\"");
  }
  for (const Tick& t : c.ay.ticks) {
    const double y = c.bottom - (t.at - c.ay.lo) / (c.ay.hi - c.ay.lo) * kPlotH;
    o << "<line x1=\"" << num(c.left) << "\" y1=\"" << num(y) << "\" x2=\"" << num(c.right)
      << "\" y2=\"" << num(y) << "\" stroke=\"" << (t.major ? "#dddddd" : "#f0f0f0") << "\"/>\n";
    o << "<line x1=\"" << num(c.left - (t.major ? 5 : 3)) << "\" y1=\"" << num(y) << "\" x2=\""
      << num(c.left) << "\" y2=\"" << num(y) << "\" stroke=\"black\"/>\n";
    if (t.major) o << svgText(c.left - 8, y + 4, "end", tickSvg(t), "class=\"tick\"");
  }
  o << "<rect x=\"" << num(c.left) << "\" y=\"" << num(c.top) << "\" width=\"" << num(kPlotW)
    << "\" height=\"" << num(kPlotH) << "\" fill=\"none\" stroke=\"black\"/>\n";
  o << "</g>\n";
}

}  // namespace

int plotMarkerCount() {
  return kShapes;
}
int plotColourCount() {
  return int(kColours.size());
}

PlotLayout plotLayout(const std::vector<PlotSeries>& series, bool logX, bool logY) {
  return makeChart(series, logX, logY).layout;
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char ch : text) {
    const unsigned char c = static_cast<unsigned char>(ch);
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += (c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f ? '?' : ch;
    }
  }
  return out;
}

std::string svgPlot(const std::string& title, const std::string& xLabel, const std::string& yLabel,
                    const std::vector<PlotSeries>& series, bool logX, bool logY) {
  const Chart c = makeChart(series, logX, logY);
  const PlotLayout& L = c.layout;
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(L.width) << "\" height=\""
    << num(L.height) << "\" viewBox=\"0 0 " << num(L.width) << " " << num(L.height)
    << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
  o << "<rect x=\"0\" y=\"0\" width=\"" << num(L.width) << "\" height=\"" << num(L.height)
    << "\" fill=\"white\"/>\n";
  o << svgText(centredX(c, title, kTitleFontSize), c.top - 20, "middle", xmlEscape(title),
               "class=\"title\" font-size=\"15\"");
  svgAxes(o, c);
  o << svgText(centredX(c, xLabel, kFontSize), c.bottom + 45, "middle", xmlEscape(xLabel),
               "class=\"axis-label\"");
  o << "<text class=\"axis-label\" transform=\"translate(" << num(c.left - 58) << ","
    << num(c.top + kPlotH / 2) << ") rotate(-90)\" text-anchor=\"middle\">" << xmlEscape(yLabel)
    << "</text>\n";

  // Series: line first so markers sit on top of it.
  for (size_t s = 0; s < series.size(); ++s) {
    const std::string& colour = L.styles[s].colour;
    const int shape = L.styles[s].marker;
    const std::string name = xmlEscape(series[s].name);
    o << "<g class=\"series\" data-name=\"" << name << "\">\n";
    if (c.drawn[s].size() > 1) {
      o << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.5\" points=\"";
      for (const auto& [p, xy] : c.drawn[s]) o << num(xy.first) << "," << num(xy.second) << " ";
      o << "\"/>\n";
    }
    for (const auto& [p, xy] : c.drawn[s]) {
      char coords[80];
      std::snprintf(coords, sizeof coords, "(%g, %g)", p->x, p->y);
      o << markerSvg(
               shape, xy.first, xy.second,
               "class=\"marker\" fill=\"" + colour + "\" stroke=\"white\" stroke-width=\"0.8\"")
        << "><title>" << name << " " << coords << (p->label.empty() ? "" : " ")
        << xmlEscape(p->label) << "</title></" << (shape == 0 ? "circle" : "path") << ">\n";
    }
    o << "</g>\n";
  }
  for (const PlotLayout::Label& l : L.labels)
    o << svgText(l.x, l.y, "", xmlEscape(l.text),
                 "class=\"point-label\" font-size=\"10\" fill=\"#333333\"");

  // Legend beside the plot, so it never hides a point.
  o << "<g class=\"legend\">\n";
  for (size_t s = 0; s < series.size(); ++s) {
    const std::string& colour = L.styles[s].colour;
    const double y = c.top + 10 + 22 * double(s);
    o << "<line x1=\"" << num(c.legendX) << "\" y1=\"" << num(y) << "\" x2=\""
      << num(c.legendX + 28) << "\" y2=\"" << num(y) << "\" stroke=\"" << colour
      << "\" stroke-width=\"1.5\"/>\n";
    o << markerSvg(L.styles[s].marker, c.legendX + 14, y,
                   "class=\"legend-marker\" fill=\"" + colour + "\"")
      << "/>\n";
    o << svgText(c.legendX + 36, y + 4, "", xmlEscape(c.legendText(s, series)));
  }
  o << "</g>\n";
  for (size_t i = 0; i < c.notes.size(); ++i)
    o << svgText(c.left, c.bottom + kMarginBottom + 4 + kNoteLine * double(i), "",
                 xmlEscape(c.notes[i]), "class=\"note\" font-size=\"11\" fill=\"#a00000\"");
  o << "</svg>\n";
  return o.str();
}

void writeSvgPlot(const std::string& path, const std::string& title, const std::string& xLabel,
                  const std::string& yLabel, const std::vector<PlotSeries>& series, bool logX,
                  bool logY) {
  const std::string svg = svgPlot(title, xLabel, yLabel, series, logX, logY);
  const std::string tmp = path + ".partial";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f.write(svg.data(), std::streamsize(svg.size()));
    f.close();
    if (!f) {
      std::remove(tmp.c_str());
      throw Error(path, "", "cannot write SVG plot");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw Error(path, "", "cannot rename " + tmp + ": " + ec.message());
  }
}

namespace {

// A white RGB canvas in [0, 1] that blends colour by coverage: the PNG's drawing.
struct Canvas {
  HdrImage img;
  Canvas(int w, int h) {
    img.width = w, img.height = h;
    img.rgb.assign(size_t(w) * size_t(h) * 3, 1.0f);
  }
  static std::array<float, 3> rgb(const std::string& hex) {
    const unsigned v = unsigned(std::stoul(hex.substr(1), nullptr, 16));
    return {float(v >> 16 & 255) / 255, float(v >> 8 & 255) / 255, float(v & 255) / 255};
  }
  void blend(int x, int y, const std::array<float, 3>& c, double a) {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height || !(a > 0)) return;
    float* p = &img.rgb[(size_t(y) * size_t(img.width) + size_t(x)) * 3];
    const float k = float(std::min(a, 1.0));
    for (int i = 0; i < 3; ++i) p[i] += k * (c[i] - p[i]);
  }
  // A segment `w` pixels wide: each pixel's coverage from its centre's distance to it.
  void line(double x0, double y0, double x1, double y1, double w, const std::array<float, 3>& c) {
    const double h = w / 2 + 0.5, dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    for (int y = int(std::floor(std::min(y0, y1) - h)); y <= int(std::ceil(std::max(y0, y1) + h));
         ++y)
      for (int x = int(std::floor(std::min(x0, x1) - h)); x <= int(std::ceil(std::max(x0, x1) + h));
           ++x) {
        const double px = x + 0.5 - x0, py = y + 0.5 - y0;
        const double t = len2 > 0 ? std::clamp((px * dx + py * dy) / len2, 0.0, 1.0) : 0.0;
        const double d = std::hypot(px - t * dx, py - t * dy);
        blend(x, y, c, std::clamp(w / 2 + 0.5 - d, 0.0, 1.0));
      }
  }
  // A marker filled at 4 x 4 samples a pixel (even-odd rule on its outline, or a disc).
  void marker(int shape, double cx, double cy, double r, const std::array<float, 3>& c) {
    const auto poly = markerOutline(shape, cx, cy, r);
    auto inside = [&](double x, double y) {
      if (poly.empty()) return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r;
      bool in = false;
      for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
        const auto [xi, yi] = poly[i];
        const auto [xj, yj] = poly[j];
        if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) in = !in;
      }
      return in;
    };
    const int R = int(std::ceil(1.4 * r)) + 1;
    for (int y = int(cy) - R; y <= int(cy) + R; ++y)
      for (int x = int(cx) - R; x <= int(cx) + R; ++x) {
        int n = 0;
        for (int sy = 0; sy < 4; ++sy)
          for (int sx = 0; sx < 4; ++sx) n += inside(x + (sx + 0.5) / 4, y + (sy + 0.5) / 4);
        blend(x, y, c, n / 16.0);
      }
  }
  // Text from its baseline's start (rotated: reading upwards, the baseline's start at the bottom).
  double text(double x, double y, const std::string& s, double size, const std::array<float, 3>& c,
              bool rotated = false) {
    const plotfont::Font& f = size <= 11 ? plotfont::kFont10 : plotfont::kFont12;
    int pen = 0;
    for (char ch : s) {
      const unsigned u = static_cast<unsigned char>(ch);
      const plotfont::Glyph& g = f.glyphs[u >= 32 && u < 127 ? u - 32 : '?' - 32];
      for (int r = 0; r < g.rows; ++r)
        for (int k = 0; k < g.width; ++k) {
          const char h = g.bits[r * g.width + k];
          const double a = (h <= '9' ? h - '0' : h - 'a' + 10) / 15.0;
          const int u0 = pen + g.left + k, v0 = r - g.top;  // along and below the baseline
          if (rotated)
            blend(int(std::lround(x)) + v0, int(std::lround(y)) - u0, c, a);
          else
            blend(int(std::lround(x)) + u0, int(std::lround(y)) + v0, c, a);
        }
      pen += g.advance;
    }
    return pen;
  }
  double textAnchored(double x, double y, const std::string& s, double size,
                      const std::array<float, 3>& c, const std::string& anchor) {
    const double w = textWidth(s, size);
    return text(anchor == "middle" ? x - w / 2 : anchor == "end" ? x - w : x, y, s, size, c);
  }
};

void pngAxes(Canvas& cv, const Chart& c) {
  const auto black = Canvas::rgb("#000000"), major = Canvas::rgb("#dddddd"),
             minor = Canvas::rgb("#f0f0f0");
  auto tickLabel = [&](double x, double y, const Tick& t, const std::string& anchor) {
    const double w = textWidth(t.text, kFontSize) + textWidth(t.raised, 9);
    const double x0 = anchor == "middle" ? x - w / 2 : anchor == "end" ? x - w : x;
    const double adv = cv.text(x0, y, t.text, kFontSize, black);
    if (!t.raised.empty()) cv.text(x0 + adv, y - 6, t.raised, 9, black);
  };
  for (const Tick& t : c.ax.ticks) {
    const double x = c.left + (t.at - c.ax.lo) / (c.ax.hi - c.ax.lo) * kPlotW;
    cv.line(x, c.top, x, c.bottom, 1, t.major ? major : minor);
    cv.line(x, c.bottom, x, c.bottom + (t.major ? 5 : 3), 1, black);
    if (t.major) tickLabel(x, c.bottom + 20, t, "middle");
  }
  for (const Tick& t : c.ay.ticks) {
    const double y = c.bottom - (t.at - c.ay.lo) / (c.ay.hi - c.ay.lo) * kPlotH;
    cv.line(c.left, y, c.right, y, 1, t.major ? major : minor);
    cv.line(c.left - (t.major ? 5 : 3), y, c.left, y, 1, black);
    if (t.major) tickLabel(c.left - 8, y + 4, t, "end");
  }
  cv.line(c.left, c.top, c.right, c.top, 1, black);
  cv.line(c.right, c.top, c.right, c.bottom, 1, black);
  cv.line(c.right, c.bottom, c.left, c.bottom, 1, black);
  cv.line(c.left, c.bottom, c.left, c.top, 1, black);
}

}  // namespace

void writePngPlot(const std::string& path, const std::string& title, const std::string& xLabel,
                  const std::string& yLabel, const std::vector<PlotSeries>& series, bool logX,
                  bool logY) {
  const Chart c = makeChart(series, logX, logY);
  const PlotLayout& L = c.layout;
  Canvas cv(int(L.width), int(L.height));
  const auto black = Canvas::rgb("#000000"), white = Canvas::rgb("#ffffff");
  cv.textAnchored(centredX(c, title, kTitleFontSize), c.top - 20, title, kTitleFontSize, black,
                  "middle");
  pngAxes(cv, c);
  cv.textAnchored(centredX(c, xLabel, kFontSize), c.bottom + 45, xLabel, kFontSize, black,
                  "middle");
  cv.text(c.left - 58 + 4, c.top + kPlotH / 2 + textWidth(yLabel, kFontSize) / 2, yLabel, kFontSize,
          black, true);
  for (size_t s = 0; s < series.size(); ++s) {
    const auto colour = Canvas::rgb(L.styles[s].colour);
    for (size_t i = 1; i < c.drawn[s].size(); ++i) {
      const auto [a, b] = std::make_pair(c.drawn[s][i - 1].second, c.drawn[s][i].second);
      cv.line(a.first, a.second, b.first, b.second, 1.5, colour);
    }
    for (const auto& [p, xy] : c.drawn[s]) {
      cv.marker(L.styles[s].marker, xy.first, xy.second, kMarkerR + 0.8, white);
      cv.marker(L.styles[s].marker, xy.first, xy.second, kMarkerR, colour);
    }
  }
  const auto grey = Canvas::rgb("#333333");
  for (const PlotLayout::Label& l : L.labels) cv.text(l.x, l.y, l.text, kLabelFontSize, grey);
  for (size_t s = 0; s < series.size(); ++s) {
    const auto colour = Canvas::rgb(L.styles[s].colour);
    const double y = c.top + 10 + 22 * double(s);
    cv.line(c.legendX, y, c.legendX + 28, y, 1.5, colour);
    cv.marker(L.styles[s].marker, c.legendX + 14, y, kMarkerR, colour);
    cv.text(c.legendX + 36, y + 4, c.legendText(s, series), kFontSize, black);
  }
  const auto red = Canvas::rgb("#a00000");
  for (size_t i = 0; i < c.notes.size(); ++i)
    cv.text(c.left, c.bottom + kMarginBottom + 4 + kNoteLine * double(i), c.notes[i], 11, red);
  writePng(path, cv.img);
}

}  // namespace nestlight::gi
