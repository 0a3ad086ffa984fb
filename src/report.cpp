#include "semioctree/report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "canvas.h"
#include "semioctree/charts.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/version.h"

namespace semioctree {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kProgressChart = "report_progress.svg";
constexpr const char* kCoverageChart = "report_coverage.svg";
constexpr const char* kMapChart = "report_map.svg";
constexpr const char* kLevelsChart = "report_levels.svg";
constexpr const char* kPlan = "report_plan.svg";
// The labels of Table 1, in survey.json's volume_percent.
const std::array<Label, 6> kVolumeLabels = {Label::kEmpty, Label::kOccupied, Label::kOccluded,
                                            Label::kDoor,  Label::kWindow,   Label::kOut};

bool has_number(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number();
}

double number_or(const json& j, const char* key, double fallback) {
  return has_number(j, key) ? j[key].get<double>() : fallback;
}

// A number of `j[key]` in printf format, or "—" when absent or null.
std::string num(const json& j, const char* key, const char* format = "%.2f", double scale = 1) {
  if (!has_number(j, key)) return "—";
  char b[64];
  std::snprintf(b, sizeof b, format, scale * j[key].get<double>());
  // "-0.0" (a tiny negative rounded away) reads as a sign that means something.
  if (b[0] == '-' && std::string(b + 1).find_first_not_of("0.") == std::string::npos) return b + 1;
  return b;
}

std::string text_of(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || j[key].is_null()) return "—";
  return j[key].is_string() ? j[key].get<std::string>() : j[key].dump();
}

std::string size_text(std::uintmax_t bytes) {
  char b[32];
  if (bytes >= 1u << 20)
    std::snprintf(b, sizeof b, "%.1f MB", double(bytes) / (1 << 20));
  else if (bytes >= 1u << 10)
    std::snprintf(b, sizeof b, "%.1f kB", double(bytes) / (1 << 10));
  else
    std::snprintf(b, sizeof b, "%ju B", bytes);
  return b;
}

std::string color_css(Rgb c) {
  char b[16];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c.r, c.g, c.b);
  return b;
}

// What a file of the output is and which program opens it, from its name.
struct FileRole {
  std::string what, opens_with;
};

FileRole role_of(const fs::path& relative) {
  const std::string name = relative.filename().string(), ext = relative.extension().string();
  if (name == "survey.json")
    return {"the record of the survey (docs/outputs.md)", "any browser or text editor"};
  if (name == "semioctree.ot")
    return {
        "the map after this scan with every label (SemiOcTree)",
        "semioctree info / export / map-nbv; programs linking semioctree (octovis cannot read it)"};
  if (name == "labels_color.ot")
    return {"the map in its label colours, scans and NBV marked (ColorOcTree)",
            "octovis, octomap-tools"};
  if (name == "occupancy.bt")
    return {"the map as occupancy: occupied, free, unknown",
            "octovis, octomap-tools, octomap_server"};
  if (name == "slice.png") return {"the map cut at scanner height", "any browser or image viewer"};
  if (name == "cloud.ply")
    return {"the merged, registered point cloud so far", "CloudCompare, MeshLab"};
  if (name == "coverage_missed.ply")
    return {"reference surface the survey missed (orange: in view but too sparse, blue: hidden)",
            "CloudCompare (beside cloud.ply)"};
  if (name.rfind("report_", 0) == 0 && ext == ".svg")
    return {"a figure of this report", "any browser"};
  if (name == "report.html") return {"the page of this output", "any browser"};
  if (name == "comparison.md") return {"Tables 1 and 2, Fig 15's counts", "any text editor"};
  if (name == "comparison.json")
    return {"the comparison with the homogeneous grid", "any browser or text editor"};
  if (name.rfind("fig15_octants", 0) == 0)
    return {"Fig 15: octants against resolution", "any browser or image viewer"};
  if (ext == ".png" || ext == ".svg") return {"a figure", "any browser or image viewer"};
  if (ext == ".json") return {"a record (docs/outputs.md)", "any browser or text editor"};
  if (ext == ".ply") return {"a point cloud", "CloudCompare, MeshLab"};
  if (ext == ".ot" || ext == ".bt") return {"an OctoMap file", "octovis, octomap-tools"};
  if (ext == ".md") return {"a text report", "any text editor"};
  return {"", ""};
}

// Every file under `dir` (relative paths, sorted), but the page itself and temporaries.
std::vector<fs::path> output_files(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const fs::path rel = fs::relative(it->path(), dir, ec);
    const std::string name = rel.filename().string();
    if (rel == "report.html" || name.find(".tmp-") != std::string::npos) continue;
    files.push_back(rel);
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string scan_folder(std::size_t index) {
  char b[16];
  std::snprintf(b, sizeof b, "scan_%02zu", index);
  return b;
}

// The charts of the survey's progress; each only when the survey has its data.
void write_charts(const json& survey, const fs::path& dir, std::vector<std::string>& written) {
  const json& scans = survey["scans"];
  // A scan record's `key` against its index, for the scans that have both.
  auto per_scan = [&](const char* key, ChartSeries series) {
    for (const json& s : scans)
      if (has_number(s, key) && has_number(s, "index")) {
        series.x.push_back(s["index"].get<double>());
        series.y.push_back(s[key].get<double>());
      }
    return series;
  };
  const ChartSeries stop = per_scan(
      "stop_percent", {"stop percentage (Eq 5)", {200, 0, 0}, {}, {}, ChartSeries::Values::kBelow});
  if (!stop.x.empty()) {
    LineChart c;
    c.title = "Stop percentage after each scan (log scale)";
    c.x_label = "scan";
    c.y_label = "stop %";
    c.log_y = true;
    c.series = {stop};
    if (has_number(survey, "stop_threshold_percent")) {
      c.reference_y = survey["stop_threshold_percent"].get<double>();
      c.reference_name = "threshold " + num(survey, "stop_threshold_percent", "%g") + " %";
    }
    write_line_chart(c, (dir / kProgressChart).string());
    written.push_back(kProgressChart);
  }
  const ChartSeries covered = per_scan(
      "coverage_percent", {"surface covered", {0, 130, 60}, {}, {}, ChartSeries::Values::kBelow});
  if (!covered.x.empty()) {
    LineChart c;
    c.title = "Surface coverage after each scan";
    c.x_label = "scan";
    c.y_label = "% of the reference surface";
    c.series = {covered};
    write_line_chart(c, (dir / kCoverageChart).string());
    written.push_back(kCoverageChart);
  }
  LineChart map;
  map.title = "The map after each scan: volume % per label";
  map.x_label = "scan";
  map.y_label = "% of the mapped volume";
  for (Label l : {Label::kEmpty, Label::kOccupied, Label::kOccluded, Label::kOut}) {
    ChartSeries s;
    s.name = std::string(label_name(l));
    // The label colours, a shade darker where they would fade on white.
    s.color = l == Label::kEmpty ? Rgb{70, 150, 230}
              : l == Label::kOut ? Rgb{210, 170, 0}
                                 : label_color(l);
    for (const json& r : scans)
      if (r.contains("volume_percent") && has_number(r["volume_percent"], s.name.c_str())) {
        s.x.push_back(number_or(r, "index", 0));
        s.y.push_back(r["volume_percent"][s.name].get<double>());
      }
    if (!s.x.empty()) map.series.push_back(s);
  }
  if (!map.series.empty()) {
    write_line_chart(map, (dir / kMapChart).string());
    written.push_back(kMapChart);
  }
  LineChart levels;
  levels.title = "Octants per level after each scan (log scale)";
  levels.x_label = "level (0: coarse voxels of " + num(survey, "coarse", "%g") +
                   " m … last: leaves of " + num(survey, "leaf", "%g") + " m)";
  levels.y_label = "octants";
  levels.log_y = true;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const json& r = scans[i];
    if (!r.contains("octants") || !r["octants"].contains("by_level")) continue;
    ChartSeries s;
    s.name = "scan " + std::to_string(i);
    // From light to dark blue with the scan number.
    const double t = scans.size() > 1 ? double(i) / double(scans.size() - 1) : 1.0;
    s.color = {std::uint8_t(150 - 150 * t), std::uint8_t(190 - 130 * t),
               std::uint8_t(250 - 90 * t)};
    for (std::size_t l = 0; l < r["octants"]["by_level"].size(); ++l) {
      s.x.push_back(double(l));
      s.y.push_back(r["octants"]["by_level"][l].get<double>());
    }
    if (!s.x.empty()) levels.series.push_back(s);
  }
  if (!levels.series.empty()) {
    write_line_chart(levels, (dir / kLevelsChart).string());
    written.push_back(kLevelsChart);
  }
}

// The floor plan: the room box where the NBV targets were counted, the scans in their
// order, the NBV, and the doors and windows (numbered as in the report's table).
void write_plan(const json& survey, const fs::path& dir, std::vector<std::string>& written) {
  struct P {
    double x, y;
  };
  std::vector<P> scans, all;
  for (const json& s : survey["scans"])
    if (s.contains("pose") && has_number(s["pose"], "x"))
      scans.push_back({s.at("pose").at("x").get<double>(), s.at("pose").at("y").get<double>()});
  if (scans.empty()) return;
  all = scans;
  // The robot's routes (survey.json's `route` of scans and failed scans), when recorded.
  std::vector<std::vector<P>> routes;
  const auto add_route = [&](const json& holder) {
    if (!holder.contains("route") || !holder["route"].is_array() || holder["route"].empty()) return;
    std::vector<P>& route = routes.emplace_back();
    for (const json& p : holder["route"]) {
      route.push_back({p.at(0).get<double>(), p.at(1).get<double>()});
      all.push_back(route.back());
    }
  };
  for (const json& s : survey["scans"]) add_route(s);
  for (const json& f : survey.value("registration_failures", json::array())) add_route(f);
  const json& last = survey["scans"].back();
  std::optional<P> nbv;
  if (last.contains("nbv") && has_number(last["nbv"], "x"))
    nbv = P{last.at("nbv").at("x").get<double>(), last.at("nbv").at("y").get<double>()};
  if (nbv) all.push_back(*nbv);
  std::optional<std::array<P, 2>> room;
  if (last.contains("room") && last["room"].is_object()) {
    const json& r = last["room"];
    room = std::array<P, 2>{P{r.at("min").at(0).get<double>(), r.at("min").at(1).get<double>()},
                            P{r.at("max").at(0).get<double>(), r.at("max").at(1).get<double>()}};
    all.push_back((*room)[0]);
    all.push_back((*room)[1]);
  }
  const json openings = survey.value("openings", json::array());
  for (const json& o : openings)
    for (const json& c : o.at("corners"))
      all.push_back({c.at(0).get<double>(), c.at(1).get<double>()});
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const P& p : all) {
    x0 = std::min(x0, p.x);
    y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x);
    y1 = std::max(y1, p.y);
  }
  x0 -= 0.6;
  y0 -= 0.6;
  x1 += 0.6;
  y1 += 0.6;
  const double plot = 640, scale = plot / std::max(x1 - x0, y1 - y0);
  const double left = 60, top = 40;
  const int w = int(left + (x1 - x0) * scale + 30), h = int(top + (y1 - y0) * scale + 50);
  Canvas img(Canvas::Format::kSvg, std::max(w, 420), h);
  auto X = [&](double x) { return left + (x - x0) * scale; };
  auto Y = [&](double y) { return top + (y1 - y) * scale; };
  const Rgb black{0, 0, 0}, grid{225, 225, 225};
  for (double gx = std::ceil(x0); gx <= x1; gx += 1) {
    img.line(X(gx), Y(y0), X(gx), Y(y1), grid);
    img.text(X(gx), Y(y0) + 14, std::to_string(int(gx)), 11, black, 0.5);
  }
  for (double gy = std::ceil(y0); gy <= y1; gy += 1) {
    img.line(X(x0), Y(gy), X(x1), Y(gy), grid);
    img.text(X(x0) - 6, Y(gy), std::to_string(int(gy)), 11, black, 1.0);
  }
  img.outline_rect(X(x0), Y(y1), X(x1), Y(y0), black);
  img.text(left, 16,
           routes.empty() ? "Plan: scans, next best view, doors and windows (m, survey frame)"
                          : "Plan: scans, the robot's route, next best view, doors and windows "
                            "(m, survey frame)",
           15, black, 0.0, true);
  if (room) {
    img.set_dashed(true);
    img.outline_rect(X((*room)[0].x), Y((*room)[1].y), X((*room)[1].x), Y((*room)[0].y),
                     {120, 120, 120}, 1.2);
    img.set_dashed(false);
    img.text(X((*room)[0].x) + 4, Y((*room)[1].y) + 10, "room (NBV targets)", 11, {120, 120, 120});
  }
  int doors = 0, windows = 0;
  for (const json& o : openings) {
    const bool door = o.value("kind", "") == "door";
    const Rgb c = label_color(door ? Label::kDoor : Label::kWindow);
    const json& a = o.at("corners").at(0);
    const json& b = o.at("corners").at(1);
    img.line(X(a.at(0).get<double>()), Y(a.at(1).get<double>()), X(b.at(0).get<double>()),
             Y(b.at(1).get<double>()), c, 6);
    const std::string name = door ? "D" + std::to_string(++doors) : "W" + std::to_string(++windows);
    img.text((X(a.at(0).get<double>()) + X(b.at(0).get<double>())) / 2 + 6,
             (Y(a.at(1).get<double>()) + Y(b.at(1).get<double>())) / 2 - 10, name, 12, c, 0.0,
             true);
  }
  if (routes.empty())
    for (std::size_t i = 0; i + 1 < scans.size(); ++i)
      img.line(X(scans[i].x), Y(scans[i].y), X(scans[i + 1].x), Y(scans[i + 1].y), black, 1.5);
  for (const std::vector<P>& route : routes)
    for (std::size_t i = 0; i + 1 < route.size(); ++i)
      img.line(X(route[i].x), Y(route[i].y), X(route[i + 1].x), Y(route[i + 1].y), black, 1.5);
  if (nbv) {
    img.set_dashed(true);
    img.line(X(scans.back().x), Y(scans.back().y), X(nbv->x), Y(nbv->y), label_color(Label::kNbv),
             1.5);
    img.set_dashed(false);
    img.disc(X(nbv->x), Y(nbv->y), 7, label_color(Label::kNbv), {255, 255, 255});
    img.text(X(nbv->x) + 10, Y(nbv->y) - 10, "NBV", 12, label_color(Label::kNbv), 0.0, true);
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    img.disc(X(scans[i].x), Y(scans[i].y), 7, black, {255, 255, 255});
    img.text(X(scans[i].x) + 10, Y(scans[i].y) - 10, std::to_string(i), 12, black, 0.0, true);
  }
  img.write((dir / kPlan).string());
  written.push_back(kPlan);
}

const char* kStyle = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;margin:0 auto;
 max-width:1400px;padding:16px 24px;color:#222;background:#fff}
h1{font-size:1.6em;margin:.2em 0}h2{font-size:1.25em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0;font-size:.85em}
th,td{border:1px solid #ccc;padding:3px 6px;vertical-align:top;text-align:left}
th{background:#f0f3f7}td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.cards{display:flex;flex-wrap:wrap;gap:10px;margin:.5em 0}
.card{border:1px solid #ccc;border-radius:6px;padding:8px 14px;min-width:130px;background:#fafbfc}
.card b{display:block;font-size:1.4em}.card span{color:#555;font-size:.85em}
.ok{color:#070}.warn{color:#b00}
.figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(560px,1fr));gap:12px}
.figs img{border:1px solid #ddd;width:100%;height:auto}
img.slice{width:200px;border:1px solid #ddd}img.plan{max-width:100%;width:960px;border:1px solid #ddd}
.wide{overflow-x:auto}
.swatch{display:inline-block;width:.9em;height:.9em;border:1px solid #555;vertical-align:middle;margin-right:4px}
small{color:#555}
)";

// Writes the inline check the browser test reads: how many images loaded and broke, and
// how many rows the scans table has (docs/outputs.md).
const char* kCheckScript = R"(<script>
window.addEventListener('load', function () {
  var images = document.images, loaded = 0;
  for (var i = 0; i < images.length; ++i)
    if (images[i].complete && images[i].naturalWidth > 0) ++loaded;
  var check = document.createElement('div');
  check.id = 'report-check';
  check.hidden = true;
  check.setAttribute('data-images', String(images.length));
  check.setAttribute('data-images-loaded', String(loaded));
  check.setAttribute('data-scan-rows', String(document.querySelectorAll('#scans tbody tr').length));
  document.body.appendChild(check);
});
</script>
)";

// Every file of the output with what it is and which program opens it.
void files_section(std::ostream& h, const fs::path& dir) {
  auto e = [](const std::string& s) { return html_escape(s); };
  h << "<h2>Files</h2>\n<table id=\"files\">\n<thead><tr><th>file</th><th>size</th><th>what it "
       "is</th><th>opens with</th></tr></thead>\n<tbody>\n";
  for (const fs::path& f : output_files(dir)) {
    const FileRole role = role_of(f);
    std::error_code ec;
    const std::uintmax_t bytes = fs::file_size(dir / f, ec);
    h << "<tr><td><a href=\"" << e(f.generic_string()) << "\">" << e(f.generic_string())
      << "</a></td><td class=\"n\">" << (ec ? "—" : size_text(bytes)) << "</td><td>" << e(role.what)
      << "</td><td>" << e(role.opens_with) << "</td></tr>\n";
  }
  h << "</tbody>\n</table>\n"
    << "<p><small>octovis and octomap-tools come with OctoMap (Debian: octovis, octomap-tools); "
       "CloudCompare and MeshLab open point clouds.</small></p>\n";
}

// The page's head: its title and the style.
void page_head(std::ostream& h, const std::string& title) {
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
    << "<title>" << html_escape(title) << "</title>\n<style>" << kStyle
    << "</style>\n</head>\n<body>\n<h1>" << html_escape(title) << "</h1>\n";
}

std::string html_page(const json& survey, const fs::path& dir) {
  const json& scans = survey["scans"];
  std::ostringstream h;
  auto e = [](const std::string& s) { return html_escape(s); };
  const std::string scene = survey.contains("scene") ? text_of(survey, "scene") : "";
  const std::string title = scene.empty() ? "Survey of " + std::to_string(scans.size()) + " scans"
                                          : "Survey of " + fs::path(scene).filename().string();
  page_head(h, title);
  h << "<p><small>Written by semioctree " << e(version())
    << " from <a href=\"survey.json\">survey.json</a>.</small></p>\n";
  if (survey.contains("error"))
    h << "<p class=\"warn\"><b>The survey stopped on an error:</b> " << e(text_of(survey, "error"))
      << "</p>\n";

  // Summary.
  const json* last = scans.empty() ? nullptr : &scans.back();
  double max_error_m = -1, max_error_deg = -1;
  for (const json& s : scans)
    if (s.contains("pose_error") && has_number(s["pose_error"], "m")) {
      max_error_m = std::max(max_error_m, s["pose_error"]["m"].get<double>());
      max_error_deg = std::max(max_error_deg, number_or(s["pose_error"], "deg", 0));
    }
  const bool complete = survey.value("complete", false);
  h << "<h2>Summary</h2>\n<div class=\"cards\">\n";
  auto card = [&](const std::string& value, const std::string& what, const char* cls = "") {
    h << "<div class=\"card\"><b class=\"" << cls << "\">" << e(value) << "</b><span>" << e(what)
      << "</span></div>\n";
  };
  card(std::to_string(scans.size()), "scans");
  const std::string why = text_of(survey, "stopped_because");
  const std::string why_text = why == "stop_percentage"       ? "done"
                               : why == "max_scans"           ? "scan budget spent"
                               : why == "no_candidate"        ? "no feasible position left"
                               : why == "registration_failed" ? "a scan failed to register"
                                                              : why;
  card(why_text,
       (complete ? "stop percentage below the threshold" : "occluded space remains") +
           std::string(" (") + why + ")",
       complete ? "ok" : "warn");
  card(last ? num(*last, "stop_percent", "%.3f") + " %" : "—",
       "stop percentage (threshold " + num(survey, "stop_threshold_percent", "%g") + " %)");
  if (survey.contains("coverage"))
    card(num(survey["coverage"], "percent", "%.2f") + " %", "surface coverage");
  card(num(survey, "seconds_total", "%.1f") + " s", "total time");
  if (has_number(survey, "distance_driven_m"))
    card(num(survey, "distance_driven_m", "%.2f") + " m", "distance driven");
  if (max_error_m >= 0) {
    char b[64];
    std::snprintf(b, sizeof b, "%.1f mm, %.2f°", 1000 * max_error_m, max_error_deg);
    card(b, "largest pose error after registration");
  }
  card(std::to_string(survey.value("openings", json::array()).size()), "doors and windows found");
  h << "</div>\n";

  // Settings.
  h << "<h2>Scene and settings</h2>\n<table>\n";
  auto row = [&](const std::string& k, const std::string& v) {
    h << "<tr><th>" << e(k) << "</th><td>" << e(v) << "</td></tr>\n";
  };
  if (!scene.empty()) row("scene", scene);
  if (survey.contains("inputs") && survey["inputs"].is_array()) {
    std::string files;
    for (const json& f : survey["inputs"])
      files += (files.empty() ? "" : ", ") + (f.is_string() ? f.get<std::string>() : f.dump());
    row("scan files", files);
  }
  if (survey.contains("policy")) row("next scan chosen by", text_of(survey, "policy"));
  row("NBV scoring method", text_of(survey, "method"));
  if (survey.contains("seed")) row("seed (scanner noise, odometry drift)", text_of(survey, "seed"));
  row("octants", "coarse voxels of " + num(survey, "coarse", "%g") + " m, leaves of " +
                     num(survey, "leaf", "%g") + " m" +
                     (survey.value("homogeneous", false) ? " (homogeneous grid)" : ""));
  row("stop threshold", num(survey, "stop_threshold_percent", "%g") + " %");
  if (survey.contains("platform")) {
    const json& p = survey["platform"];
    row("robot", "safety cylinder of radius " + num(p, "robot_radius", "%g") + " m");
    row("scanner", "optical centre at " + num(p, "scanner_height", "%g") + " m; elevation " +
                       num(p, "elevation_min_deg", "%g") + "° to " +
                       num(p, "elevation_max_deg", "%g") + "°; range " + num(p, "min_range", "%g") +
                       " to " + num(p, "max_range", "%g") + " m");
  }
  h << "</table>\n";

  // Figures.
  std::vector<std::string> figures;
  write_charts(survey, dir, figures);
  write_plan(survey, dir, figures);
  if (!figures.empty()) {
    h << "<h2>Figures</h2>\n<div class=\"figs\">\n";
    for (const std::string& f : figures)
      h << "<a href=\"" << e(f) << "\"><img src=\"" << e(f) << "\" alt=\"" << e(f) << "\"></a>\n";
    h << "</div>\n";
  }

  // One row per scan.
  h << "<h2>Scans</h2>\n<p><small>Estimated pose in the survey frame (the first scan's); true pose "
       "in the scene's frame; error: the estimate against the truth. Volumes in % of the mapped "
       "volume; times in seconds. Click a slice for the full image.</small></p>\n"
    << "<div class=\"wide\"><table id=\"scans\">\n<thead><tr><th>scan</th><th>slice at scanner "
       "height</th>"
       "<th>position x, y (m), yaw</th><th>points</th><th>octants</th><th>volume %</th>"
       "<th>stop %</th><th>surface covered %</th><th>next best view</th><th>time (s)</th></tr>"
       "</thead>\n<tbody>\n";
  for (const json& s : scans) {
    const std::size_t index = s.value("index", std::size_t(0));
    const std::string folder = scan_folder(index);
    h << "<tr id=\"" << folder << "\"><td class=\"n\">" << index << "<br><small>"
      << e(text_of(s, "placed_by")) << "</small></td>";
    if (fs::exists(dir / folder / "slice.png"))
      h << "<td><a href=\"" << folder << "/slice.png\"><img class=\"slice\" src=\"" << folder
        << "/slice.png\" alt=\"slice of " << folder << "\"></a></td>";
    else
      h << "<td>—</td>";
    auto pose = [&](const json& p) {
      return num(p, "x") + ", " + num(p, "y") + ", " + num(p, "yaw_deg", "%.1f") + "°";
    };
    h << "<td class=\"n\">estimated " << e(s.contains("pose") ? pose(s["pose"]) : "—");
    if (s.contains("true_pose")) h << "<br>true " << e(pose(s["true_pose"]));
    if (s.contains("pose_error"))
      h << "<br>error " << e(num(s["pose_error"], "m", "%.1f", 1000)) << " mm, "
        << e(num(s["pose_error"], "deg", "%.2f")) << "°";
    h << "</td><td class=\"n\">" << e(num(s, "points_raw", "%.0f")) << " read<br>"
      << e(num(s, "points_kept", "%.0f")) << " kept</td>";
    h << "<td class=\"n\">"
      << e(s.contains("octants") ? num(s["octants"], "total", "%.0f") : std::string("—"))
      << "</td><td class=\"n\">";
    if (s.contains("volume_percent"))
      for (Label l : kVolumeLabels) {
        const std::string name(label_name(l));
        h << "<span class=\"swatch\" style=\"background:" << color_css(label_color(l))
          << "\"></span>" << e(name) << " " << e(num(s["volume_percent"], name.c_str(), "%.2f"))
          << "<br>";
      }
    h << "</td><td class=\"n\">" << e(num(s, "stop_percent", "%.3f")) << "</td><td class=\"n\">"
      << e(num(s, "coverage_percent", "%.2f")) << "</td><td class=\"n\">";
    if (s.contains("nbv") && s["nbv"].is_object())
      h << "(" << e(num(s["nbv"], "x")) << ", " << e(num(s["nbv"], "y")) << ")<br>score "
        << e(num(s["nbv"], "score", "%.1f")) << "<br><small>" << e(num(s, "candidates", "%.0f"))
        << " candidates</small>";
    else
      h << "none feasible";
    h << "</td><td class=\"n\">";
    if (s.contains("seconds")) {
      const json& t = s["seconds"];
      const double map = number_or(t, "returns", 0) + number_or(t, "occupancy", 0) +
                         number_or(t, "openings", 0) + number_or(t, "occlusion", 0);
      char b[32];
      std::snprintf(b, sizeof b, "%.2f", map);
      if (has_number(t, "scan")) h << "scan " << e(num(t, "scan")) << "<br>";
      h << "preprocess " << e(num(t, "preprocess")) << "<br>register " << e(num(t, "register"))
        << "<br>map " << b << "<br>NBV " << e(num(t, "nbv")) << "<br>write " << e(num(t, "write"))
        << "<br><b>total " << e(num(t, "total")) << "</b>";
    }
    h << "</td></tr>\n";
  }
  h << "</tbody>\n</table></div>\n";

  // Doors and windows.
  const json openings = survey.value("openings", json::array());
  h << "<h2>Doors and windows</h2>\n";
  if (openings.empty()) {
    h << "<p>None found.</p>\n";
  } else {
    const std::string last_slice =
        scans.empty() ? ""
                      : scan_folder(scans.back().value("index", std::size_t(0))) + "/slice.png";
    if (!last_slice.empty() && fs::exists(dir / last_slice))
      h << "<figure><a href=\"" << last_slice << "\"><img class=\"plan\" src=\"" << last_slice
        << "\" alt=\"the last scan's slice with the doors and windows\"></a><figcaption><small>The "
           "last scan's slice: doors and windows as bars across their walls.</small>"
           "</figcaption></figure>\n";
    h << "<p><small>Numbered as on the plan and the last slice (D: doors, W: windows, in the order "
         "of survey.json); corners in the survey frame.</small></p>\n"
      << "<table id=\"openings\">\n<thead><tr><th>#</th><th>kind</th><th>width (m)</th>"
         "<th>height (m)</th><th>bottom above the floor (m)</th><th>from (x, y)</th><th>to (x, "
         "y)</th></tr></thead>\n<tbody>\n";
    int doors = 0, windows = 0;
    for (const json& o : openings) {
      const std::string kind = o.value("kind", "");
      const bool door = kind == "door";
      const std::string name =
          door ? "D" + std::to_string(++doors) : "W" + std::to_string(++windows);
      const json c = o.value("corners", json());
      char from[64] = "—", to[64] = "—", bottom[32] = "—";
      if (c.is_array() && c.size() == 4) {
        std::snprintf(from, sizeof from, "%.2f, %.2f", c.at(0).at(0).get<double>(),
                      c.at(0).at(1).get<double>());
        std::snprintf(to, sizeof to, "%.2f, %.2f", c.at(1).at(0).get<double>(),
                      c.at(1).at(1).get<double>());
        std::snprintf(bottom, sizeof bottom, "%.2f",
                      std::min(c.at(0).at(2).get<double>(), c.at(1).at(2).get<double>()));
      }
      h << "<tr><td>" << name << "</td><td><span class=\"swatch\" style=\"background:"
        << color_css(label_color(door ? Label::kDoor : Label::kWindow)) << "\"></span>" << e(kind)
        << "</td><td class=\"n\">" << e(num(o, "width")) << "</td><td class=\"n\">"
        << e(num(o, "height")) << "</td><td class=\"n\">" << bottom << "</td><td class=\"n\">"
        << from << "</td><td class=\"n\">" << to << "</td></tr>\n";
    }
    h << "</tbody>\n</table>\n";
  }

  // The missed surface.
  if (survey.contains("coverage") && survey["coverage"].is_object()) {
    const json& c = survey["coverage"];
    const json missed = c.value("missed", json::object());
    h << "<h2>Surface coverage</h2>\n<p>" << e(num(c, "covered", "%.0f")) << " of "
      << e(num(c, "reference_points", "%.0f"))
      << " reference surface samples (what a dense grid of scan positions could see) have a "
         "measured point within 3 cm: <b>"
      << e(num(c, "percent", "%.2f"))
      << " %</b>. Missed: " << e(num(missed, "in_view_percent", "%.2f"))
      << " % in view of a scan but sampled too sparsely there, "
      << e(num(missed, "hidden_percent", "%.2f"))
      << " % hidden from every scan (<a href=\"coverage_missed.ply\">coverage_missed.ply</a>: "
         "orange in view, blue hidden).</p>\n";
    const json parts = missed.value("parts", json::array());
    if (!parts.empty()) {
      h << "<table id=\"missed\">\n<thead><tr><th>scene element</th><th>missed in view %</th>"
           "<th>missed hidden %</th></tr></thead>\n<tbody>\n";
      for (const json& p : parts)
        h << "<tr><td>" << e(text_of(p, "part")) << "</td><td class=\"n\">"
          << e(num(p, "in_view_percent", "%.2f")) << "</td><td class=\"n\">"
          << e(num(p, "hidden_percent", "%.2f")) << "</td></tr>\n";
      h << "</tbody>\n</table>\n";
    }
  }

  files_section(h, dir);
  h << kCheckScript << "</body>\n</html>\n";
  return h.str();
}

// The comparison's page: Tables 1 and 2, Fig 15 and the slices, from comparison.json.
std::string comparison_page(const json& c, const fs::path& dir) {
  std::ostringstream h;
  auto e = [](const std::string& s) { return html_escape(s); };
  page_head(h, "The semioctree against the homogeneous grid");
  h << "<p><small>Written by semioctree " << e(version())
    << " from <a href=\"comparison.json\">comparison.json</a> (the paper's Table 1, Table 2 and "
       "Fig 15).</small></p>\n";
  h << "<h2>Table 1. Volume % of each class</h2>\n<table id=\"table1\">\n<thead><tr>"
       "<th>method</th><th>leaf (m)</th><th>coarse (m)</th>";
  for (Label l : kVolumeLabels)
    h << "<th><span class=\"swatch\" style=\"background:" << color_css(label_color(l))
      << "\"></span>" << e(std::string(label_name(l))) << "</th>";
  h << "</tr></thead>\n<tbody>\n";
  const json table1 = c.value("table1", json::array());
  for (const json& r : table1) {
    h << "<tr><td>" << e(text_of(r, "method")) << "</td><td class=\"n\">" << num(r, "leaf", "%g")
      << "</td><td class=\"n\">" << num(r, "coarse", "%g") << "</td>";
    for (Label l : kVolumeLabels)
      h << "<td class=\"n\">"
        << (r.contains("volume_percent")
                ? num(r["volume_percent"], std::string(label_name(l)).c_str(), "%.2f")
                : "—")
        << "</td>";
    h << "</tr>\n";
  }
  h << "</tbody>\n</table>\n";
  h << "<h2>Table 2. Increment factor of the octant count per halving of the leaf</h2>\n"
       "<table id=\"table2\">\n<thead><tr><th>method</th><th>factors</th><th>average</th></tr>"
       "</thead>\n<tbody>\n";
  const json table2 = c.value("table2", json::object());
  for (const auto& [method, t] : table2.items()) {
    std::string factors;
    for (const json& f : t.value("factors", json::array()))
      if (f.is_number()) {
        char b[32];
        std::snprintf(b, sizeof b, "%.3f", f.get<double>());
        factors += (factors.empty() ? "" : ", ") + std::string(b);
      }
    h << "<tr><td>" << e(method) << "</td><td class=\"n\">" << factors << "</td><td class=\"n\">"
      << num(t, "average", "%.3f") << "</td></tr>\n";
  }
  h << "</tbody>\n</table>\n<h2>Figures</h2>\n<div class=\"figs\">\n";
  // Fig 15, then the slices of each leaf size, coarsest first, the two methods side by side
  // (named as `compare` writes them: slice_<method>_<leaf>.png).
  std::vector<std::string> figures = {"fig15_octants.svg"};
  std::vector<std::pair<double, std::string>> slices;
  for (const json& r : table1)
    if (has_number(r, "leaf") && r.contains("method") && r["method"].is_string()) {
      char name[96];
      std::snprintf(name, sizeof name, "slice_%s_%g.png", r["method"].get<std::string>().c_str(),
                    r["leaf"].get<double>());
      slices.emplace_back(-r["leaf"].get<double>(), name);
    }
  std::stable_sort(slices.begin(), slices.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& s : slices) figures.push_back(s.second);
  for (const std::string& name : figures)
    if (fs::exists(dir / name))
      h << "<figure><a href=\"" << e(name) << "\"><img src=\"" << e(name) << "\" alt=\"" << e(name)
        << "\"></a><figcaption><small>" << e(name) << "</small></figcaption></figure>\n";
  h << "</div>\n";
  files_section(h, dir);
  h << kCheckScript << "</body>\n</html>\n";
  return h.str();
}

json read_record(const fs::path& source, const std::string& format) {
  std::ifstream in(source);
  if (!in) throw FileError(source.string() + ": cannot open it");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& ex) {
    throw FileError(source.string() + ": not JSON: " + ex.what());
  }
  if (!j.is_object() || j.value("format", "") != format)
    throw FileError(source.string() + ": not a " + format + " record");
  return j;
}

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) switch (c) {
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
        out += "&#39;";
        break;
      default:
        out += c;
    }
  return out;
}

std::vector<std::string> survey_report_files() {
  return {"report.html", kProgressChart, kCoverageChart, kMapChart, kLevelsChart, kPlan};
}

void write_survey_report(const std::string& dir) {
  const fs::path d(dir), source = d / "survey.json";
  const json survey = read_record(source, "semioctree-survey");
  if (!survey.contains("scans") || !survey["scans"].is_array())
    throw FileError(source.string() + ": not a semioctree-survey record (no scans)");
  // Figures of an earlier report that this survey has no data for must not linger.
  for (const std::string& f : survey_report_files()) {
    std::error_code ec;
    fs::remove(d / f, ec);
  }
  try {
    const std::string page = html_page(survey, d);
    write_file_atomically((d / "report.html").string(), [&](std::ostream& out) { out << page; });
  } catch (const json::exception& ex) {
    throw FileError(source.string() + ": a value of unexpected type: " + ex.what());
  }
}

void write_comparison_report(const std::string& dir) {
  const fs::path d(dir), source = d / "comparison.json";
  const json comparison = read_record(source, "semioctree-comparison");
  try {
    const std::string page = comparison_page(comparison, d);
    write_file_atomically((d / "report.html").string(), [&](std::ostream& out) { out << page; });
  } catch (const json::exception& ex) {
    throw FileError(source.string() + ": a value of unexpected type: " + ex.what());
  }
}

}  // namespace semioctree
