// Running the built `semioctree` tool from a test.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "scratch.h"

namespace semioctree::testing {

inline std::string slurp(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct CliRun {
  int exit_code;
  std::string out, err;
  std::string all() const { return out + err; }
};

// Runs `semioctree ARGS` (the path the build passes as SEMIOCTREE_CLI).
inline CliRun run_cli(const std::string& args) {
  const std::string out = (scratch() / "cli.out").string();
  const std::string err = (scratch() / "cli.err").string();
  const int status =
      std::system((std::string(SEMIOCTREE_CLI) + " " + args + " >" + out + " 2>" + err).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace semioctree::testing
