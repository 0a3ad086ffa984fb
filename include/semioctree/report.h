// report.html: a survey (or a comparison) on one page for the person who ran it and the one who
// paid for it (docs/outputs.md, "report.html"). Built from survey.json alone, so it can be
// rewritten from any survey's output folder; self-contained: no network, no external
// script or style, its figures beside it in the folder (linked by relative paths).
#pragma once

#include <string>
#include <vector>

namespace semioctree {

// Writes DIR/report.html and its figures (report_progress.svg, report_coverage.svg,
// report_map.svg, report_levels.svg, report_plan.svg) from DIR/survey.json, linking every file
// found in DIR and its subfolders with what it is and which program opens it. Each file is written
// atomically. Throws FileError naming the file: survey.json missing, not JSON or not a survey.
void write_survey_report(const std::string& dir);

// Writes DIR/report.html of `compare` from DIR/comparison.json: Tables 1 and 2, Fig 15
// (fig15_octants.svg) and the slices found in DIR, and every file. Throws FileError as
// above.
void write_comparison_report(const std::string& dir);

// The files write_survey_report writes into DIR.
std::vector<std::string> survey_report_files();

// `text` with &, <, >, " and ' replaced by their HTML entities.
std::string html_escape(const std::string& text);

}  // namespace semioctree
