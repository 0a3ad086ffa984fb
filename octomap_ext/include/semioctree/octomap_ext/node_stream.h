// Guards in front of OctoMap's node-stream readers. OctoMap's readData and
// readBinaryData trust their input (an exhausted stream leaves the child mask
// uninitialised and can recurse without bound), so every byte stream is
// walked here first: depth bounded by 16, no byte missing, none left over.
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>

namespace semioctree {

std::uint64_t fnv1a64(const char* data, std::size_t n);

// Reads exactly n bytes in bounded chunks (a corrupted length cannot make us
// allocate more than the stream holds); throws FileFormatError when short.
std::string read_exactly(std::istream& s, std::uint64_t n);

// Walks OctoMap's .ot node stream (per node: `node_bytes` of data, then a
// child mask byte). `check(const char* data, unsigned depth, bool has_children)`
// returns an error text or nullptr. Returns the node count; throws
// FileFormatError on truncation, trailing bytes, depth > 16 or a failed check.
template <class Check>
std::size_t validate_node_stream(const std::string& payload, std::size_t node_bytes,
                                 const Check& check);

// Walks OctoMap's .bt binary stream (2 bytes of child codes per inner node).
// Returns the node count (root included); throws FileFormatError.
std::size_t validate_binary_stream(const std::string& payload);

}  // namespace semioctree

#include "semioctree/octomap_ext/node_stream_impl.hxx"
