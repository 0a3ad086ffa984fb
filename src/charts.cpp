#include "semioctree/charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "canvas.h"

namespace semioctree {

namespace {

constexpr Rgb kBlack{0, 0, 0}, kGrid{215, 215, 215};

std::string number(double v) {
  char t[32];
  if (std::abs(v) >= 1e6 || (std::abs(v) < 1e-3 && v != 0))
    std::snprintf(t, sizeof t, "%.3g", v);
  else
    std::snprintf(t, sizeof t, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return t;
}

// A point's value: integers in full (octant counts), others to 3 significant digits.
std::string value_text(double v) {
  char t[32];
  if (v == std::floor(v) && std::abs(v) < 1e15)
    std::snprintf(t, sizeof t, "%.0f", v);
  else
    std::snprintf(t, sizeof t, "%.3g", v);
  return t;
}

// A step of 1, 2 or 5 × 10^k giving about `n` intervals over `range`.
double nice_step(double range, int n) {
  const double raw = range / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

}  // namespace

void write_line_chart(const LineChart& chart, const std::string& path) {
  double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
  for (const ChartSeries& s : chart.series) {
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("chart '" + chart.title + "': series '" + s.name + "' has " +
                                  std::to_string(s.x.size()) + " x and " +
                                  std::to_string(s.y.size()) + " y values");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (x_lo > x_hi) throw std::invalid_argument("chart '" + chart.title + "' has no points");
  for (double t : chart.x_ticks) {
    x_lo = std::min(x_lo, t);
    x_hi = std::max(x_hi, t);
  }
  if (chart.reference_y) {
    y_lo = std::min(y_lo, *chart.reference_y);
    y_hi = std::max(y_hi, *chart.reference_y);
  }
  if (x_hi - x_lo < 1e-12) {  // one x: centred
    x_lo -= 0.5;
    x_hi += 0.5;
  }
  // A margin on both sides, so that the end points and their values stay inside.
  const double x_pad = 0.06 * (x_hi - x_lo);
  x_lo -= x_pad;
  x_hi += x_pad;
  // The y range: decades (log), or from 0 (or the lowest value below it) to a tick above
  // the highest value.
  std::vector<double> y_ticks;
  if (chart.log_y) {
    double lowest_positive = 1e300;
    for (const ChartSeries& s : chart.series)
      for (double y : s.y)
        if (y > 0) lowest_positive = std::min(lowest_positive, y);
    if (chart.reference_y && *chart.reference_y > 0)
      lowest_positive = std::min(lowest_positive, *chart.reference_y);
    if (lowest_positive > 1e299) lowest_positive = 1;
    y_lo = std::floor(std::log10(lowest_positive));
    y_hi = std::max(std::ceil(std::log10(std::max(y_hi, lowest_positive))), y_lo + 1);
    for (double e = y_lo; e <= y_hi + 1e-9; e += 1) y_ticks.push_back(e);
  } else {
    y_lo = std::min(0.0, y_lo);
    if (y_hi <= y_lo) y_hi = y_lo + 1;
    const double step = nice_step(y_hi - y_lo, 5);
    y_lo = std::floor(y_lo / step) * step;
    y_hi = std::ceil(y_hi / step - 1e-9) * step;
    for (double v = y_lo; v <= y_hi + step * 1e-6; v += step) y_ticks.push_back(v);
  }

  Canvas img(Canvas::format_of(path), chart.width, chart.height);
  const double left = 84, right = 24, top = 58, bottom = 56;
  const double W = chart.width, H = chart.height;
  auto X = [&](double x) { return left + (W - left - right) * (x - x_lo) / (x_hi - x_lo); };
  auto Y = [&](double y) {
    const double v = chart.log_y ? std::max(std::log10(std::max(y, 1e-300)), y_lo) : y;
    return top + (H - top - bottom) * (1.0 - (v - y_lo) / (y_hi - y_lo));
  };
  auto Yt = [&](double t) { return top + (H - top - bottom) * (1.0 - (t - y_lo) / (y_hi - y_lo)); };

  for (double t : y_ticks) {
    img.line(left - 5, Yt(t), W - right, Yt(t), kGrid);
    const int decade = int(std::lround(t));
    const std::string label = !chart.log_y  ? number(t)
                              : decade >= 4 ? "1e" + std::to_string(decade)
                                            : number(std::pow(10.0, decade));
    img.text(left - 9, Yt(t), label, 12, kBlack, 1.0);
  }
  std::vector<double> ticks = chart.x_ticks;
  std::vector<std::string> labels = chart.x_tick_labels;
  if (ticks.empty())
    for (double x = std::ceil(x_lo); x <= x_hi + 1e-9; x += 1) {
      ticks.push_back(x);
      labels.push_back(number(x));
    }
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    img.line(X(ticks[i]), H - bottom, X(ticks[i]), H - bottom + 5, kBlack);
    if (i < labels.size()) img.text(X(ticks[i]), H - bottom + 16, labels[i], 12, kBlack, 0.5);
  }
  img.line(left, top, left, H - bottom, kBlack);
  img.line(left, H - bottom, W - right, H - bottom, kBlack);
  img.text(left, 18, chart.title, 15, kBlack, 0.0, true);
  img.text((left + W - right) / 2, H - 14, chart.x_label, 12, kBlack, 0.5);
  img.vertical_text(16, (top + H - bottom) / 2, chart.y_label, 12, kBlack);

  if (chart.reference_y) {
    img.set_dashed(true);
    img.line(left, Y(*chart.reference_y), W - right, Y(*chart.reference_y), {200, 0, 0}, 1.2);
    img.set_dashed(false);
    img.text(left + 6, Y(*chart.reference_y) - 9, chart.reference_name, 11, {200, 0, 0});
  }
  // The legend: one row under the title.
  double legend_x = left;
  for (const ChartSeries& s : chart.series) {
    if (s.name.empty()) continue;
    img.line(legend_x, 40, legend_x + 24, 40, s.color, 3);
    img.text(legend_x + 30, 40, s.name, 12, kBlack);
    legend_x += 30 + img.text_width(s.name, 12) + 24;
  }
  for (const ChartSeries& s : chart.series) {
    for (std::size_t i = 0; i + 1 < s.x.size(); ++i)
      img.line(X(s.x[i]), Y(s.y[i]), X(s.x[i + 1]), Y(s.y[i + 1]), s.color, 2.5);
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      img.disc(X(s.x[i]), Y(s.y[i]), 4, s.color, s.color);
      if (s.values == ChartSeries::Values::kAbove)
        img.text(X(s.x[i]) - 8, Y(s.y[i]) - 12, value_text(s.y[i]), 12, s.color, 1.0);
      else if (s.values == ChartSeries::Values::kBelow)
        img.text(X(s.x[i]) + 8, Y(s.y[i]) + 14, value_text(s.y[i]), 12, s.color, 0.0);
    }
  }
  img.write(path);
}

}  // namespace semioctree
