#pragma once

#include <stdexcept>

namespace semioctree {

class FileFormatError;
[[noreturn]] void throw_format_error(const std::string& what);

namespace detail {

template <class Check>
void validate_node_recurs(const std::string& p, std::size_t& pos, unsigned depth,
                          std::size_t node_bytes, const Check& check, std::size_t& count) {
  if (pos + node_bytes + 1 > p.size())
    throw_format_error("node data is truncated at byte " + std::to_string(pos));
  const char* data = p.data() + pos;
  const auto mask = static_cast<unsigned char>(p[pos + node_bytes]);
  pos += node_bytes + 1;
  ++count;
  if (mask != 0 && depth >= 16)
    throw_format_error("node at depth 16 has children (byte " + std::to_string(pos - 1) + ")");
  if (const char* err = check(data, depth, mask != 0))
    throw_format_error(std::string(err) + " at byte " + std::to_string(pos - node_bytes - 1));
  for (unsigned i = 0; i < 8; ++i)
    if (mask & (1u << i)) validate_node_recurs(p, pos, depth + 1, node_bytes, check, count);
}

}  // namespace detail

template <class Check>
std::size_t validate_node_stream(const std::string& payload, std::size_t node_bytes,
                                 const Check& check) {
  std::size_t pos = 0, count = 0;
  if (payload.empty()) return 0;
  detail::validate_node_recurs(payload, pos, 0, node_bytes, check, count);
  if (pos != payload.size())
    throw_format_error(std::to_string(payload.size() - pos) + " unexpected bytes after the tree");
  return count;
}

}  // namespace semioctree
