#include "semioctree/version.h"

namespace semioctree {
const char* version() {
  return SEMIOCTREE_VERSION;
}
}  // namespace semioctree
