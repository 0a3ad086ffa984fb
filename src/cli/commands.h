// Subcommands of the `semioctree` tool. Each add_*_command registers one
// subcommand on the app; its callback throws std::exception with a message
// that names the offending file or option, and main() turns that into
// "semioctree: error: ..." and exit code 1.
#pragma once

#include <CLI/CLI.hpp>

namespace semioctree::cli {

void add_info_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_discretize_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_classify_command(CLI::App& app);
void add_nbv_command(CLI::App& app);
void add_map_nbv_command(CLI::App& app);
void add_report_command(CLI::App& app);
#ifdef SEMIOCTREE_HAVE_SIM
void add_scan_command(CLI::App& app);
void add_scene_info_command(CLI::App& app);
void add_make_scene_command(CLI::App& app);
void add_survey_command(CLI::App& app);
void add_coverage_bound_command(CLI::App& app);
#endif

}  // namespace semioctree::cli
