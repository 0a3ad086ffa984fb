// Line charts of the figures and the survey report (Fig 15, stop percentage and map
// shares per scan, octants per level), drawn with cairo as SVG or PNG.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/labels.h"

namespace semioctree {

struct ChartSeries {
  std::string name;  // in the legend
  Rgb color{0, 0, 0};
  std::vector<double> x, y;  // the points, joined in this order (same length)
  // Each point's y value written beside it: above-left, or below-right.
  enum class Values { kNone, kAbove, kBelow } values = Values::kNone;
};

struct LineChart {
  std::string title, x_label, y_label;
  bool log_y = false;  // decades from the lowest positive value; 0 or less drawn at the bottom
  // Ticks of the x axis at these x with these labels; empty: one per integer x.
  std::vector<double> x_ticks;
  std::vector<std::string> x_tick_labels;
  // A dashed horizontal line (e.g. the stop threshold) with its name.
  std::optional<double> reference_y;
  std::string reference_name;
  std::vector<ChartSeries> series;
  int width = 620, height = 360;  // pixels (PNG) or points (SVG)
};

// Writes the chart to `path`: SVG when it ends in .svg, else PNG. Atomically; throws
// FileError, or std::invalid_argument for a chart with no points or series of
// mismatched x and y.
void write_line_chart(const LineChart& chart, const std::string& path);

}  // namespace semioctree
