// Survey plans with perfect knowledge of what each position covers: greedy, then local
// search (the yardstick of `semioctree coverage-bound`).
#include "semioctree/sim/coverage/plan.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace semioctree::sim {

namespace {

std::size_t bits_set(const std::uint64_t* words, std::size_t n) {
  std::size_t count = 0;
  for (std::size_t w = 0; w < n; ++w) count += std::size_t(__builtin_popcountll(words[w]));
  return count;
}

// The sets as 64-bit words: the plan searches take unions and counts of them many times.
struct PackedSets {
  std::size_t words = 0, samples = 0;
  std::vector<std::uint64_t> bits;  // sets × words
  explicit PackedSets(const std::vector<std::vector<bool>>& covered) {
    if (covered.empty()) throw std::invalid_argument("coverage plan: no scan positions");
    samples = covered[0].size();
    words = (samples + 63) / 64;
    bits.assign(covered.size() * words, 0);
    for (std::size_t v = 0; v < covered.size(); ++v) {
      if (covered[v].size() != samples)
        throw std::invalid_argument("coverage plan: the sets differ in size");
      for (std::size_t i = 0; i < samples; ++i)
        if (covered[v][i]) bits[v * words + i / 64] |= std::uint64_t(1) << (i % 64);
    }
  }
  std::size_t sets() const { return bits.size() / std::max<std::size_t>(words, 1); }
  const std::uint64_t* set(std::size_t v) const { return bits.data() + v * words; }
  // The union of the sets of `views`, leaving out views[skip].
  std::vector<std::uint64_t> union_of(const std::vector<std::size_t>& views,
                                      std::size_t skip = SIZE_MAX) const {
    std::vector<std::uint64_t> u(words, 0);
    for (std::size_t k = 0; k < views.size(); ++k)
      if (k != skip)
        for (std::size_t w = 0; w < words; ++w) u[w] |= set(views[k])[w];
    return u;
  }
  // The position adding most to `u` (lowest index on ties) and the size of the union.
  std::pair<std::size_t, std::size_t> best_addition(const std::vector<std::uint64_t>& u) const {
    const std::size_t base = bits_set(u.data(), u.size());
    std::size_t best = 0, best_gain = 0;
    for (std::size_t v = 0; v < sets(); ++v) {
      std::size_t gain = 0;
      for (std::size_t w = 0; w < words; ++w)
        gain += std::size_t(__builtin_popcountll(set(v)[w] & ~u[w]));
      if (gain > best_gain) best = v, best_gain = gain;
    }
    return {best, base + best_gain};
  }
  double percent(std::size_t count) const {
    return samples ? 100.0 * double(count) / double(samples) : 0.0;
  }
};

}  // namespace

CoveragePlan greedy_coverage_plan(const std::vector<std::vector<bool>>& covered, std::size_t first,
                                  std::size_t scans) {
  const PackedSets sets(covered);
  if (first >= sets.sets()) throw std::invalid_argument("coverage plan: no such first position");
  CoveragePlan plan;
  plan.views.push_back(first);
  std::size_t count = bits_set(sets.set(first), sets.words);
  while (plan.views.size() < scans) {
    const auto [v, n] = sets.best_addition(sets.union_of(plan.views));
    if (n == count) break;  // no position adds a sample: a scan more would repeat one
    plan.views.push_back(v);
    count = n;
  }
  plan.percent = sets.percent(count);
  return plan;
}

CoveragePlan improve_coverage_plan(const std::vector<std::vector<bool>>& covered,
                                   CoveragePlan plan) {
  const PackedSets sets(covered);
  if (plan.views.empty()) throw std::invalid_argument("coverage plan: no first position");
  const std::vector<std::uint64_t> all = sets.union_of(plan.views);
  std::size_t count = bits_set(all.data(), all.size());
  for (bool improved = true; improved;) {
    improved = false;
    for (std::size_t k = 1; k < plan.views.size(); ++k) {
      const auto [v, n] = sets.best_addition(sets.union_of(plan.views, k));
      if (n > count) {
        plan.views[k] = v;
        count = n;
        improved = true;
      }
    }
  }
  plan.percent = sets.percent(count);
  return plan;
}

}  // namespace semioctree::sim
