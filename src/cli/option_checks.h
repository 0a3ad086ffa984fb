// Checks for numeric options. CLI11's PositiveNumber and Range let "nan" and
// "inf" through (every comparison with NaN is false) and print the limits of a
// double in full; these say what is wanted in words.
#pragma once

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

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

}  // namespace semioctree::cli
