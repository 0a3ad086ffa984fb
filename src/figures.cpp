#include "semioctree/figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "semioctree/charts.h"
#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

namespace {

using nlohmann::json;

const Label kTableLabels[] = {Label::kEmpty, Label::kOccupied, Label::kOccluded,
                              Label::kDoor,  Label::kWindow,   Label::kOut};

json run_json(const DiscretizationRun& r) {
  json j;
  j["method"] = r.method;
  j["leaf"] = r.leaf;
  j["coarse"] = r.coarse;
  j["coarse_voxels"] = r.stats.coarse_voxels;
  j["octants"] = r.stats.total();
  json by_level = json::array();
  for (unsigned l = 0; l < r.stats.count.size(); ++l) {
    json lv;
    lv["level"] = l;
    lv["size"] = r.coarse / double(1u << l);
    lv["octants"] = r.stats.at_level(l);
    json by_label = json::object();
    for (int k = 0; k < kLabelCount; ++k)
      if (r.stats.count[l][std::size_t(k)])
        by_label[std::string(kLabelNames[std::size_t(k)])] = r.stats.count[l][std::size_t(k)];
    lv["by_label"] = by_label;
    by_level.push_back(lv);
  }
  j["by_level"] = by_level;
  json by_label = json::object(), volume = json::object(), pct = json::object();
  for (int k = 0; k < kLabelCount; ++k) {
    const std::string name(kLabelNames[std::size_t(k)]);
    by_label[name] = r.stats.with_label(Label(k));
    volume[name] = r.stats.volume[std::size_t(k)];
  }
  for (Label l : kTableLabels) pct[std::string(label_name(l))] = volume_percent(r.stats, l);
  j["by_label"] = by_label;
  j["volume_m3"] = volume;
  j["volume_percent"] = pct;
  j["memory_bytes"] = r.memory_bytes;
  j["seconds"] = r.seconds;
  return j;
}

void write_text(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& s) { s << text; });
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof(b), f, v);
  return b;
}

// Fig 15: octants against resolution, both methods, log-scale counts; the curves rise to
// the right, so the homogeneous grid's (upper) counts go above-left of its points and the
// semioctree's below-right, clear of the lines.
void write_fig15(const std::map<std::string, std::vector<DiscretizationRun>>& by_method,
                 const std::string& path) {
  LineChart chart;
  chart.title = "Fig 15: octants needed for a resolution (log scale)";
  chart.x_label = "leaf size (resolution)";
  chart.y_label = "octants";
  chart.log_y = true;
  chart.width = 980;
  chart.height = 600;
  std::vector<double> leaves;
  for (const auto& [m, runs] : by_method)
    for (const auto& r : runs)
      if (std::find(leaves.begin(), leaves.end(), r.leaf) == leaves.end()) leaves.push_back(r.leaf);
  std::sort(leaves.rbegin(), leaves.rend());
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    chart.x_ticks.push_back(double(i));
    chart.x_tick_labels.push_back(fmt("%g m", leaves[i]));
  }
  const std::map<std::string, Rgb> colors = {{"homogeneous", {200, 60, 0}},
                                             {"semioctree", {0, 80, 200}}};
  for (const auto& [m, runs] : by_method) {
    ChartSeries s;
    s.name = m;
    s.color = colors.count(m) ? colors.at(m) : Rgb{0, 0, 0};
    s.values = m == "semioctree" ? ChartSeries::Values::kBelow : ChartSeries::Values::kAbove;
    for (const auto& r : runs) {
      s.x.push_back(double(std::find(leaves.begin(), leaves.end(), r.leaf) - leaves.begin()));
      s.y.push_back(double(r.stats.total()));
    }
    chart.series.push_back(s);
  }
  write_line_chart(chart, path);
}

}  // namespace

double volume_percent(const OctantStatistics& s, Label l) {
  double total = 0;
  for (Label t : kTableLabels) total += s.volume[std::size_t(t)];
  return total > 0 ? 100.0 * s.volume[std::size_t(l)] / total : 0.0;
}

DiscretizationRun describe_run(const SemiOcTree& tree, double seconds) {
  DiscretizationRun run;
  run.method = tree.leaf_level() == 0 ? "homogeneous" : "semioctree";
  run.leaf = tree.leaf_size();
  run.coarse = tree.coarse_size();
  run.stats = tree.statistics();
  run.memory_bytes = tree.memory_bytes();
  run.seconds = seconds;
  return run;
}

void write_run_json(const DiscretizationRun& run, const std::string& path) {
  json j = run_json(run);
  j["format"] = "semioctree-stats";
  j["version"] = 1;
  write_text(path, j.dump(2) + "\n");
}

void write_openings_json(const std::vector<DetectedOpening>& openings, const std::string& path) {
  json list = json::array();
  for (const auto& o : openings) {
    json corners = json::array();
    for (const auto& c : o.corners) corners.push_back({c.x(), c.y(), c.z()});
    list.push_back({{"kind", to_string(o.kind)},
                    {"corners", corners},
                    {"width", o.width},
                    {"height", o.height},
                    {"sill", o.sill},
                    {"los_fraction", o.los_fraction}});
  }
  json j = {{"format", "semioctree-openings"}, {"version", 1}, {"openings", list}};
  write_text(path, j.dump(2) + "\n");
}

std::vector<double> increment_factors(const std::vector<DiscretizationRun>& runs) {
  std::vector<double> f;
  for (std::size_t i = 0; i + 1 < runs.size(); ++i)
    f.push_back(double(runs[i + 1].stats.total()) /
                double(std::max<std::uint64_t>(1, runs[i].stats.total())));
  return f;
}

void write_comparison(const std::vector<DiscretizationRun>& runs, const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::map<std::string, std::vector<DiscretizationRun>> by_method;
  for (const auto& r : runs) by_method[r.method].push_back(r);
  for (auto& [m, v] : by_method)
    std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.leaf > b.leaf; });

  json j;
  j["format"] = "semioctree-comparison";
  j["version"] = 1;
  json table1 = json::array(), table2 = json::object(), fig15 = json::object();
  std::ostringstream md;
  md << "# Semioctree against the homogeneous grid\n\n"
     << "## Table 1. Volume % of each class\n\n"
     << "| method | octant size | empty | occupied | occluded | door | window | out |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const auto& [m, v] : by_method)
    for (const auto& r : v) {
      json row;
      row["method"] = m;
      row["leaf"] = r.leaf;
      row["coarse"] = r.coarse;
      const std::string size = m == "homogeneous"
                                   ? fmt("%gm", r.leaf)
                                   : fmt("%gm", r.coarse) + " to " + fmt("%gm", r.leaf);
      md << "| " << m << " | " << size;
      for (Label l : kTableLabels) {
        row["volume_percent"][std::string(label_name(l))] = volume_percent(r.stats, l);
        md << " | " << fmt("%.2f", volume_percent(r.stats, l));
      }
      md << " |\n";
      table1.push_back(row);
    }
  md << "\n## Table 2. Increment factor per halving of the resolution\n\n| method |";
  const auto& any = by_method.begin()->second;
  for (std::size_t i = 0; i + 1 < any.size(); ++i)
    md << " " << fmt("%g", any[i].leaf) << " → " << fmt("%g m", any[i + 1].leaf) << " |";
  md << " average |\n|---|";
  for (std::size_t i = 0; i + 1 < any.size(); ++i) md << "---|";
  md << "---|\n";
  for (const auto& [m, v] : by_method) {
    const auto f = increment_factors(v);
    double avg = 0;
    for (double x : f) avg += x;
    avg = f.empty() ? 0 : avg / double(f.size());
    table2[m]["factors"] = f;
    table2[m]["average"] = avg;
    md << "| " << m << " |";
    for (double x : f) md << " " << fmt("%.4f", x) << " |";
    md << " " << fmt("%.4f", avg) << " |\n";
  }
  md << "\n## Fig 15. Octants needed for a resolution\n\n| leaf size |";
  for (const auto& [m, v] : by_method) md << " " << m << " |";
  md << " ratio |\n|---|";
  for (std::size_t i = 0; i <= by_method.size(); ++i) md << "---|";
  md << "\n";
  for (std::size_t i = 0; i < any.size(); ++i) {
    md << "| " << fmt("%g m", any[i].leaf) << " |";
    std::vector<double> counts;
    for (const auto& [m, v] : by_method) {
      const double c = i < v.size() ? double(v[i].stats.total()) : 0;
      counts.push_back(c);
      md << " " << std::uint64_t(c) << " |";
      fig15[m].push_back({{"leaf", i < v.size() ? v[i].leaf : 0},
                          {"octants", std::uint64_t(c)},
                          {"memory_bytes", i < v.size() ? v[i].memory_bytes : 0},
                          {"seconds", i < v.size() ? v[i].seconds : 0}});
    }
    const double ratio =
        by_method.count("homogeneous") && by_method.count("semioctree") &&
                i < by_method["semioctree"].size() && i < by_method["homogeneous"].size()
            ? double(by_method["homogeneous"][i].stats.total()) /
                  double(std::max<std::uint64_t>(1, by_method["semioctree"][i].stats.total()))
            : 0.0;
    md << " " << fmt("%.2f", ratio) << " |\n";
  }
  j["table1"] = table1;
  j["table2"] = table2;
  j["fig15"] = fig15;
  json all = json::array();
  for (const auto& r : runs) all.push_back(run_json(r));
  j["runs"] = all;
  write_text((std::filesystem::path(dir) / "comparison.json").string(), j.dump(2) + "\n");
  write_text((std::filesystem::path(dir) / "comparison.md").string(), md.str());
  // SVG for browsers and the report, PNG for image viewers and documents.
  for (const char* name : {"fig15_octants.svg", "fig15_octants.png"})
    write_fig15(by_method, (std::filesystem::path(dir) / name).string());
}

}  // namespace semioctree
