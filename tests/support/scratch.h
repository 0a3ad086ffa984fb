// Scratch directories of the test process's own (ctest runs test cases as parallel
// processes): all of them lie under one directory that is removed when the process ends.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>
#include <system_error>

namespace semioctree::testing {

// Created on first use, removed when the process ends.
inline const std::filesystem::path& scratch() {
  static const struct Dir {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("semioctree_test_" + std::to_string(::getpid()));
    Dir() { std::filesystem::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } dir;
  return dir.path;
}

// A fresh empty directory under scratch() (so removed with it).
inline std::filesystem::path temp_dir(const std::string& name) {
  std::random_device rd;
  const auto dir = scratch() / (name + "-" + std::to_string(rd()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace semioctree::testing
