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

}  // namespace semioctree::nbv_detail
