// `semioctree report DIR`: rewrites DIR/report.html (and its figures) from the
// DIR/survey.json a `survey` or `nbv` run left there, or the DIR/comparison.json of
// `compare`.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "semioctree/report.h"

namespace semioctree::cli {

void add_report_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "report",
      "Rewrite DIR/report.html, the page for any browser that survey, nbv and compare write "
      "themselves, from DIR/survey.json (summary, settings, one row per scan with its slice, "
      "charts, doors and windows, the missed surface and every file of DIR) or, without one, "
      "from DIR/comparison.json (Tables 1 and 2, Fig 15, the slices).");
  cmd->add_option("DIR", *dir, "output directory of a survey, nbv or compare run")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->callback([dir] {
    const std::filesystem::path d(*dir);
    if (std::filesystem::exists(d / "survey.json") ||
        !std::filesystem::exists(d / "comparison.json"))
      write_survey_report(*dir);  // without either, its error names survey.json
    else
      write_comparison_report(*dir);
    std::printf("wrote %s\n", (std::filesystem::path(*dir) / "report.html").string().c_str());
  });
}

}  // namespace semioctree::cli
