#include "plane_grid.h"

#include <algorithm>
#include <limits>

namespace semioctree::nbv_detail {

std::pair<CoarseIndex, CoarseIndex> coarse_columns(const SemiOcTree& tree) {
  CoarseIndex lo{std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), 0};
  CoarseIndex hi{std::numeric_limits<int>::min(), std::numeric_limits<int>::min(), 0};
  tree.for_each_coarse([&](const CoarseIndex& c, SemiOcTreeNode*) {
    lo.x = std::min(lo.x, c.x), lo.y = std::min(lo.y, c.y);
    hi.x = std::max(hi.x, c.x), hi.y = std::max(hi.y, c.y);
  });
  return {lo, hi};
}

Plane plane_over(const SemiOcTree& tree) {
  const std::int64_t span = std::int64_t(1) << tree.leaf_level();
  const std::pair<CoarseIndex, CoarseIndex> columns = coarse_columns(tree);
  const CoarseIndex &lo = columns.first, &hi = columns.second;
  Plane p;
  p.lo = lo, p.hi = hi;
  p.x0 = std::int64_t(lo.x) * span - 1, p.y0 = std::int64_t(lo.y) * span - 1;
  p.nx = static_cast<int>((std::int64_t(hi.x) - lo.x + 1) * span + 2);
  p.ny = static_cast<int>((std::int64_t(hi.y) - lo.y + 1) * span + 2);
  return p;
}

}  // namespace semioctree::nbv_detail
