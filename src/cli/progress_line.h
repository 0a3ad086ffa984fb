// A progress line that rewrites itself on a terminal and, when the output goes
// to a log file or a pipe, prints one line per update instead of a run of
// carriage returns.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <string>

namespace semioctree::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::FILE* stream) : stream_(stream), tty_(isatty(fileno(stream)) == 1) {}
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine() { finish(); }

  void update(const std::string& text) {
    std::fprintf(stream_, tty_ ? "\r%s" : "%s\n", text.c_str());
    std::fflush(stream_);
    open_ = tty_;
  }
  // Ends the rewritten line (nothing to do in a log).
  void finish() {
    if (open_) std::fputc('\n', stream_);
    open_ = false;
  }

 private:
  std::FILE* stream_;
  bool tty_;
  bool open_ = false;
};

}  // namespace semioctree::cli
