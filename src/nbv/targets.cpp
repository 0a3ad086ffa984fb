#include "targets.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "label_roles.h"

namespace semioctree::nbv_detail {

unsigned resolve_level(const SemiOcTree& tree, const NbvParams& p) {
  if (p.method == 1) return tree.leaf_level();
  if (p.method == 3) return tree.leaf_level();
  if (p.method != 2) throw std::invalid_argument("NbvParams::method must be 1, 2 or 3");
  if (p.level == NbvParams::kLeafLevel) return tree.leaf_level();
  if (p.level > tree.leaf_level())
    throw std::invalid_argument("NbvParams::level is finer than the tree's leaf level");
  return p.level;
}

std::vector<Target> method1_targets(const SemiOcTree& tree, const std::optional<RoomBox>& room) {
  std::vector<Target> out;
  const unsigned k = tree.leaf_level();
  const double leaf_volume = std::pow(tree.leaf_size(), 3);
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    Target t;
    t.center = o.center;
    t.weight = double(std::uint64_t(1) << (3 * (k - o.level)));
    if (room) {
      const double inside = room->overlap(o.center, o.size);
      if (inside <= 0) return;
      t.weight = std::min(t.weight, inside / leaf_volume);
    }
    out.push_back(t);
  });
  return out;
}

// Occluded octants with a face on free space: the occlusion frontier. The
// neighbour across a face is the octant holding a point a quarter leaf beyond
// the face's centre (a finer neighbour thus stands for the whole face).
std::vector<Target> method3_targets(const SemiOcTree& tree) {
  std::vector<Target> out;
  const double step = 0.25 * tree.leaf_size();
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    Target t;
    t.center = o.center;
    t.half = 0.5 * o.size;
    for (unsigned f = 0; f < 6; ++f) {
      Point3 q = o.center;
      const double d = (f & 1 ? 1.0 : -1.0) * (t.half + step);
      (f < 2 ? q.x : f < 4 ? q.y : q.z) += d;
      const auto nb = tree.find_octant(q);
      if (nb && free_space(nb->label())) t.free_faces |= 1u << f;
    }
    if (t.free_faces == 0) return;
    t.weight = o.size * o.size;
    out.push_back(t);
  });
  return out;
}

std::vector<Target> method2_targets(const SemiOcTree& tree, unsigned level) {
  std::vector<Target> out;
  const unsigned k = tree.leaf_level();
  const std::int64_t c = std::int64_t(1) << (k - level);
  const double r = tree.leaf_size();
  auto cell_of = [&](const octomap::OcTreeKey& key, std::int64_t cell[3]) {
    for (int i = 0; i < 3; ++i) {
      const std::int64_t v = leaf_cell(key.k[i]);
      cell[i] = v >= 0 ? (v / c) * c : -((-v + c - 1) / c) * c;
    }
  };
  auto push = [&](const std::int64_t cell[3]) {
    Target t;
    t.center =
        Point3((double(cell[0]) + 0.5 * double(c)) * r, (double(cell[1]) + 0.5 * double(c)) * r,
               (double(cell[2]) + 0.5 * double(c)) * r);
    std::copy(cell, cell + 3, t.cell);
    out.push_back(t);
  };
  // Octants finer than ℓ come in depth-first order, so the descendants of one
  // level-ℓ cell are consecutive: aggregate them, flush when the cell changes.
  bool open = false, occupied = false;
  std::int64_t cur[3] = {0, 0, 0};
  std::uint64_t occluded_cells = 0;  // leaf cells
  const std::uint64_t cell_volume = std::uint64_t(1) << (3 * (k - level));
  auto flush = [&] {
    if (open && !occupied && 2 * occluded_cells >= cell_volume) push(cur);
    open = false;
  };
  tree.for_each_octant([&](const Octant& o) {
    if (o.level > level) {
      std::int64_t cell[3];
      cell_of(o.key, cell);
      if (!open || !std::equal(cell, cell + 3, cur)) {
        flush();
        open = true;
        occupied = false;
        occluded_cells = 0;
        std::copy(cell, cell + 3, cur);
      }
      occupied |= o.label() == Label::kOccupied;
      if (o.label() == Label::kOccluded) occluded_cells += std::uint64_t(1) << (3 * (k - o.level));
      return;
    }
    flush();
    if (o.label() != Label::kOccluded) return;
    const std::int64_t sub = std::int64_t(1) << (level - o.level);
    std::int64_t base[3];
    for (int i = 0; i < 3; ++i) base[i] = leaf_cell(o.key.k[i]);
    for (std::int64_t z = 0; z < sub; ++z)
      for (std::int64_t y = 0; y < sub; ++y)
        for (std::int64_t x = 0; x < sub; ++x) {
          const std::int64_t cell[3] = {base[0] + x * c, base[1] + y * c, base[2] + z * c};
          push(cell);
        }
  });
  flush();
  return out;
}

std::vector<Target> targets_for(const SemiOcTree& tree, const NbvParams& params) {
  const unsigned level = resolve_level(tree, params);
  if (params.method == 1) return method1_targets(tree, params.room);
  std::vector<Target> t = params.method == 3 ? method3_targets(tree) : method2_targets(tree, level);
  if (params.room)
    t.erase(std::remove_if(t.begin(), t.end(),
                           [&](const Target& x) { return !params.room->contains(x.center); }),
            t.end());
  return t;
}

}  // namespace semioctree::nbv_detail
