// Checks for numeric options. CLI11's PositiveNumber and Range let "nan" and
// "inf" through (every comparison with NaN is false) and print the limits of a
// double in full; these say what is wanted in words. And the check that no
// output of a command overwrites one of its inputs.
#pragma once

#include <fnmatch.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace semioctree::cli {

namespace detail {
inline bool parse_number(const std::string& s, double& v) {
  const char* begin = s.c_str();
  char* end = nullptr;
  v = std::strtod(begin, &end);
  return end != begin && *end == '\0';
}
inline std::string text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
}  // namespace detail

// A finite number in [lo, hi] (either bound may be infinite: "at least"/"at most").
inline CLI::Validator finite_in(double lo, double hi) {
  const double inf = std::numeric_limits<double>::infinity();
  std::string want = lo == -inf && hi == inf ? "a finite number"
                     : hi == inf             ? "a finite number ≥ " + detail::text(lo)
                     : lo == -inf            ? "a finite number ≤ " + detail::text(hi)
                                  : "a number from " + detail::text(lo) + " to " + detail::text(hi);
  return CLI::Validator(
      [lo, hi, want](std::string& s) -> std::string {
        double v = 0;
        if (!detail::parse_number(s, v) || !std::isfinite(v) || v < lo || v > hi)
          return "must be " + want + ", got " + s;
        return {};
      },
      "", "finite_in");
}

// A finite number > 0 (and at most `hi`).
inline CLI::Validator finite_positive(double hi = std::numeric_limits<double>::infinity()) {
  const std::string want =
      "a positive number" + (std::isinf(hi) ? std::string() : " ≤ " + detail::text(hi));
  return CLI::Validator(
      [hi, want](std::string& s) -> std::string {
        double v = 0;
        if (!detail::parse_number(s, v) || !std::isfinite(v) || v <= 0 || v > hi)
          return "must be " + want + ", got " + s;
        return {};
      },
      "", "finite_positive");
}

// A whole number in [lo, hi], written without sign tricks ("-1" is not 2^64-1).
inline CLI::Validator whole_in(long long lo, long long hi) {
  const std::string want =
      "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, want](std::string& s) -> std::string {
        const char* begin = s.c_str();
        char* end = nullptr;
        errno = 0;
        const long long v = std::strtoll(begin, &end, 10);
        if (end == begin || *end != '\0' || errno != 0 || v < lo || v > hi)
          return "must be " + want + ", got " + s;
        return {};
      },
      "", "whole_in");
}

// 0 (off), or a whole number from lo to hi.
inline CLI::Validator zero_or_whole_in(long long lo, long long hi) {
  const CLI::Validator range = whole_in(lo, hi);
  return CLI::Validator(
      [range, lo, hi](std::string& s) -> std::string {
        if (s == "0") return {};
        std::string copy = s;
        if (range(copy).empty()) return {};
        return "must be 0 (off) or a whole number from " + std::to_string(lo) + " to " +
               std::to_string(hi) + ", got " + s;
      },
      "", "zero_or_whole_in");
}

// A seed: any whole number from 0 (no sign tricks: "-1" is refused).
inline CLI::Validator seed_value() {
  return whole_in(0, std::numeric_limits<long long>::max());
}

// Worker threads: 0 (one per core) up to a bound far above any machine's cores;
// each thread holds per-thread buffers, so a typo like 100000 must not pass.
inline CLI::Validator thread_count() {
  return whole_in(0, 256);
}

// A file or directory a command reads or writes, and the option (or argument) naming it.
struct NamedPath {
  std::string option;  // "--scene", "IN"
  std::string path;
};

// A directory a command writes into, and what it writes there: file names, "*"
// and "[0-9]" as in the shell; a name ending in "/" is a folder the command replaces.
struct OutputDir {
  NamedPath dir;
  std::vector<std::string> written;
};

// `a` and `b` name the same file: std::filesystem::equivalent when both exist,
// else their weakly canonical paths are equal.
inline bool same_path(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ea, eb, ec;
  if (fs::exists(a, ea) && fs::exists(b, eb)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  const fs::path ca = fs::weakly_canonical(a, ea), cb = fs::weakly_canonical(b, eb);
  return !ea && !eb ? ca == cb
                    : fs::absolute(a).lexically_normal() == fs::absolute(b).lexically_normal();
}

// Called before anything is written. Throws std::invalid_argument naming both
// options when an output file is an input or another output, when an output
// directory is an input, or when an input lies in an output directory where
// the command writes or replaces something.
inline void check_outputs_spare_inputs(const std::vector<NamedPath>& inputs,
                                       const std::vector<NamedPath>& files,
                                       const std::vector<OutputDir>& dirs = {}) {
  namespace fs = std::filesystem;
  auto refuse = [](const NamedPath& out, const NamedPath& in, const std::string& how) {
    throw std::invalid_argument(out.option + " " + out.path + " " + how + " " + in.option + " " +
                                in.path + ": it would be overwritten; write elsewhere");
  };
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (files[i].path.empty()) continue;
    for (const NamedPath& in : inputs)
      if (!in.path.empty() && same_path(files[i].path, in.path))
        refuse(files[i], in, "is the input");
    for (std::size_t j = 0; j < i; ++j)
      if (!files[j].path.empty() && same_path(files[i].path, files[j].path))
        refuse(files[i], files[j], "is also");
  }
  for (const OutputDir& d : dirs) {
    if (d.dir.path.empty()) continue;
    std::error_code dir_ec;
    const fs::path dir = fs::weakly_canonical(d.dir.path, dir_ec);
    for (const NamedPath& in : inputs) {
      if (in.path.empty()) continue;
      if (same_path(d.dir.path, in.path)) refuse(d.dir, in, "is the input");
      std::error_code ec;
      const fs::path rel = fs::weakly_canonical(in.path, ec).lexically_relative(dir);
      if (dir_ec || ec || rel.empty() || *rel.begin() == "..") continue;
      const std::string first = rel.begin()->string();
      const bool in_folder = std::next(rel.begin()) != rel.end();
      for (const std::string& w : d.written) {
        const bool folder = !w.empty() && w.back() == '/';
        const std::string pattern = folder ? w.substr(0, w.size() - 1) : w;
        if ((folder || !in_folder) && ::fnmatch(pattern.c_str(), first.c_str(), 0) == 0)
          throw std::invalid_argument(d.dir.option + " " + d.dir.path + ": " + in.option + " " +
                                      in.path + " lies where this command writes (" + w +
                                      "): it would be overwritten; write elsewhere");
      }
    }
  }
}

}  // namespace semioctree::cli
