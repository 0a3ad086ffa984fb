// Whether the tests run under the sanitizers (.ci/run sets SEMIOCTREE_SANITIZED): there a
// heavy duplicate of a lighter test skips, naming the test that stands for it (docs/ci.md).
#pragma once

#include <cstdlib>

namespace semioctree::testing {

inline bool sanitized() {
  return std::getenv("SEMIOCTREE_SANITIZED") != nullptr;
}

}  // namespace semioctree::testing
