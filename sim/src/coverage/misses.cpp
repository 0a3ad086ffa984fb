// Why a survey missed reference samples: in view of one of its scans, or hidden from all.
#include "semioctree/sim/coverage/misses.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <utility>

#include "coverage/visibility_rule.h"
#include "coverage/wall_culling.h"
#include "parallel.h"

namespace semioctree::sim {

namespace {

// Indices into reference.points of the samples not covered.
std::vector<std::size_t> missed_of(const std::vector<bool>& covered) {
  std::vector<std::size_t> missed;
  for (std::size_t i = 0; i < covered.size(); ++i)
    if (!covered[i]) missed.push_back(i);
  return missed;
}

// One flag per missed sample: sample_visible_from one of the optical centres (the walls
// prepared once).
std::vector<std::uint8_t> in_view_flags(const GroundTruth& truth,
                                        const std::vector<SurfaceSample>& missed_samples,
                                        const std::vector<Eigen::Vector3d>& optical_centres,
                                        unsigned threads) {
  const detail::ScannerLimits lim = detail::scanner_limits(truth.scene().scanner);
  const std::vector<detail::WallSlab> walls = detail::wall_slabs(truth.scene());
  std::vector<std::vector<double>> centre_offsets;
  for (const Eigen::Vector3d& c : optical_centres) {
    centre_offsets.emplace_back(walls.size());
    detail::wall_offsets(walls, c, centre_offsets.back().data());
  }
  std::vector<std::uint8_t> in_view(missed_samples.size(), 0);
  std::atomic<std::size_t> next{0};
  auto work = [&](bool) {
    std::vector<double> target_offsets(walls.size());
    for (std::size_t m; (m = next.fetch_add(1)) < missed_samples.size();) {
      const SurfaceSample& s = missed_samples[m];
      const Eigen::Vector3d target = detail::segment_target(s);
      detail::wall_offsets(walls, target, target_offsets.data());
      for (std::size_t k = 0; k < optical_centres.size() && !in_view[m]; ++k) {
        const Eigen::Vector3d& c = optical_centres[k];
        in_view[m] = detail::within_limits(lim, s, c) &&
                     detail::at_walls(walls, c, centre_offsets[k].data(), target,
                                      target_offsets.data(), false) != detail::AtWalls::opening &&
                     detail::line_of_sight(truth, s, c);
      }
    }
  };
  detail::run_on_threads(
      std::min<unsigned>(detail::thread_count(threads), static_cast<unsigned>(std::max<std::size_t>(
                                                            1, missed_samples.size() / 256))),
      work);
  return in_view;
}

// The counts, per scene element too (most missed first), and the lists of samples.
MissedSamples tally(const GroundTruth& truth, const std::vector<std::size_t>& missed,
                    const std::vector<SurfaceSample>& missed_samples,
                    const std::vector<std::uint8_t>& in_view) {
  MissedSamples out;
  std::vector<MissedPart> parts;
  auto part_of = [&](const PartRef& p) -> MissedPart& {
    for (MissedPart& q : parts)
      if (q.part.kind == p.kind && q.part.index == p.index) return q;
    parts.push_back({p, part_label(truth.scene(), p), 0, 0});
    return parts.back();
  };
  for (std::size_t m = 0; m < missed.size(); ++m) {
    MissedPart& part = part_of(missed_samples[m].part);
    if (in_view[m]) {
      ++out.in_view;
      ++part.in_view;
      out.in_view_samples.push_back(static_cast<std::uint32_t>(missed[m]));
    } else {
      ++out.hidden;
      ++part.hidden;
      out.hidden_samples.push_back(static_cast<std::uint32_t>(missed[m]));
    }
  }
  std::stable_sort(parts.begin(), parts.end(), [](const MissedPart& a, const MissedPart& b) {
    return a.in_view + a.hidden > b.in_view + b.hidden;
  });
  out.parts = std::move(parts);
  return out;
}

}  // namespace

std::string part_label(const Scene& scene, const PartRef& part) {
  std::string label = std::string(to_string(part.kind)) + "[" + std::to_string(part.index) + "]";
  const auto i = static_cast<std::size_t>(part.index);
  std::string name;
  if (part.kind == PartKind::box && i < scene.boxes.size()) name = scene.boxes[i].name;
  if (part.kind == PartKind::cylinder && i < scene.cylinders.size()) name = scene.cylinders[i].name;
  if (part.kind == PartKind::mesh && i < scene.meshes.size()) name = scene.meshes[i].file;
  return name.empty() ? label : label + " (" + name + ")";
}

MissedSamples explain_missed_samples(const GroundTruth& truth, const CoverageReference& reference,
                                     const std::vector<bool>& covered,
                                     const std::vector<Eigen::Vector3d>& optical_centres,
                                     unsigned threads) {
  if (covered.size() != reference.visible.size())
    throw std::invalid_argument("explain_missed_samples: one covered flag per reference sample");
  // Only the missed samples are kept (all of a large scene's run to hundreds of MB).
  const std::vector<std::size_t> missed = missed_of(covered);
  std::vector<std::uint32_t> sample_indices;
  sample_indices.reserve(missed.size());
  for (std::size_t m : missed) sample_indices.push_back(reference.visible[m]);
  std::size_t sample_count = 0;
  const std::vector<SurfaceSample> missed_samples =
      surface_samples_at(truth.scene(), reference.sample_spacing, sample_indices, &sample_count);
  if (sample_count != reference.sample_count)
    throw std::invalid_argument("explain_missed_samples: the reference is of another scene");
  const std::vector<std::uint8_t> in_view =
      in_view_flags(truth, missed_samples, optical_centres, threads);
  return tally(truth, missed, missed_samples, in_view);
}

}  // namespace semioctree::sim
