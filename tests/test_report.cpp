// The survey report (report.h): the page built from a survey.json written here by hand
// (escaping, one row per scan, its figures, bad input), and a real survey's report opened
// in headless Chromium from a copy of its folder (self-contained): a screenshot that is
// not blank, every image loaded, a row per scan, no console message. The browser test
// skips only when no Chromium is installed (CI installs it: .ci/run).
#include <gtest/gtest.h>
#include <png.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/report.h"
#include "support/cli_run.h"

namespace semioctree {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::run_cli;
using testing::scratch;
using testing::slurp;

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// A survey record of `scans` scans with the keys the report reads (docs/outputs.md).
json sample_survey(std::size_t scans) {
  json records = json::array();
  for (std::size_t i = 0; i < scans; ++i)
    records.push_back(
        {{"index", i},
         {"pose", {{"x", 1.0 + double(i)}, {"y", 2.0}, {"z", 1.5}, {"yaw_deg", 0.0}}},
         {"true_pose", {{"x", 1.0 + double(i)}, {"y", 2.0}, {"z", 1.5}, {"yaw_deg", 0.0}}},
         {"pose_error", {{"m", 0.001 * double(i)}, {"deg", 0.01}}},
         {"placed_by", i ? "pose+icp" : "pose"},
         {"points_raw", 1000},
         {"points_kept", 900},
         {"octants", {{"total", 700}, {"by_level", {10, 90, 600}}}},
         {"volume_percent",
          {{"empty", 50.0},
           {"occupied", 5.0},
           {"occluded", 45.0 - double(i)},
           {"door", 0.0},
           {"window", 0.0},
           {"out", double(i)}}},
         {"stop_percent", 2.0 / double(1 + 10 * i)},
         {"coverage_percent", 80.0 + double(i)},
         {"nbv", {{"x", 3.0}, {"y", 1.0}, {"z", 1.5}, {"score", 10.0}}},
         {"candidates", 12},
         {"room", {{"min", {0, 0, 0}}, {"max", {5, 4, 2.8}}}},
         {"seconds",
          {{"preprocess", 0.1},
           {"register", 0.2},
           {"occupancy", 0.3},
           {"openings", 0.1},
           {"occlusion", 0.2},
           {"nbv", 0.5},
           {"write", 0.1},
           {"total", 1.5}}}});
  return {{"format", "semioctree-survey"},
          {"version", 1},
          {"leaf", 0.05},
          {"coarse", 0.8},
          {"stop_threshold_percent", 0.1},
          {"method", 1},
          {"scene", "rooms/<b>&\"odd\".scene.json"},
          {"stopped_because", "stop_percentage"},
          {"complete", true},
          {"scans", records},
          {"openings",
           {{{"kind", "door"},
             {"corners", {{5, 1, 0}, {5, 2, 0}, {5, 2, 2}, {5, 1, 2}}},
             {"width", 1.0},
             {"height", 2.0}}}},
          {"seconds_total", 4.5}};
}

void write_json(const fs::path& path, const json& j) {
  std::ofstream(path) << j.dump(2);
}

TEST(Report, HtmlEscapeReplacesEveryMarkupCharacter) {
  EXPECT_EQ(html_escape("a<b>&\"c\"'d'"), "a&lt;b&gt;&amp;&quot;c&quot;&#39;d&#39;");
  EXPECT_EQ(html_escape("plain 1.5 m"), "plain 1.5 m");
}

TEST(Report, PageHasARowPerScanItsFiguresAndEscapedText) {
  const fs::path dir = scratch() / "hand";
  fs::create_directories(dir / "scan_00");
  write_json(dir / "survey.json", sample_survey(3));
  std::ofstream(dir / "scan_00" / "cloud.ply") << "ply\n";
  write_survey_report(dir.string());
  const std::string page = slurp((dir / "report.html").string());
  ASSERT_FALSE(page.empty());
  // The scene's name is text, not markup.
  EXPECT_NE(page.find("rooms/&lt;b&gt;&amp;&quot;odd&quot;.scene.json"), std::string::npos);
  EXPECT_EQ(page.find("<b>&\"odd\""), std::string::npos);
  // One row per scan, each named after its folder.
  for (const char* row : {"<tr id=\"scan_00\">", "<tr id=\"scan_01\">", "<tr id=\"scan_02\">"})
    EXPECT_EQ(count_of(page, row), 1u) << row;
  EXPECT_EQ(count_of(page, "<tr id=\"scan_"), 3u);
  // The door in its table, every file of the folder linked with the program that opens it.
  EXPECT_NE(page.find("<td>D1</td>"), std::string::npos);
  EXPECT_NE(page.find("href=\"scan_00/cloud.ply\""), std::string::npos);
  EXPECT_NE(page.find("CloudCompare, MeshLab"), std::string::npos);
  // Offline: nothing from the network, no absolute path.
  EXPECT_EQ(page.find("http://"), std::string::npos);
  EXPECT_EQ(page.find("https://"), std::string::npos);
  EXPECT_EQ(page.find(dir.string()), std::string::npos);
  // The figures: SVG documents, each shown by the page.
  for (const std::string& f : survey_report_files()) {
    if (f == "report.html") continue;
    const std::string svg = slurp((dir / f).string());
    EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << f;
    EXPECT_NE(svg.find("<svg"), std::string::npos) << f;
    EXPECT_NE(svg.find("</svg>"), std::string::npos) << f;
    EXPECT_GT(count_of(svg, "<path"), 10u) << f << ": lines and glyphs drawn";
    EXPECT_NE(page.find("<img src=\"" + f + "\""), std::string::npos) << f;
  }
}

TEST(Report, FiguresWithoutTheirDataAreLeftOut) {
  // A survey that stopped before its first NBV: no stop percentage to chart.
  const fs::path dir = scratch() / "no-nbv";
  fs::create_directories(dir);
  json s = sample_survey(1);
  s["scans"][0]["stop_percent"] = nullptr;
  s["scans"][0]["nbv"] = nullptr;
  std::ofstream(dir / "report_progress.svg") << "left by an earlier report";
  write_json(dir / "survey.json", s);
  write_survey_report(dir.string());
  EXPECT_FALSE(fs::exists(dir / "report_progress.svg"));
  EXPECT_TRUE(fs::exists(dir / "report_levels.svg"));
  const std::string page = slurp((dir / "report.html").string());
  EXPECT_NE(page.find("none feasible"), std::string::npos);
}

TEST(Report, BadSurveyRecordIsAFileErrorNamingIt) {
  const fs::path dir = scratch() / "bad";
  fs::create_directories(dir);
  auto message = [&] {
    try {
      write_survey_report(dir.string());
    } catch (const FileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message().find("survey.json: cannot open"), std::string::npos) << message();
  std::ofstream(dir / "survey.json") << "{ not json";
  EXPECT_NE(message().find("survey.json: not JSON"), std::string::npos) << message();
  std::ofstream(dir / "survey.json") << R"({"format": "semioctree-stats"})";
  EXPECT_NE(message().find("not a semioctree-survey record"), std::string::npos) << message();
  json s = sample_survey(1);
  s["openings"][0]["corners"] = json::array({{5, 1}});  // a corner short of z, one corner
  write_json(dir / "survey.json", s);
  EXPECT_NE(message().find("survey.json: a value of unexpected type"), std::string::npos)
      << message();
  s = sample_survey(1);
  s["scans"][0] = "north";  // a scan that is not a record
  write_json(dir / "survey.json", s);
  EXPECT_NE(message().find("survey.json: a value of unexpected type"), std::string::npos)
      << message();
  EXPECT_FALSE(fs::exists(dir / "report.html"));
}

TEST(Report, TheReportCommandRewritesEitherPageAndNamesWhatIsMissing) {
  const fs::path dir = scratch() / "command";
  fs::create_directories(dir);
  auto r = run_cli("report " + dir.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find((dir / "survey.json").string() + ": cannot open it"), std::string::npos)
      << r.all();
  write_json(dir / "survey.json", sample_survey(2));
  r = run_cli("report " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  EXPECT_EQ(count_of(slurp((dir / "report.html").string()), "<tr id=\"scan_"), 2u);
  // A comparison's folder (no survey.json): the comparison's page.
  const fs::path cmp = scratch() / "command-compare";
  fs::create_directories(cmp);
  write_json(cmp / "comparison.json",
             {{"format", "semioctree-comparison"},
              {"version", 1},
              {"table1", {{{"method", "semioctree"}, {"leaf", 0.1}, {"coarse", 0.8}}}},
              {"table2", {{"semioctree", {{"factors", {4.0}}, {"average", 4.0}}}}}});
  r = run_cli("report " + cmp.string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  const std::string page = slurp((cmp / "report.html").string());
  EXPECT_NE(page.find("Table 1"), std::string::npos);
  EXPECT_EQ(count_of(page, "<td>semioctree</td>"), 2u);
}

// --- in a browser ---------------------------------------------------------------------

// The Chromium to test with: $SEMIOCTREE_CHROMIUM, else the first of Debian's and
// Google's names found on PATH; empty when there is none.
std::string find_chromium() {
  if (const char* given = std::getenv("SEMIOCTREE_CHROMIUM")) return given;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string d;
  while (std::getline(dirs, d, ':'))
    for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
      const fs::path candidate = fs::path(d) / name;
      if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
  return "";
}

struct PngPixels {
  unsigned width = 0, height = 0;
  std::vector<std::uint32_t> rgb;  // 0xRRGGBB per pixel
};

PngPixels read_png_pixels(const fs::path& path) {
  const std::string bytes = slurp(path.string());
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  PngPixels img;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return img;
  image.format = PNG_FORMAT_RGB;
  std::vector<png_byte> rgb(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) return img;
  img.width = image.width;
  img.height = image.height;
  for (std::size_t i = 0; i + 2 < rgb.size(); i += 3)
    img.rgb.push_back(std::uint32_t(rgb[i]) << 16 | std::uint32_t(rgb[i + 1]) << 8 | rgb[i + 2]);
  return img;
}

std::string attribute(const std::string& element, const std::string& name) {
  const std::regex re(name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(element, m, re) ? m[1].str() : "";
}

// What Chromium made of a page: the page's own check (written on `load`) and its
// console messages (--enable-logging=stderr writes them as lines with ":CONSOLE").
struct BrowserView {
  std::string check;  // <div id="report-check" ...>, empty when the script did not run
  std::vector<std::string> console;
};

// Headless Chromium as root needs --no-sandbox; it gets a profile of its own.
std::string chromium_command(const std::string& chromium) {
  return "timeout 120 '" + chromium +
         "' --headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run "
         "--user-data-dir='" +
         (scratch() / "chromium-profile").string() + "' ";
}

BrowserView open_in_chromium(const std::string& chromium, const fs::path& page) {
  const fs::path dom = scratch() / "dom.html", log = scratch() / "chromium.log";
  const int status = std::system(
      (chromium_command(chromium) + "--enable-logging=stderr --v=0 --dump-dom 'file://" +
       page.string() + "' >'" + dom.string() + "' 2>'" + log.string() + "'")
          .c_str());
  EXPECT_EQ(status, 0) << slurp(log.string());
  BrowserView view;
  const std::string dumped = slurp(dom.string());
  std::smatch m;
  if (std::regex_search(dumped, m, std::regex("<div id=\"report-check\"[^>]*>")))
    view.check = m[0].str();
  std::istringstream lines(slurp(log.string()));
  for (std::string line; std::getline(lines, line);)
    if (line.find(":CONSOLE") != std::string::npos) view.console.push_back(line);
  return view;
}

// Copies `dir` elsewhere, removes it, and opens the copy's report.html: every image
// loaded, no console message. Returns the check (for the rows) and the copy.
std::pair<std::string, fs::path> check_copied_report(const std::string& chromium,
                                                     const fs::path& dir, std::size_t min_images) {
  const fs::path copy = scratch() / ("copied " + dir.filename().string());
  fs::copy(dir, copy, fs::copy_options::recursive);
  fs::remove_all(dir);
  const std::string page = slurp((copy / "report.html").string());
  // Offline: nothing from the network, no absolute path.
  EXPECT_EQ(page.find("http://"), std::string::npos);
  EXPECT_EQ(page.find("https://"), std::string::npos);
  EXPECT_EQ(page.find(dir.string()), std::string::npos);
  const std::size_t images = count_of(page, "<img ");
  EXPECT_GE(images, min_images);
  const BrowserView view = open_in_chromium(chromium, copy / "report.html");
  EXPECT_FALSE(view.check.empty()) << "the page's check did not run";
  EXPECT_EQ(attribute(view.check, "data-images"), std::to_string(images)) << view.check;
  EXPECT_EQ(attribute(view.check, "data-images-loaded"), std::to_string(images)) << view.check;
  for (const std::string& line : view.console) ADD_FAILURE() << "console message: " << line;
  return {view.check, copy};
}

TEST(ReportInBrowser, TheSurveysPageRendersFromACopiedFolder) {
  const std::string chromium = find_chromium();
  if (chromium.empty())
    GTEST_SKIP() << "no Chromium found (chromium, chromium-browser or google-chrome on PATH, or "
                    "$SEMIOCTREE_CHROMIUM): Debian: apt-get install chromium";
  const fs::path out = scratch() / "box";
  const auto r = run_cli("survey --scene " + std::string(SEMIOCTREE_SOURCE_DIR) +
                         "/sim/scenes/box-room.scene.json --max-scans 2 --out " + out.string() +
                         " --cache " + (scratch() / "cache").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  const json survey = json::parse(slurp((out / "survey.json").string()));
  const std::size_t scans = survey["scans"].size();
  ASSERT_GE(scans, 1u);
  // A slice per scan and the five figures, from a copy of the folder.
  const auto [check, copy] = check_copied_report(chromium, out, scans + 5);
  EXPECT_EQ(attribute(check, "data-scan-rows"), std::to_string(scans)) << check;

  // A screenshot of the top of the page: text, tables and figures, not a blank page.
  const fs::path shot = scratch() / "report.png", log = scratch() / "chromium.log";
  const int shot_status = std::system(
      (chromium_command(chromium) + "--window-size=1280,2400 --screenshot='" + shot.string() +
       "' 'file://" + (copy / "report.html").string() + "' >/dev/null 2>'" + log.string() + "'")
          .c_str());
  ASSERT_EQ(shot_status, 0) << slurp(log.string());
  const PngPixels img = read_png_pixels(shot);
  ASSERT_EQ(img.width, 1280u);
  ASSERT_EQ(img.height, 2400u);
  std::set<std::uint32_t> colours(img.rgb.begin(), img.rgb.end());
  std::size_t not_white = 0;
  for (std::uint32_t c : img.rgb) not_white += c != 0xffffff;
  EXPECT_GT(colours.size(), 200u) << "anti-aliased text, label colours, charts";
  EXPECT_GT(double(not_white) / double(img.rgb.size()), 0.05);
  // The label colours of the slices are on screen (the slices were drawn, not broken icons).
  EXPECT_EQ(colours.count(0x96c8ffu), 1u) << "empty (150, 200, 255) of a slice";
}

TEST(ReportInBrowser, TheComparisonsPageRendersFromACopiedFolder) {
  const std::string chromium = find_chromium();
  if (chromium.empty())
    GTEST_SKIP() << "no Chromium found (chromium, chromium-browser or google-chrome on PATH, or "
                    "$SEMIOCTREE_CHROMIUM): Debian: apt-get install chromium";
  const fs::path out = scratch() / "compare";
  const auto r = run_cli("compare --scene " + std::string(SEMIOCTREE_SOURCE_DIR) +
                         "/sim/scenes/box-room.scene.json --leaves 0.4,0.2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  const std::string page = slurp((out / "report.html").string());
  EXPECT_EQ(count_of(page, "<td>semioctree</td>"), 2u + 1u) << "Table 1's two rows, Table 2's";
  EXPECT_EQ(count_of(page, "<td>homogeneous</td>"), 2u + 1u);
  // Fig 15 and a slice per run.
  check_copied_report(chromium, out, 1 + 4);
}

}  // namespace
}  // namespace semioctree
