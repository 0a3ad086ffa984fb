#include "semioctree/octomap_ext/file_io.h"

#include <octomap/ColorOcTree.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include "semioctree/octomap_ext/node_stream.h"

namespace semioctree {

namespace {

constexpr const char* kOtHeader = "# Octomap OcTree file";
constexpr const char* kBtHeader = "# Octomap OcTree binary file";

struct Header {
  std::string id;
  std::size_t size = 0;
  double res = 0;
};

// Parses "id/size/res/data" lines after the first line; comments allowed.
Header parse_header(std::istream& s, bool binary) {
  Header h;
  bool have_size = false, have_res = false;
  std::string line;
  for (int lines = 0; lines < 64; ++lines) {
    if (!std::getline(s, line)) throw FileFormatError("header ends before the 'data' line");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string token;
    ls >> token;
    if (token == "data") {
      if (h.id.empty() && !binary) throw FileFormatError("header has no 'id' line");
      if (h.id.empty()) h.id = "OcTree";  // legacy .bt files carry no id
      if (!have_size) throw FileFormatError("header has no 'size' line");
      if (!have_res) throw FileFormatError("header has no 'res' line");
      return h;
    }
    std::string value, rest;
    if (!(ls >> value) || (ls >> rest))
      throw FileFormatError("malformed header line '" + line + "'");
    if (token == "id") {
      h.id = value;
    } else if (token == "size") {
      char* end = nullptr;
      errno = 0;
      const unsigned long long v = std::strtoull(value.c_str(), &end, 10);
      if (errno != 0 || *end != '\0' || value[0] == '-')
        throw FileFormatError("header 'size' is not a node count: '" + value + "'");
      h.size = std::size_t(v);
      have_size = true;
    } else if (token == "res") {
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(v > 0) || !std::isfinite(v))
        throw FileFormatError("header 'res' is not a positive resolution: '" + value + "'");
      h.res = v;
      have_res = true;
    } else {
      throw FileFormatError("unknown header line '" + line + "'");
    }
  }
  throw FileFormatError("header is too long (no 'data' line)");
}

std::string slurp(std::istream& s) {
  std::ostringstream ss;
  ss << s.rdbuf();
  return ss.str();
}

TreeFile read_ot(std::istream& s, const Header& h) {
  TreeFile out;
  out.type = h.id;
  out.header_size = h.size;
  if (h.id == "SemiOcTree") {
    auto tree = std::make_unique<SemiOcTree>(h.res);
    if (h.size > 0) tree->readData(s);  // validates itself
    if (tree->size() != h.size)
      throw FileFormatError("header says " + std::to_string(h.size) + " nodes, data holds " +
                            std::to_string(tree->size()));
    out.tree = std::move(tree);
    return out;
  }
  std::size_t node_bytes = 0;
  if (h.id == "OcTree")
    node_bytes = sizeof(float);
  else if (h.id == "ColorOcTree")
    node_bytes = sizeof(float) + 3;
  else
    throw FileFormatError("unsupported tree type '" + h.id +
                          "' (supported: OcTree, ColorOcTree, SemiOcTree)");
  const std::string payload = slurp(s);
  const auto check = [](const char* data, unsigned, bool) -> const char* {
    float v;
    std::memcpy(&v, data, sizeof(v));
    return std::isfinite(v) ? nullptr : "non-finite log-odds";
  };
  const std::size_t counted = validate_node_stream(payload, node_bytes, check);
  if (counted != h.size)
    throw FileFormatError("header says " + std::to_string(h.size) + " nodes, data holds " +
                          std::to_string(counted));
  std::unique_ptr<octomap::AbstractOcTree> tree;
  if (h.id == "OcTree")
    tree = std::make_unique<octomap::OcTree>(h.res);
  else
    tree = std::make_unique<octomap::ColorOcTree>(h.res);
  if (counted > 0) {
    std::istringstream nodes(payload);
    tree->readData(nodes);
  }
  out.tree = std::move(tree);
  return out;
}

TreeFile read_bt(std::istream& s, const Header& h) {
  TreeFile out;
  out.type = "OcTree";
  out.binary = true;
  out.header_size = h.size;
  const std::string payload = slurp(s);
  const std::size_t counted = validate_binary_stream(payload);
  if (counted != h.size)
    throw FileFormatError("header says " + std::to_string(h.size) + " nodes, data holds " +
                          std::to_string(counted));
  auto tree = std::make_unique<octomap::OcTree>(h.res);
  if (counted > 0) {
    std::istringstream nodes(payload);
    tree->readBinaryData(nodes);
  }
  out.tree = std::move(tree);
  return out;
}

}  // namespace

TreeFile read_tree_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))  // an ifstream opens a directory on Linux
    throw FileError(path + ": is a directory, not an OctoMap file");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw FileError(path + ": cannot open: " + std::strerror(errno));
  return read_tree_stream(f, path);
}

TreeFile read_tree_stream(std::istream& in, const std::string& name) {
  try {
    std::string first;
    if (!std::getline(in, first)) throw FileFormatError("file is empty");
    if (!first.empty() && first.back() == '\r') first.pop_back();
    if (first.rfind(kBtHeader, 0) == 0) return read_bt(in, parse_header(in, true));
    if (first.rfind(kOtHeader, 0) == 0) return read_ot(in, parse_header(in, false));
    throw FileFormatError("not an OctoMap file (first line is neither '" + std::string(kOtHeader) +
                          "' nor '" + kBtHeader + "')");
  } catch (const FileFormatError& e) {
    throw FileError(name + ": " + e.what());
  } catch (const std::bad_alloc&) {
    throw FileError(name + ": out of memory while reading (corrupted sizes?)");
  }
}

std::unique_ptr<SemiOcTree> read_semioctree_file(const std::string& path) {
  TreeFile tf = read_tree_file(path);
  auto* semi = dynamic_cast<SemiOcTree*>(tf.tree.get());
  if (!semi)
    throw FileError(path + ": holds a " + tf.type + (tf.binary ? " (.bt)" : "") +
                    ", not a SemiOcTree");
  tf.tree.release();
  return std::unique_ptr<SemiOcTree>(semi);
}

namespace {

// The PID of a temporary's name "NAME.tmp-PID" or "NAME.tmp-PID-N"; 0 if not ours.
pid_t temporary_owner(const std::string& name) {
  const std::size_t at = name.rfind(".tmp-");
  if (at == std::string::npos || at == 0) return 0;
  const std::string rest = name.substr(at + 5);
  const std::size_t dash = rest.find('-');
  const std::string pid = rest.substr(0, dash);
  const std::string n = dash == std::string::npos ? "1" : rest.substr(dash + 1);
  const auto digits = [](const std::string& s) {
    return !s.empty() && s.size() <= 20 &&
           std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  if (!digits(pid) || !digits(n) || pid.size() > 9) return 0;
  return pid_t(std::stol(pid));
}

}  // namespace

std::size_t remove_stale_temporaries(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::size_t removed = 0;
  for (fs::directory_iterator it(dir.empty() ? "." : dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const pid_t pid = temporary_owner(it->path().filename().string());
    std::error_code type;
    if (pid <= 0 || pid == ::getpid() || !it->is_regular_file(type)) continue;
    // kill(pid, 0) fails with ESRCH only when no such process exists.
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    removed += fs::remove(it->path(), rm) && !rm;
  }
  return removed;
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  {
    // Once per directory and process: later temporaries there are this run's own.
    static std::mutex mutex;
    static std::set<std::string> cleaned;
    const std::string dir = std::filesystem::path(path).parent_path().string();
    std::lock_guard<std::mutex> lock(mutex);
    if (cleaned.insert(dir).second) remove_stale_temporaries(dir);
  }
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw FileError(path + ": cannot write: " + std::strerror(errno));
    write(f);
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      throw FileError(path + ": write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw FileError(path + ": cannot rename into place: " + std::strerror(err));
  }
}

void write_tree_file(const octomap::AbstractOcTree& tree, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& s) {
    if (!tree.write(s)) throw FileError(path + ": OctoMap could not write the tree");
  });
}

void write_ot_header(std::ostream& s, const std::string& type, std::size_t size,
                     double resolution) {
  s << kOtHeader
    << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
    << "id " << type << "\nsize " << size << "\nres " << resolution << "\ndata\n";
}

void write_bt_header(std::ostream& s, std::size_t size, double resolution) {
  // OctoMap's writeBinaryConst writes this same header but also prints " done." on stderr.
  const std::streamsize precision = s.precision(15);
  s << kBtHeader << "\n# written by semioctree\nid OcTree\nsize " << size << "\nres " << resolution
    << "\ndata\n";
  s.precision(precision);
}

void write_binary_file(const octomap::OcTree& tree, const std::string& path) {
  // The node stream is OctoMap's own writeBinaryData.
  write_file_atomically(path, [&](std::ostream& s) {
    write_bt_header(s, tree.size(), tree.getResolution());
    tree.writeBinaryData(s);
    if (!s) throw FileError(path + ": could not write the tree");
  });
}

}  // namespace semioctree
