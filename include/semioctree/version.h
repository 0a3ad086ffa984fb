// Version of the semioctree library.
#pragma once

namespace semioctree {
const char* version();
}  // namespace semioctree
