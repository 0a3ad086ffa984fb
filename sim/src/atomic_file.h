// Internal: files written under a temporary name in the same directory, then renamed
// over the final name, so an interrupted run never leaves a half-written file there.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <random>
#include <string>

namespace semioctree::sim::detail {

// Calls write(temporary path); when it returns true and the file is there, renames it to
// `path`. Returns false (nothing left behind, `path` untouched) otherwise.
inline bool replace_file_atomically(const std::string& path,
                                    const std::function<bool(const std::string&)>& write) {
  namespace fs = std::filesystem;
  std::random_device rd;
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(rd());
  std::error_code ec;
  if (!write(tmp) || !fs::exists(tmp, ec)) {
    fs::remove(tmp, ec);
    return false;
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return false;
  }
  return true;
}

}  // namespace semioctree::sim::detail
