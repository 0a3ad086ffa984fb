// Benchmark: the whole update of the map by each scan of a lab survey, against OctoMap's
// insertPointCloud of the same scan. The built-in lab is surveyed as `semioctree survey`
// surveys it (the scene's robot and scanner, the CLI's planning defaults, the simulated
// platform) for --scans scans, with 1 thread and with all threads. A scan's update is what
// the survey does between taking the scan and planning the next one: preprocessing (5.4 M
// returns levelled, floor and ceiling cut, decimated to ~400 000 points), registration,
// the directions of its returns, occupancy, doors and windows, occlusion study. OctoMap's
// side replays the same scans: each scan's preprocessed points, placed where the survey
// registered them, inserted from its optical centre into one OcTree at the same leaf size
// (its ray carving, which tells free from unknown space). OctoMap's insertPointCloud has no
// threads (the system's liboctomap is built without OpenMP): its all-threads ratio is null.
// Also printed: each stage's seconds per scan, the survey's wall seconds (Survey::run, the
// NBV included, no files written) and the peak resident memory of the first survey (on all
// threads). JSON on stdout, progress on stderr.
//
//   bench_update [--scans 5]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semioctree/preprocess.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/survey.h"
#include "semioctree/timing.h"
#include "semioctree/update.h"
#include "support/bench_common.h"
#include "support/cli_survey_params.h"

using namespace semioctree;
using json = nlohmann::ordered_json;  // fields in the order written

namespace {

// Keeps each scan as the platform gave it (if `keep_scans`: for OctoMap's replay).
class Recorder : public SurveyObserver {
 public:
  explicit Recorder(bool keep_scans) : keep_scans_(keep_scans) {}
  void scan_taken(std::size_t index, const IncomingScan& scan) override {
    if (!keep_scans_) return;
    if (raw.size() <= index) raw.resize(index + 1);
    raw[index] = scan.points;
  }
  void stage_done(SurveyStage stage, const ScanRecord& r) override {
    if (stage == SurveyStage::kPlanned)
      std::fprintf(stderr, "bench_update: scan %zu: update %.2f s, NBV %.2f s\n", r.index,
                   update_seconds(r), r.seconds.nbv);
  }
  static double update_seconds(const ScanRecord& r) {
    return r.seconds.preprocess + r.seconds.registration + r.seconds.returns + r.seconds.occupancy +
           r.seconds.openings + r.seconds.occlusion;
  }
  std::vector<Cloud::Ptr> raw;

 private:
  bool keep_scans_;
};

struct SurveyRun {
  std::vector<ScanRecord> records;
  std::vector<Cloud::Ptr> raw;
  double seconds = 0;
};

SurveyRun survey_lab(const sim::Scene& scene, int scans, unsigned threads, bool keep_scans) {
  SurveyParams p = testing::cli_survey_params(scene, threads, std::size_t(scans));
  sim_platform::SimulatedPlatform platform(scene, 1, threads);
  p.may_stand = platform.survey_area_rule();
  BestScorePolicy policy;
  Recorder recorder(keep_scans);
  Survey survey(p, &recorder);
  const auto t0 = Clock::now();
  const SurveyOutcome outcome = survey.run(platform, policy);
  SurveyRun run;
  run.seconds = seconds_since(t0);
  if (!outcome.error.empty()) throw std::runtime_error("the lab survey failed: " + outcome.error);
  run.records = survey.records();
  run.raw = std::move(recorder.raw);
  if (keep_scans && run.raw.size() < run.records.size())
    throw std::runtime_error("a scan of the survey was not seen");
  return run;
}

// OctoMap's insertPointCloud of each scan of `run` into one OcTree: the scan preprocessed
// as the survey did (untimed), placed where the survey registered it; seconds per scan.
std::vector<double> octomap_replay(const SurveyRun& run, const SurveyParams& params, double leaf,
                                   std::size_t* nodes) {
  octomap::OcTree tree(leaf);
  std::vector<double> seconds;
  for (const ScanRecord& r : run.records) {
    const Cloud::Ptr seen = within_limits(run.raw[r.index], params.map.limits);
    const PreprocessResult pre = preprocess(*seen, params.preprocess);
    if (pre.output_points != r.points_kept)
      throw std::runtime_error("scan " + std::to_string(r.index) +
                               ": preprocessing again kept another number of points");
    const Eigen::Affine3f to_survey((r.scanner_to_survey * pre.transform.inverse()).cast<float>());
    octomap::Pointcloud cloud;
    cloud.reserve(pre.cloud->size());
    for (const auto& q : *pre.cloud) {
      const Eigen::Vector3f v = to_survey * q.getVector3fMap();
      cloud.push_back(v.x(), v.y(), v.z());
    }
    const Point3 o = r.scanner();
    std::fprintf(stderr, "bench_update: OctoMap insertPointCloud of scan %zu ...\n", r.index);
    const auto t0 = Clock::now();
    tree.insertPointCloud(cloud, octomap::point3d(float(o.x), float(o.y), float(o.z)));
    seconds.push_back(seconds_since(t0));
  }
  *nodes = tree.size();
  return seconds;
}

json stage_seconds(const ScanRecord& r) {
  return {{"preprocess", r.seconds.preprocess},    {"registration", r.seconds.registration},
          {"returns", r.seconds.returns},          {"occupancy", r.seconds.occupancy},
          {"openings", r.seconds.openings},        {"occlusion", r.seconds.occlusion},
          {"update", Recorder::update_seconds(r)}, {"nbv", r.seconds.nbv}};
}

}  // namespace

int main(int argc, char** argv) {
  map_large_allocations();  // as the CLI does: the same peak memory
  int scans = 5;
  CLI::App app{
      "The whole update of the map by each scan of a lab survey (preprocessing, registration, "
      "directions of the returns, occupancy, openings, occlusion), with 1 thread and with all "
      "threads, against OctoMap's insertPointCloud of the same preprocessed scans placed where "
      "the survey registered them (one thread). JSON on stdout, progress on stderr."};
  app.add_option("--scans", scans, "scans of the lab survey (it stops earlier if complete)")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const sim::Scene scene =
        sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
    // What the replay preprocesses with: the survey's.
    const SurveyParams params = testing::cli_survey_params(scene, 0, std::size_t(scans));

    json runs = json::array();
    bench::SideSeconds ours, octo;
    std::vector<double> octo_per_scan;
    std::size_t octo_nodes = 0, scans_compared = 0;
    double survey_peak_mib = 0;
    // All threads first: the 1-thread run keeps its raw scans (86 MB each) for OctoMap's
    // replay, after the survey's peak memory was read.
    std::vector<unsigned> thread_counts = bench::thread_counts();
    std::reverse(thread_counts.begin(), thread_counts.end());
    for (unsigned threads : thread_counts) {
      std::fprintf(stderr, "bench_update: the lab survey on %u thread(s) ...\n", threads);
      const bool replay = threads == 1;
      const SurveyRun run = survey_lab(scene, scans, threads, replay);
      if (survey_peak_mib == 0) survey_peak_mib = peak_resident_mib();
      double update = 0;
      json per_scan = json::array();
      for (const ScanRecord& r : run.records) {
        update += Recorder::update_seconds(r);
        per_scan.push_back(stage_seconds(r));
      }
      if (replay) {
        octo_per_scan = octomap_replay(run, params, params.map.grid.leaf, &octo_nodes);
        scans_compared = run.records.size();
        for (std::size_t i = 0; i < run.records.size(); ++i) {
          per_scan[i]["octomap_insertPointCloud"] = octo_per_scan[i];
          per_scan[i]["ratio"] =
              bench::ratio(octo_per_scan[i], per_scan[i]["update"].get<double>());
          octo.one_thread += octo_per_scan[i];
        }
        ours.one_thread = update;
      } else {
        ours.all_threads = update;
      }
      const ScanRecord& last = run.records.back();
      runs.push_back({{"threads", threads},
                      {"scans", run.records.size()},
                      {"update_seconds", update},
                      {"survey_seconds", run.seconds},
                      {"stop_percent", last.stop_percent() ? json(*last.stop_percent()) : json()},
                      {"per_scan", per_scan}});
    }
    if (bench::all_threads() == 1) ours.all_threads = ours.one_thread;

    json out;
    out["benchmark"] =
        "whole map update by each scan of the lab survey, against OctoMap's insertPointCloud "
        "of the same scans";
    out["scans"] = scans_compared;
    out["threads"] = bench::all_threads();
    out["octomap"] = {{"leaf", params.map.grid.leaf}, {"nodes", octo_nodes}};
    out["runs"] = runs;
    // The first survey's (the raw scans the replay keeps come after).
    out["survey_peak_mib"] = survey_peak_mib;
    out["headlines"] = json::array(
        {bench::headline("scan_update_vs_octomap_insertPointCloud",
                         "OctoMap insertPointCloud of every scan of the survey (preprocessed, "
                         "placed as registered) / the survey's whole update of the map by the "
                         "same scans (preprocessing to occlusion study), seconds summed",
                         octo, ours,
                         "OctoMap's insertPointCloud runs on one thread: its all-threads ratio "
                         "is null; the 1-thread ratio is the headline")});
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_update: error: %s\n", e.what());
    return 1;
  }
}
