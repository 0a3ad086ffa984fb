// A progress line that rewrites itself on a terminal and, when the output goes
// to a log file or a pipe, prints one line per update instead of a run of
// carriage returns.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <utility>

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

// "<prefix> <done> of <total> <noun>" from worker threads (NbvParams::progress), at most
// every 2 s: scoring usually takes a few seconds, a large map (a real scan seen through
// its openings) minutes.
class CountProgress {
 public:
  CountProgress(std::FILE* stream, std::string prefix, std::string noun)
      : line_(stream), prefix_(std::move(prefix)), noun_(std::move(noun)) {}

  // Thread-safe.
  void update(std::size_t done, std::size_t total) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::seconds(2)) return;
    last_ = now;
    line_.update(prefix_ + " " + std::to_string(done) + " of " + std::to_string(total) + " " +
                 noun_);
  }
  std::function<void(std::size_t, std::size_t)> callback() {
    return [this](std::size_t done, std::size_t total) { update(done, total); };
  }
  void finish() { line_.finish(); }

 private:
  ProgressLine line_;
  std::string prefix_, noun_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace semioctree::cli
