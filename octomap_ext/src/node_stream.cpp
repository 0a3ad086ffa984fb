#include "semioctree/octomap_ext/node_stream.h"

#include <algorithm>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

void throw_format_error(const std::string& what) {
  throw FileFormatError(what);
}

std::uint64_t fnv1a64(const char* data, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

std::string read_exactly(std::istream& s, std::uint64_t n) {
  std::string out;
  constexpr std::uint64_t kChunk = 1u << 20;
  while (out.size() < n) {
    const std::size_t want = std::size_t(std::min<std::uint64_t>(kChunk, n - out.size()));
    const std::size_t old = out.size();
    out.resize(old + want);
    s.read(&out[old], std::streamsize(want));
    if (std::size_t(s.gcount()) != want)
      throw FileFormatError("data is truncated: expected " + std::to_string(n) + " bytes, got " +
                            std::to_string(old + std::size_t(s.gcount())));
  }
  return out;
}

namespace {

void validate_binary_recurs(const std::string& p, std::size_t& pos, unsigned depth,
                            std::size_t& count) {
  if (pos + 2 > p.size())
    throw FileFormatError("binary node data is truncated at byte " + std::to_string(pos));
  const unsigned bits =
      static_cast<unsigned char>(p[pos]) | (unsigned(static_cast<unsigned char>(p[pos + 1])) << 8);
  pos += 2;
  unsigned inner = 0;
  for (unsigned i = 0; i < 8; ++i) {
    const unsigned code = (bits >> (2 * i)) & 3u;  // 01 free, 10 occupied, 11 inner, 00 unknown
    if (code != 0) ++count;
    if (code == 3) inner |= 1u << i;
  }
  if (inner != 0 && depth + 1 >= 16)
    throw FileFormatError("binary node at depth 16 has children (byte " + std::to_string(pos - 2) +
                          ")");
  for (unsigned i = 0; i < 8; ++i)
    if (inner & (1u << i)) validate_binary_recurs(p, pos, depth + 1, count);
}

}  // namespace

std::size_t validate_binary_stream(const std::string& payload) {
  std::size_t pos = 0, count = 1;
  if (payload.empty()) return 0;
  validate_binary_recurs(payload, pos, 0, count);
  if (pos != payload.size())
    throw FileFormatError(std::to_string(payload.size() - pos) +
                          " unexpected bytes after the tree");
  return count;
}

}  // namespace semioctree
