// SVG charts. References: W3C SVG 1.1 (Second Edition), 2011, for the format; Okabe and Ito,
// "Color Universal Design" (2008), for a palette that colour-blind readers can tell apart; tick
// steps of 1, 2 and 5 times a power of ten as in Heckbert, "Nice numbers for graph labels",
// Graphics Gems, 1990.
#include "nestlight/gi/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

// Blue, vermillion, bluish green, reddish purple, orange, sky blue, black, yellow: Okabe-Ito,
// reordered so that the first series get the colours that read best on white.
constexpr std::array<const char*, 8> kColours = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                 "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr int kShapes = 4;  // circle, square, triangle, diamond: a second cue beside colour

constexpr double kMarginLeft = 80, kMarginTop = 50, kPlotW = 520, kPlotH = 380, kMarginBottom = 60;
constexpr double kLegendGap = 30, kCharW = 7.5, kNoteLine = 16;

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

struct Tick {
  double at;          // on the axis' own scale (log10 of the value on a log axis)
  std::string label;  // SVG text content, already escaped
  bool major = true;
};

struct Axis {
  bool log = false;
  double lo = 0, hi = 1;  // on the axis' own scale
  std::vector<Tick> ticks;
  double scale(double v) const { return log ? std::log10(v) : v; }
  double fraction(double v) const { return (scale(v) - lo) / (hi - lo); }
};

std::string decadeLabel(int k) {
  // 10 with a raised exponent; 1 and 10 themselves read better plain.
  if (k == 0) return "1";
  if (k == 1) return "10";
  return "10<tspan dy=\"-6\" font-size=\"9\">" + std::to_string(k) + "</tspan>";
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
    a.ticks.push_back({k, decadeLabel(int(k)), true});
    if (step == 1 && decades <= 6 && k < hi)
      for (int m = 2; m <= 9; ++m) a.ticks.push_back({k + std::log10(double(m)), "", false});
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
    a.ticks.push_back({v, buf, true});
  }
  return a;
}

Axis makeAxis(const std::vector<double>& values, bool log) {
  if (values.empty()) return log ? logAxis(1, 10) : linearAxis(0, 1);
  const auto [mn, mx] = std::minmax_element(values.begin(), values.end());
  return log ? logAxis(*mn, *mx) : linearAxis(*mn, *mx);
}

std::string markerShape(int shape, double x, double y, const std::string& attrs) {
  const double r = 4;
  switch (shape % kShapes) {
    case 0:
      return "<circle " + attrs + " cx=\"" + num(x) + "\" cy=\"" + num(y) + "\" r=\"" + num(r) +
             "\"";
    case 1:
      return "<rect " + attrs + " x=\"" + num(x - r) + "\" y=\"" + num(y - r) + "\" width=\"" +
             num(2 * r) + "\" height=\"" + num(2 * r) + "\"";
    case 2:
      return "<path " + attrs + " d=\"M" + num(x) + "," + num(y - 1.2 * r) + " L" +
             num(x + 1.1 * r) + "," + num(y + 0.8 * r) + " L" + num(x - 1.1 * r) + "," +
             num(y + 0.8 * r) + " Z\"";
    default:
      return "<path " + attrs + " d=\"M" + num(x) + "," + num(y - 1.3 * r) + " L" +
             num(x + 1.3 * r) + "," + num(y) + " L" + num(x) + "," + num(y + 1.3 * r) + " L" +
             num(x - 1.3 * r) + "," + num(y) + " Z\"";
  }
}

std::string plural(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

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
  // Sort points into drawable and left out before sizing the axes, which only drawable ones shape.
  size_t skippedLog = 0, skippedNonFinite = 0;
  std::vector<std::vector<const PlotPoint*>> drawn(series.size());
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
      drawn[s].push_back(&p);
      xs.push_back(p.x);
      ys.push_back(p.y);
    }
  const Axis ax = makeAxis(xs, logX), ay = makeAxis(ys, logY);

  std::vector<std::string> notes;
  if (xs.empty()) notes.push_back("No point to draw.");
  if (skippedLog)
    notes.push_back(plural(skippedLog, "point", "points") +
                    " left out: zero or negative values cannot be drawn on a log axis.");
  if (skippedNonFinite)
    notes.push_back(plural(skippedNonFinite, "point", "points") +
                    " left out: not finite (NaN or Inf).");

  const std::string nothingDrawn = " (nothing drawn)";
  size_t longestName = 0;
  for (size_t s = 0; s < series.size(); ++s)
    longestName =
        std::max(longestName, series[s].name.size() + (drawn[s].empty() ? nothingDrawn.size() : 0));
  const double legendX = kMarginLeft + kPlotW + kLegendGap;
  const double width = std::max(800.0, legendX + 40 + kCharW * double(longestName) + 20);
  const double height =
      std::max(kMarginTop + kPlotH + kMarginBottom + kNoteLine * double(notes.size()) + 10,
               kMarginTop + 22 * double(series.size()) + 20);
  const double left = kMarginLeft, top = kMarginTop, right = left + kPlotW, bottom = top + kPlotH;
  auto px = [&](double fx) { return left + fx * kPlotW; };
  auto py = [&](double fy) { return bottom - fy * kPlotH; };

  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(width) << "\" height=\""
    << num(height) << "\" viewBox=\"0 0 " << num(width) << " " << num(height)
    << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
  o << "<rect x=\"0\" y=\"0\" width=\"" << num(width) << "\" height=\"" << num(height)
    << "\" fill=\"white\"/>\n";
  o << "<text class=\"title\" x=\"" << num(left + kPlotW / 2) << "\" y=\"" << num(top - 20)
    << "\" text-anchor=\"middle\" font-size=\"15\">" << xmlEscape(title) << "</text>\n";

  // Grid and ticks.
  o << "<g class=\"axes\" stroke-width=\"1\">\n";
  for (const Tick& t : ax.ticks) {
    const double x = px((t.at - ax.lo) / (ax.hi - ax.lo));
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(top) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(bottom) << "\" stroke=\"" << (t.major ? "#dddddd" : "#f0f0f0") << "\"/>\n";
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(bottom) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(bottom + (t.major ? 5 : 3)) << "\" stroke=\"black\"/>\n";
    if (t.major)
      o << "<text class=\"tick\" x=\"" << num(x) << "\" y=\"" << num(bottom + 20)
        << "\" text-anchor=\"middle\">" << t.label << "</text>\n";
  }
  for (const Tick& t : ay.ticks) {
    const double y = py((t.at - ay.lo) / (ay.hi - ay.lo));
    o << "<line x1=\"" << num(left) << "\" y1=\"" << num(y) << "\" x2=\"" << num(right)
      << "\" y2=\"" << num(y) << "\" stroke=\"" << (t.major ? "#dddddd" : "#f0f0f0") << "\"/>\n";
    o << "<line x1=\"" << num(left - (t.major ? 5 : 3)) << "\" y1=\"" << num(y) << "\" x2=\""
      << num(left) << "\" y2=\"" << num(y) << "\" stroke=\"black\"/>\n";
    if (t.major)
      o << "<text class=\"tick\" x=\"" << num(left - 8) << "\" y=\"" << num(y + 4)
        << "\" text-anchor=\"end\">" << t.label << "</text>\n";
  }
  o << "<rect x=\"" << num(left) << "\" y=\"" << num(top) << "\" width=\"" << num(kPlotW)
    << "\" height=\"" << num(kPlotH) << "\" fill=\"none\" stroke=\"black\"/>\n";
  o << "</g>\n";
  o << "<text class=\"axis-label\" x=\"" << num(left + kPlotW / 2) << "\" y=\"" << num(bottom + 45)
    << "\" text-anchor=\"middle\">" << xmlEscape(xLabel) << "</text>\n";
  o << "<text class=\"axis-label\" transform=\"translate(" << num(left - 58) << ","
    << num(top + kPlotH / 2) << ") rotate(-90)\" text-anchor=\"middle\">" << xmlEscape(yLabel)
    << "</text>\n";

  // Series: line first so markers sit on top of it.
  for (size_t s = 0; s < series.size(); ++s) {
    const std::string colour = kColours[s % kColours.size()];
    const std::string name = xmlEscape(series[s].name);
    o << "<g class=\"series\" data-name=\"" << name << "\">\n";
    if (drawn[s].size() > 1) {
      o << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.5\" points=\"";
      for (const PlotPoint* p : drawn[s])
        o << num(px(ax.fraction(p->x))) << "," << num(py(ay.fraction(p->y))) << " ";
      o << "\"/>\n";
    }
    for (const PlotPoint* p : drawn[s]) {
      const double x = px(ax.fraction(p->x)), y = py(ay.fraction(p->y));
      char coords[80];
      std::snprintf(coords, sizeof coords, "(%g, %g)", p->x, p->y);
      o << markerShape(
               int(s), x, y,
               "class=\"marker\" fill=\"" + colour + "\" stroke=\"white\" stroke-width=\"0.8\"")
        << "><title>" << name << " " << coords << (p->label.empty() ? "" : " ")
        << (p->label.empty() ? std::string() : xmlEscape(p->label)) << "</title></"
        << (s % kShapes == 0   ? "circle"
            : s % kShapes == 1 ? "rect"
                               : "path")
        << ">\n";
      if (!p->label.empty())
        o << "<text class=\"point-label\" x=\"" << num(x + 6) << "\" y=\"" << num(y - 6)
          << "\" font-size=\"10\" fill=\""
          << "#333333\">" << xmlEscape(p->label) << "</text>\n";
    }
    o << "</g>\n";
  }

  // Legend beside the plot, so it never hides a point.
  o << "<g class=\"legend\">\n";
  for (size_t s = 0; s < series.size(); ++s) {
    const std::string colour = kColours[s % kColours.size()];
    const double y = top + 10 + 22 * double(s);
    o << "<line x1=\"" << num(legendX) << "\" y1=\"" << num(y) << "\" x2=\"" << num(legendX + 28)
      << "\" y2=\"" << num(y) << "\" stroke=\"" << colour << "\" stroke-width=\"1.5\"/>\n";
    o << markerShape(int(s), legendX + 14, y, "class=\"legend-marker\" fill=\"" + colour + "\"")
      << "/>\n";
    o << "<text x=\"" << num(legendX + 36) << "\" y=\"" << num(y + 4) << "\">"
      << xmlEscape(series[s].name) << (drawn[s].empty() ? nothingDrawn : "") << "</text>\n";
  }
  o << "</g>\n";

  for (size_t i = 0; i < notes.size(); ++i)
    o << "<text class=\"note\" x=\"" << num(left) << "\" y=\""
      << num(bottom + kMarginBottom + 4 + kNoteLine * double(i))
      << "\" font-size=\"11\" fill=\"#a00000\">" << xmlEscape(notes[i]) << "</text>\n";
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

}  // namespace nestlight::gi
