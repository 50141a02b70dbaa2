// Speed-against-error charts for `nestlight bench`: a standalone SVG (no script, no external
// font or style sheet) that opens in any browser and diffs as text, and the same chart drawn into
// a PNG for documents that show images only. Reference: W3C, Scalable Vector Graphics (SVG) 1.1
// (Second Edition), 2011.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace nestlight::gi {

struct PlotPoint {
  PlotPoint() = default;
  // Not an aggregate, so that {x, y} needs no label and draws no missing-initialiser warning.
  PlotPoint(double px, double py, std::string text = {}) : x(px), y(py), label(std::move(text)) {}
  double x = 0, y = 0;
  std::string label;  // optional text beside the marker (e.g. "256 spp"): give its unit
};

// Points are joined by a line in the order given, so give them in the order of the swept
// parameter (sample count, VPL count, ...), not sorted by x.
struct PlotSeries {
  std::string name;
  std::vector<PlotPoint> points;
  // Series of one group (a method's variants) share one colour and take one marker each, in the
  // order they come; series without a group each take a colour and a marker of their own.
  std::string group;
};

// Where a chart's parts go, in pixels from its top-left corner: what the SVG and the PNG draw.
struct PlotLayout {
  double width = 0, height = 0;
  struct Style {
    std::string colour;  // "#rrggbb"
    int marker = 0;      // 0 .. plotMarkerCount() - 1
  };
  std::vector<Style> styles;  // per series
  struct Box {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  };
  // The point labels placed: no two boxes overlap, nor a label a marker; a label that finds no
  // free place is left out (the SVG marker's tooltip still carries it) and counted.
  struct Label {
    size_t series = 0, point = 0;
    double x = 0, y = 0;  // start of the text's baseline
    Box box;
    std::string text;
  };
  std::vector<Label> labels;
  size_t labelsLeftOut = 0;
};

int plotMarkerCount();  // distinct marker shapes before they repeat
int plotColourCount();  // distinct colours before they repeat

PlotLayout plotLayout(const std::vector<PlotSeries>& series, bool logX, bool logY);

// Axes with decade ticks where log; markers joined by lines; a legend with every series. Points
// that cannot be drawn (non-finite, or <= 0 on a log axis) are left out and a note in the chart
// says how many and why. All text is XML-escaped.
std::string svgPlot(const std::string& title, const std::string& xLabel, const std::string& yLabel,
                    const std::vector<PlotSeries>& series, bool logX, bool logY);

// svgPlot written to `path` (temporary name, then rename). Throws nestlight::Error naming it.
void writeSvgPlot(const std::string& path, const std::string& title, const std::string& xLabel,
                  const std::string& yLabel, const std::vector<PlotSeries>& series, bool logX,
                  bool logY);

// The same chart as an 8-bit RGB PNG of the SVG's size (lines, markers and text drawn with
// coverage anti-aliasing; text in a built-in bitmap of DejaVu Sans). Throws nestlight::Error.
void writePngPlot(const std::string& path, const std::string& title, const std::string& xLabel,
                  const std::string& yLabel, const std::vector<PlotSeries>& series, bool logX,
                  bool logY);

// `text` with & < > " ' as entities and the control characters XML 1.0 forbids replaced by '?'.
std::string xmlEscape(const std::string& text);

}  // namespace nestlight::gi
