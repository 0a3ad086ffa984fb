// The four point-file fuzz targets differ only in the file's extension: each
// writes its input as `input<ext>` and reads it as the CLI does (read_scans),
// then moves the scans into the survey frame (to_survey_frame). A ScanReadError
// is the reader's clear answer to a bad file; anything else escaping (another
// exception, a crash, a sanitizer report) is a finding.
#pragma once

#include "fuzz_input_file.h"
#include "semioctree/scan_io.h"

namespace semioctree::fuzz {

inline int read_point_file(const char* extension, const std::uint8_t* data, std::size_t size) {
  const std::string path = write_input(std::string("input") + extension, data, size);
  try {
    for (const Scan& scan : read_scans(path)) {
      if (!scan.points || scan.points->empty()) std::abort();  // contract: never empty
      to_survey_frame(scan);
    }
  } catch (const ScanReadError&) {
  }
  return 0;
}

}  // namespace semioctree::fuzz
