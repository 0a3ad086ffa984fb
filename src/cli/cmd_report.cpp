// `semioctree report DIR`: rewrites DIR/report.html (and its figures) from the
// DIR/survey.json a `survey` or `nbv` run left there.
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
      "Rewrite DIR/report.html, the survey's page for any browser, from DIR/survey.json (survey "
      "and nbv write it themselves): summary, settings, one row per scan with its slice, charts, "
      "doors and windows, the missed surface and every file of DIR.");
  cmd->add_option("DIR", *dir, "output directory of a survey or nbv run")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->callback([dir] {
    write_survey_report(*dir);
    std::printf("wrote %s\n", (std::filesystem::path(*dir) / "report.html").string().c_str());
  });
}

}  // namespace semioctree::cli
