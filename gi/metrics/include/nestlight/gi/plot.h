// Speed-against-error charts for `nestlight bench`: a standalone SVG (no script, no external
// font or style sheet) that opens in any browser and diffs as text. Reference: W3C, Scalable
// Vector Graphics (SVG) 1.1 (Second Edition), 2011.
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
  std::string label;  // optional text beside the marker (e.g. "256 spp")
};

// Points are joined by a line in the order given, so give them in the order of the swept
// parameter (sample count, VPL count, ...), not sorted by x.
struct PlotSeries {
  std::string name;
  std::vector<PlotPoint> points;
};

// Axes with decade ticks where log; markers (one shape and colour per series) joined by lines;
// a legend with every series. Points that cannot be drawn (non-finite, or <= 0 on a log axis)
// are left out and a note in the chart says how many and why. All text is XML-escaped.
std::string svgPlot(const std::string& title, const std::string& xLabel, const std::string& yLabel,
                    const std::vector<PlotSeries>& series, bool logX, bool logY);

// svgPlot written to `path` (temporary name, then rename). Throws nestlight::Error naming it.
void writeSvgPlot(const std::string& path, const std::string& title, const std::string& xLabel,
                  const std::string& yLabel, const std::vector<PlotSeries>& series, bool logX,
                  bool logY);

// `text` with & < > " ' as entities and the control characters XML 1.0 forbids replaced by '?'.
std::string xmlEscape(const std::string& text);

}  // namespace nestlight::gi
