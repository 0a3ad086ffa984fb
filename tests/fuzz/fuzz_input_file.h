// For fuzz targets whose reader takes a path (PCL's readers do): the input is
// written to a file in a directory of this process's own, made in
// $SEMIOCTREE_FUZZ_SCRATCH if set (run.sh sets it and removes it afterwards: a
// process ending on a finding leaves its directory behind), else on a RAM disk
// (/dev/shm) where there is one; removed when the process exits normally.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace semioctree::fuzz {

// This process's scratch directory, made on the first call.
inline const std::string& scratch_dir() {
  static const std::string dir = [] {
    namespace fs = std::filesystem;
    std::error_code ec;
    const char* given = std::getenv("SEMIOCTREE_FUZZ_SCRATCH");
    const fs::path base = given && *given                    ? fs::path(given)
                          : fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm")
                                                             : fs::temp_directory_path();
    std::string pattern = (base / "semioctree-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot make " + pattern);
    static std::string made;
    made = pattern;
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(made, ignored);
    });
    return pattern;
  }();
  return dir;
}

// Writes `data` to scratch_dir()/name (replacing it); returns the path.
inline std::string write_input(const std::string& name, const std::uint8_t* data,
                               std::size_t size) {
  const std::string path = scratch_dir() + "/" + name;
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  f.close();
  if (!f) throw std::runtime_error("cannot write " + path);
  return path;
}

}  // namespace semioctree::fuzz
