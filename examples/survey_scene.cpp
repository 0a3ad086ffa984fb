// Example: survey a scene with the simulated robot through the library alone (no CLI):
// the survey stage, the simulated platform, the NBV policy, and an observer that prints
// one line per scan. Exit code 0 when the survey ended without error.
//
//   survey_scene SCENE.scene.json [MAX_SCANS]
#include <cstdio>
#include <cstdlib>

#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/survey.h"

using namespace semioctree;

// Progress: the stage reports to an observer; it prints and writes nothing itself.
class PrintEachScan : public SurveyObserver {
 public:
  void scan_done(const ScanRecord& scan, const SurveyMap&) override {
    const Point3 at = scan.scanner();
    std::printf("scan %zu at (%.2f, %.2f): %zu points kept, %zu feasible candidates", scan.index,
                at.x, at.y, scan.points_kept, scan.nbv.candidates.size());
    if (scan.stop_percent()) std::printf(", stop percentage %.3f %%", *scan.stop_percent());
    std::printf("\n");
  }
};

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE.scene.json [MAX_SCANS]\n", argv[0]);
    return 2;
  }
  try {
    const sim::Scene scene = sim::load_scene(argv[1]);
    SurveyParams params;
    sim_platform::apply_scene(scene, params);  // the scanner's limits, the robot
    params.preprocess.target_points = 400000;
    params.max_scans = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 10;

    sim_platform::SimulatedPlatform robot(scene, /*seed=*/1, /*threads=*/0);
    params.may_stand = robot.survey_area_rule();  // the scene's survey_area, if it has one
    BestScorePolicy next_best_view;
    PrintEachScan printer;
    Survey survey(params, &printer);
    const SurveyOutcome outcome = survey.run(robot, next_best_view);
    std::printf("%zu scans, stopped because %s %s\n", survey.records().size(),
                to_string(outcome.stopped_because), outcome.error.c_str());
    return outcome.stopped_because == StopReason::kRegistrationFailed ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "survey_scene: %s\n", e.what());
    return 1;
  }
}
