// Header checks of PCD and PLY files before PCL reads them (see
// point_file_checks.h).
#include "point_file_checks.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "semioctree/scan_io.h"

namespace semioctree::detail {

namespace {

// PCL allocates what a PCD or PLY header claims before it looks at the data,
// so a small file with a huge point count exhausts memory. The checks below
// read the header themselves (at most kMaxHeader bytes) and check the counts
// against the file's size before PCL sees the file, never allocating in
// proportion to a claimed count.
constexpr std::size_t kMaxHeader = 64 * 1024;
constexpr std::uint64_t kMaxPoints = kMaxFilePoints;
constexpr std::uint64_t kSaturated = std::numeric_limits<std::uint64_t>::max();

// Saturating: a saturated byte count is simply more than any file holds.
std::uint64_t mul_sat(std::uint64_t a, std::uint64_t b) {
  std::uint64_t r = 0;
  return __builtin_mul_overflow(a, b, &r) ? kSaturated : r;
}
std::uint64_t add_sat(std::uint64_t a, std::uint64_t b) {
  std::uint64_t r = 0;
  return __builtin_add_overflow(a, b, &r) ? kSaturated : r;
}

bool starts_with(const std::string& s, const char* prefix) {
  return s.rfind(prefix, 0) == 0;
}

std::vector<std::string> split_blanks(const std::string& line) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// Digits only: PCL's stream parsing would turn "-5" into a huge unsigned count.
bool parse_count(const std::string& s, std::uint64_t& out) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, out);
  return !s.empty() && r.ec == std::errc() && r.ptr == end;
}

// A whole token that PCL reads as a number (NaN and Inf included).
bool is_number(const std::string& s) {
  const char* p = s.data();
  const char* end = p + s.size();
  if (end - p > 1 && p[0] == '+' && p[1] != '-') ++p;  // from_chars takes no '+', PCL does
  double v = 0;
  const auto r = std::from_chars(p, end, v);
  return p != end && r.ptr == end &&
         (r.ec == std::errc() || r.ec == std::errc::result_out_of_range);
}

std::string excerpt(const std::string& s) {
  return "'" + (s.size() > 60 ? s.substr(0, 60) + "..." : s) + "'";
}

struct HeaderText {
  std::vector<std::string> lines;  // up to and including the last header line
  std::vector<std::vector<std::string>> tokens;
  std::uint64_t data_offset = 0;  // first byte after the header
  bool complete = false;          // the last header line was found
  bool too_long = false;          // not within kMaxHeader bytes
  std::uint64_t file_size = 0;
};

// Reads header lines until `is_last(tokens)`, from the first kMaxHeader bytes.
template <typename IsLast>
HeaderText read_header(const std::string& path, IsLast is_last) {
  HeaderText h;
  std::error_code ec;
  h.file_size = std::filesystem::file_size(path, ec);
  std::ifstream f(path, std::ios::binary);
  if (ec || !f) throw ScanReadError(path + ": cannot open");
  std::string buf(kMaxHeader, '\0');
  f.read(buf.data(), std::streamsize(buf.size()));
  buf.resize(std::size_t(f.gcount()));
  std::size_t pos = 0;
  while (pos < buf.size()) {
    std::size_t nl = buf.find('\n', pos);
    if (nl == std::string::npos) {
      if (buf.size() == kMaxHeader) break;  // the line goes on past the cap
      nl = buf.size();
    }
    h.lines.push_back(buf.substr(pos, nl - pos));
    h.tokens.push_back(split_blanks(h.lines.back()));
    pos = std::min(nl + 1, buf.size());
    if (is_last(h.tokens.back())) {
      h.complete = true;
      h.data_offset = pos;
      return h;
    }
  }
  h.too_long = buf.size() == kMaxHeader;
  return h;
}

// PCD header entries, in the order the format requires (COLUMNS is FIELDS).
const char* const kPcdKeys[] = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
enum PcdKey {
  kVersion,
  kFields,
  kSize,
  kType,
  kCount,
  kWidth,
  kHeight,
  kViewpoint,
  kPoints,
  kData
};

// PCL recognises an entry by its prefix ("WIDTHS 3" is WIDTH); -1: not an entry.
int pcd_key(const std::string& token) {
  if (starts_with(token, "COLUMNS")) return kFields;
  for (int k = 0; k <= kData; ++k)
    if (starts_with(token, kPcdKeys[k])) return k;
  return -1;
}

struct PcdHeader {
  std::uint64_t points = 0;
  std::uint64_t point_step = 0;        // binary bytes per point
  std::uint64_t values_per_point = 0;  // ASCII numbers per point
  int data_type = 0;                   // PCL's codes: 0 ascii, 1 binary, 2 binary_compressed
  std::uint64_t data_offset = 0;
  std::size_t header_lines = 0;
  std::uint64_t file_size = 0;
};

PcdHeader parse_pcd_header(const std::string& path) {
  const HeaderText h =
      read_header(path, [](const auto& t) { return !t.empty() && pcd_key(t[0]) == kData; });
  std::vector<std::string> names, types;
  std::vector<std::uint64_t> sizes, counts;
  std::uint64_t width = 0, height = 0, points = 0;  // 0: not given
  PcdHeader out;
  int last = -1;
  for (std::size_t i = 0; i < h.lines.size(); ++i) {
    const auto& t = h.tokens[i];
    const std::string at = path + ": PCD header line " + std::to_string(i + 1) + ": ";
    if (h.lines[i].empty() || (!t.empty() && t[0][0] == '#')) continue;
    const int key = t.empty() ? -1 : pcd_key(t[0]);
    if (key < 0)
      throw ScanReadError(at + "not a PCD header entry: " + excerpt(h.lines[i]) +
                          (i == 0 ? " (not a PCD file?)" : ""));
    // The format fixes the order; PCL's buffer size depends on it.
    if (key <= last)
      throw ScanReadError(at + kPcdKeys[key] +
                          " is repeated or out of order (expected VERSION, FIELDS, SIZE, TYPE, "
                          "COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA)");
    last = key;
    const std::vector<std::string> values(t.begin() + 1, t.end());
    auto per_field = [&](const char* what) {
      if (values.size() != names.size())
        throw ScanReadError(at + what + " has " + std::to_string(values.size()) + " values for " +
                            std::to_string(names.size()) + " FIELDS");
    };
    auto positive = [&](const char* what) {
      std::uint64_t v = 0;
      if (values.empty() || !parse_count(values[0], v) || v == 0)
        throw ScanReadError(at + what + " must be a positive integer, got " +
                            excerpt(values.empty() ? "" : values[0]));
      if (v > kMaxPoints)
        throw ScanReadError(at + what + " " + values[0] + " is more than the " +
                            std::to_string(kMaxPoints) + " points PCL can read");
      return v;
    };
    switch (key) {
      case kFields:
        if (values.empty()) throw ScanReadError(at + "FIELDS names no field");
        names = values;
        break;
      case kSize:
        per_field("SIZE");
        for (const auto& v : values) {
          std::uint64_t n = 0;
          if (!parse_count(v, n) || (n != 1 && n != 2 && n != 4 && n != 8))
            throw ScanReadError(at + "SIZE must be 1, 2, 4 or 8, got " + excerpt(v));
          sizes.push_back(n);
        }
        break;
      case kType:
        per_field("TYPE");
        if (sizes.empty()) throw ScanReadError(at + "TYPE without SIZE");
        for (const auto& v : values)
          if (v != "F" && v != "I" && v != "U")
            throw ScanReadError(at + "TYPE must be F, I or U, got " + excerpt(v));
        types = values;
        break;
      case kCount:
        per_field("COUNT");
        if (types.empty()) throw ScanReadError(at + "COUNT without SIZE and TYPE");
        for (const auto& v : values) {
          std::uint64_t n = 0;
          if (!parse_count(v, n) || n == 0)
            throw ScanReadError(at + "COUNT must be a positive integer, got " + excerpt(v));
          counts.push_back(n);
        }
        break;
      case kWidth:
        width = positive("WIDTH");
        break;
      case kHeight:
        height = positive("HEIGHT");
        break;
      case kPoints:
        points = positive("POINTS");
        break;
      case kData:
        if (values.empty() ||
            (values[0] != "ascii" && values[0] != "binary" && values[0] != "binary_compressed"))
          throw ScanReadError(at + "DATA must be ascii, binary or binary_compressed, got " +
                              excerpt(values.empty() ? "" : values[0]));
        out.data_type = values[0] == "ascii" ? 0 : values[0] == "binary" ? 1 : 2;
        break;
      default:  // VERSION, VIEWPOINT: PCL checks them
        break;
    }
  }
  if (!h.complete)
    throw ScanReadError(path + (h.too_long ? ": PCD header is longer than 64 KiB (no DATA line)"
                                           : ": not a readable PCD file (no DATA line)"));
  if (names.empty()) throw ScanReadError(path + ": PCD header has no FIELDS");
  if (!sizes.empty() && types.empty()) throw ScanReadError(path + ": PCD header has no TYPE");
  if (points == 0) throw ScanReadError(path + ": PCD header has no POINTS");
  if (height != 0 && width == 0) throw ScanReadError(path + ": PCD header has HEIGHT but no WIDTH");
  if (width == 0) width = points;
  if (height == 0) height = 1;
  if (mul_sat(width, height) != points)
    throw ScanReadError(path + ": PCD header's WIDTH x HEIGHT (" + std::to_string(width) + " x " +
                        std::to_string(height) + ") is not its POINTS (" + std::to_string(points) +
                        ")");
  sizes.resize(names.size(), 4);  // PCL's defaults without SIZE, TYPE, COUNT
  types.resize(names.size(), "F");
  counts.resize(names.size(), 1);
  for (const char* axis : {"x", "y", "z"}) {
    const auto it = std::find(names.begin(), names.end(), axis);
    if (it == names.end()) throw ScanReadError(path + ": PCD file has no x, y, z fields");
    const std::size_t i = std::size_t(it - names.begin());
    // PCL fills a field of another type with 0 when converting to PointXYZ.
    if (sizes[i] != 4 || types[i] != "F" || counts[i] != 1)
      throw ScanReadError(path + ": PCD field " + axis +
                          " is not a 4-byte float (SIZE 4, TYPE F, COUNT 1 needed)");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    out.point_step = add_sat(out.point_step, mul_sat(sizes[i], counts[i]));
    out.values_per_point = add_sat(out.values_per_point, counts[i]);
  }
  out.points = points;
  out.data_offset = h.data_offset;
  out.header_lines = h.lines.size();
  out.file_size = h.file_size;
  return out;
}

// PCL's header loop ends only at a line that is no header entry, so entries in
// the data bytes right after DATA would override the header checked here.
// Streams the lines PCL would look at (comments and VERSION it skips).
bool pcd_entry_after_data(std::istream& in) {
  std::streambuf* sb = in.rdbuf();
  for (;;) {
    int c = sb->sbumpc();
    if (c == EOF) return false;
    if (c == '\n') continue;  // empty line: PCL skips it
    while (c != EOF && c != '\n' && std::isspace(c)) c = sb->sbumpc();
    std::string token;
    while (c != EOF && c != '\n' && !std::isspace(c) && token.size() < 16) {
      token += char(c);
      c = sb->sbumpc();
    }
    if (token.empty()) return false;
    if (token[0] != '#' && !starts_with(token, "VERSION")) return pcd_key(token) >= 0;
    while (c != EOF && c != '\n') c = sb->sbumpc();
    if (c == EOF) return false;
  }
}

// PCL reads a token that is not a number as 0 and a line with the wrong number
// of values as (0, 0, 0), both silently: reject such lines, naming them. Reads
// the first `points` non-empty lines (PCL ignores the rest) a byte at a time.
void check_pcd_ascii(const std::string& path, std::istream& in, const PcdHeader& h) {
  std::streambuf* sb = in.rdbuf();
  std::uint64_t seen = 0, tokens = 0;
  std::size_t lineno = h.header_lines + 1;
  std::string token, text;  // text: the line's start, for the message
  bool empty = true, bad = false;
  auto end_token = [&] {
    if (token.empty()) return;
    ++tokens;
    bad |= !is_number(token);
    token.clear();
  };
  while (seen < h.points) {
    const int c = sb->sbumpc();
    if (c == EOF || c == '\n') {
      end_token();
      if (!empty) {  // PCL skips empty lines only
        if (bad || tokens != h.values_per_point)
          throw ScanReadError(path + ":" + std::to_string(lineno) + ": expected " +
                              std::to_string(h.values_per_point) +
                              " numbers (the header's FIELDS and COUNT), got " + excerpt(text));
        ++seen;
      }
      if (c == EOF) break;
      ++lineno;
      tokens = 0;
      empty = true;
      bad = false;
      text.clear();
      continue;
    }
    empty = false;
    if (c != '\r' && text.size() <= 60) text += char(c);
    if (c == ' ' || c == '\t' || c == '\r')  // PCL's separators
      end_token();
    else if (token.size() < 64)
      token += char(c);
    else
      bad = true;  // no number is that long
  }
  if (seen < h.points)
    throw ScanReadError(path + ": PCD file is truncated (" + std::to_string(seen) + " of " +
                        std::to_string(h.points) + " points)");
  // PCL stops after POINTS rows: a further row of numbers is a point it would
  // drop silently. Other text after the data (a note) is left alone, as PCL does.
  std::string line;
  for (int c = sb->sbumpc();; c = sb->sbumpc()) {
    if (c != EOF && c != '\n') {
      if (line.size() < 4096) line += char(c);
      continue;
    }
    const std::vector<std::string> values = split_blanks(line);
    if (!values.empty() && std::all_of(values.begin(), values.end(), is_number))
      throw ScanReadError(path + ":" + std::to_string(lineno) + ": PCD POINTS (" +
                          std::to_string(h.points) +
                          ") is less than the file's data rows: one more row, " + excerpt(line));
    if (c == EOF) return;
    line.clear();
    ++lineno;
  }
}

// PCL's writer of PCLPointCloud2 binary data stretches the file to a memory
// page plus the data, whatever the header's length: the file then ends in up
// to a page of zeros (pages are at most 64 KiB; the header may since have been
// edited). True for such a tail: all zero, shorter than 64 KiB.
bool pcl_page_padding(std::istream& in, const PcdHeader& h, std::uint64_t bytes) {
  const std::uint64_t tail_size = h.file_size - h.data_offset - bytes;
  if (tail_size >= 65536) return false;
  in.clear();
  in.seekg(std::streamoff(h.data_offset + bytes));
  std::string tail(std::size_t(tail_size), '\1');
  in.read(tail.data(), std::streamsize(tail.size()));
  return std::size_t(in.gcount()) == tail.size() &&
         tail.find_first_not_of('\0') == std::string::npos;
}

}  // namespace

std::string check_pcd_file(const std::string& path) {
  const PcdHeader h = parse_pcd_header(path);
  const std::uint64_t available = h.file_size - std::min(h.file_size, h.data_offset);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ScanReadError(path + ": cannot open");
  f.seekg(std::streamoff(h.data_offset));
  const std::uint64_t bytes = mul_sat(h.points, h.point_step);
  if (h.data_type == 0) {
    // Each value takes a character and a separator (the last line may lack its newline).
    const std::uint64_t need = mul_sat(h.points, mul_sat(2, h.values_per_point)) - 1;
    if (available < need)
      throw ScanReadError(
          path + ": PCD file is truncated or its POINTS is wrong: " + std::to_string(h.points) +
          " points need at least " + std::to_string(need) + " bytes of ASCII data, the file has " +
          std::to_string(available));
    check_pcd_ascii(path, f, h);
    return "ascii";
  }
  if (pcd_entry_after_data(f)) throw ScanReadError(path + ": PCD header entry after the DATA line");
  if (h.data_type == 1 && available < bytes)
    throw ScanReadError(path + ": PCD file is truncated or its POINTS is wrong: " +
                        std::to_string(h.points) + " points need " + std::to_string(bytes) +
                        " data bytes, the file has " + std::to_string(available));
  // PCL reads POINTS rows and ignores the rest: a whole row more is a point
  // dropped. PCL's own padding is not a row (pcl_page_padding).
  if (h.data_type == 1 && available - bytes >= h.point_step && !pcl_page_padding(f, h, bytes))
    throw ScanReadError(
        path + ": PCD POINTS is less than the file's data rows: " + std::to_string(h.points) +
        " points of " + std::to_string(h.point_step) + " bytes take " + std::to_string(bytes) +
        " data bytes, the file has " + std::to_string(available) + " (" +
        std::to_string(available / h.point_step) + " rows)");
  if (h.data_type == 2) {  // binary_compressed: two uint32 sizes, then the compressed block
    f.clear();
    f.seekg(std::streamoff(h.data_offset));
    std::uint32_t sizes[2] = {0, 0};
    if (!f.read(reinterpret_cast<char*>(sizes), sizeof(sizes)) ||
        available < 8 + std::uint64_t(sizes[0]))
      throw ScanReadError(path + ": binary_compressed data is truncated: the compressed block " +
                          (available < 8
                               ? std::string("has no size")
                               : "of " + std::to_string(sizes[0]) + " bytes needs " +
                                     std::to_string(8 + std::uint64_t(sizes[0])) +
                                     " data bytes, the file has " + std::to_string(available)));
    if (sizes[1] != bytes)
      throw ScanReadError(path + ": binary_compressed data is corrupt: its block unpacks to " +
                          std::to_string(sizes[1]) + " bytes, POINTS " + std::to_string(h.points) +
                          " of " + std::to_string(h.point_step) + " bytes need " +
                          std::to_string(bytes));
    // LZF's longest back-reference, 3 bytes, expands to 264: no block grows
    // more than 88 times. PCL allocates the uncompressed size before checking.
    if (bytes > 88 * std::uint64_t(sizes[0]))
      throw ScanReadError(
          path + ": PCD file is corrupted or its POINTS is wrong: " + std::to_string(sizes[0]) +
          " compressed bytes cannot hold " + std::to_string(h.points) + " points (" +
          std::to_string(bytes) + " bytes)");
    return "binary_compressed";
  }
  return "binary";
}

namespace {

int ply_type_size(const std::string& type) {
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") return 1;
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") return 2;
  if (type == "int" || type == "int32" || type == "uint" || type == "uint32" || type == "float" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// PCL's reader gives a vertex's uchar red (or diffuse_red) a 4-byte rgb field
// where it stands, but writes the colour and moves past it only at blue: the
// properties read between the two, and all of them after a blue without its
// red, land at offsets other than their fields' (the last vertex's past the
// buffer, where PCL asserts). Red, green and blue one after another, once each,
// keep every field where PCL writes it. A uchar alpha is merged into the
// colour last read, or, with none read yet but a property named rgb declared,
// into the vertex's first four bytes (without one PCL skips it). Throws naming
// the property.
void check_ply_vertex_colours(const std::string& path,
                              const std::vector<std::pair<std::string, std::string>>& properties) {
  auto colour = [](const std::pair<std::string, std::string>& p) {
    if (p.second != "uchar" && p.second != "uint8") return -1;
    if (p.first == "alpha") return 3;
    for (int c = 0; c < 3; ++c) {
      const std::string name = c == 0 ? "red" : c == 1 ? "green" : "blue";
      if (p.first == name || p.first == "diffuse_" + name) return c;
    }
    return -1;
  };
  std::size_t first = properties.size(), seen = 0;
  bool named_rgb = false;
  for (std::size_t i = 0; i < properties.size(); ++i) {
    const int c = colour(properties[i]);
    named_rgb |= properties[i].first == "rgb";
    if (c < 0) continue;
    if (c == 3) {
      if (seen == 0 && named_rgb)
        throw ScanReadError(path +
                            ": PLY vertex property alpha comes before red, green, blue: "
                            "PCL would merge it into the vertex's first property");
      continue;
    }
    if (first == properties.size()) first = i;
    ++seen;
    if (i != first + std::size_t(c))
      throw ScanReadError(path + ": PLY vertex property " + properties[i].first +
                          " is out of place: PCL reads uchar colours only as red, green, blue, "
                          "once each and one after another");
  }
  if (seen != 0 && seen != 3)
    throw ScanReadError(path + ": PLY vertex has " + properties[first].first +
                        " without all of red, green, blue: PCL reads uchar colours only as the "
                        "three together");
}

// PLY: the header's element counts against the file's size, before PCL's
// reader allocates them (its vertex buffer, its range_grid rows).
}  // namespace

void check_ply_file(const std::string& path) {
  const HeaderText h =
      read_header(path, [](const auto& t) { return !t.empty() && t[0] == "end_header"; });
  if (h.lines.empty() || !starts_with(h.lines[0], "ply"))  // all PCL looks at
    throw ScanReadError(path + ": not a PLY file (no 'ply' line)");
  if (!h.complete)
    throw ScanReadError(path + (h.too_long ? ": PLY header is longer than 64 KiB (no end_header)"
                                           : ": not a readable PLY file (no end_header)"));
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t bytes = 0;       // binary bytes per row, at least (lists may be empty)
    std::uint64_t properties = 0;  // ASCII values per row, at least
  };
  std::vector<Element> elements;
  std::string format;
  std::vector<std::pair<std::string, std::string>> vertex_properties;  // name, type, in order
  const auto vertex_property = [&](const std::string& name) {
    return std::find_if(vertex_properties.begin(), vertex_properties.end(),
                        [&](const auto& p) { return p.first == name; });
  };
  // Cloud size as PCL's reader sets it: obj_info num_cols / num_rows, else the vertex count.
  std::uint32_t cols = 0, rows = 0;
  bool obj_info_size = false;
  for (std::size_t i = 1; i < h.lines.size(); ++i) {
    const auto& t = h.tokens[i];
    const std::string at = path + ": PLY header line " + std::to_string(i + 1) + ": ";
    if (t.empty()) continue;
    if (t[0] == "format") {
      if (t.size() < 2 ||
          (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian"))
        throw ScanReadError(at + "unknown format " + excerpt(h.lines[i]));
      format = t[1];
    } else if (t[0] == "element") {
      Element e;
      if (t.size() != 3 || !parse_count(t[2], e.count))
        throw ScanReadError(at + "expected 'element NAME COUNT' with COUNT a non-negative " +
                            "integer, got " + excerpt(h.lines[i]));
      e.name = t[1];
      // PCL counts the rows of both into one buffer sized for the first.
      if ((e.name == "vertex" || e.name == "range_grid") &&
          std::any_of(elements.begin(), elements.end(),
                      [&](const Element& o) { return o.name == e.name; }))
        throw ScanReadError(at + "a second " + e.name + " element");
      if (e.name == "vertex") {
        if (e.count == 0)
          throw ScanReadError(path + ": PLY file holds no points (element vertex 0)");
        if (e.count > kMaxPoints)
          throw ScanReadError(at + "element vertex " + t[2] + " is more than the " +
                              std::to_string(kMaxPoints) + " points PCL can read");
        if (cols == 0 || rows == 0) {
          cols = std::uint32_t(e.count);
          rows = 1;
        }
      }
      elements.push_back(e);
    } else if (t[0] == "property") {
      if (elements.empty()) throw ScanReadError(at + "property before any element");
      Element& e = elements.back();
      const bool list = t.size() >= 2 && t[1] == "list";
      if (t.size() < (list ? 5u : 3u) || ply_type_size(t[list ? 2 : 1]) == 0 ||
          (list && ply_type_size(t[3]) == 0))
        throw ScanReadError(at + "unknown property type in " + excerpt(h.lines[i]));
      e.bytes = add_sat(e.bytes, std::uint64_t(ply_type_size(t[list ? 2 : 1])));
      e.properties = add_sat(e.properties, 1);
      if (e.name == "vertex") {
        // PCL sizes its buffer from the first vertex's list lengths, which
        // the header does not bound.
        if (list)
          throw ScanReadError(
              at + "list property in the vertex element is not supported: " + excerpt(h.lines[i]));
        const std::string& name = t[2];
        if (vertex_property(name) != vertex_properties.end())
          throw ScanReadError(at + "vertex property " + name + " is declared twice");
        vertex_properties.emplace_back(name, t[1]);
      }
    } else if (t[0] == "obj_info" && std::isspace(static_cast<unsigned char>(h.lines[i][0]))) {
      // PCL's reader splits the line at blanks and asserts that its first word is
      // obj_info: a leading blank aborts the program.
      throw ScanReadError(at + "obj_info line starts with a blank: " + excerpt(h.lines[i]));
    } else if (t[0] == "obj_info" && t.size() >= 3 && (t[1] == "num_cols" || t[1] == "num_rows")) {
      // PCL reads these with atoi and sizes its buffer by them.
      const auto v = std::uint32_t(int(std::strtol(t[2].c_str(), nullptr, 10)));
      (t[1] == "num_cols" ? cols : rows) = v;
      obj_info_size = true;
    }
  }
  if (format.empty()) throw ScanReadError(path + ": PLY header has no format line");
  const auto vertex = std::find_if(elements.begin(), elements.end(),
                                   [](const Element& e) { return e.name == "vertex"; });
  if (vertex == elements.end()) throw ScanReadError(path + ": PLY file has no vertex element");
  for (const char* axis : {"x", "y", "z"}) {
    const auto it = vertex_property(axis);
    if (it == vertex_properties.end()) throw ScanReadError(path + ": PLY vertex has no x, y, z");
    // PCL fills a property of another type with 0 when converting to PointXYZ.
    if (it->second != "float" && it->second != "float32")
      throw ScanReadError(path + ": PLY vertex property " + axis + " is " + it->second +
                          ", not float");
  }
  check_ply_vertex_colours(path, vertex_properties);
  const auto grid = std::find_if(elements.begin(), elements.end(),
                                 [](const Element& e) { return e.name == "range_grid"; });
  // Each vertex is one cell's: PCL sizes its buffer by the cells.
  if (grid != elements.end() && grid->count < vertex->count)
    throw ScanReadError(path + ": PLY has more vertices (" + std::to_string(vertex->count) +
                        ") than range_grid cells (" + std::to_string(grid->count) + ")");
  if (obj_info_size) {
    // A range_grid maps the cloud's cells to vertices; without it the cells
    // are the vertices. Any other size makes PCL invent or drop points.
    const std::uint64_t cells = grid != elements.end() ? grid->count : vertex->count;
    if (std::uint64_t(cols) * rows != cells)
      throw ScanReadError(path + ": PLY obj_info num_cols x num_rows (" + std::to_string(cols) +
                          " x " + std::to_string(rows) + ") is not the " +
                          (grid != elements.end() ? "range_grid" : "vertex") + " count " +
                          std::to_string(cells));
  }
  // Each row takes at least its scalars (binary) or a character and a
  // separator per value (ASCII; the last line may lack its newline). A row
  // with no properties still counts a byte: PCL does work per row.
  const bool ascii = format == "ascii";
  std::uint64_t need = 0;
  std::string claimed;
  for (const Element& e : elements) {
    const std::uint64_t row = ascii ? mul_sat(2, e.properties) : e.bytes;
    need = add_sat(need, mul_sat(e.count, std::max<std::uint64_t>(1, row)));
    if (e.count > 0)
      claimed += (claimed.empty() ? "" : ", ") + e.name + " " + std::to_string(e.count);
  }
  if (ascii && need > 0) --need;
  const std::uint64_t available = h.file_size - std::min(h.file_size, h.data_offset);
  if (available < need)
    throw ScanReadError(path + ": PLY file is truncated or its element counts are wrong: " +
                        "the elements (" + claimed + ") need at least " + std::to_string(need) +
                        (ascii ? " bytes of ASCII data" : " data bytes") + ", the file has " +
                        std::to_string(available));
  if (!ascii) return;
  // ASCII: one line per row, elements in header order. Count the non-empty lines.
  std::ifstream f(path, std::ios::binary);
  f.seekg(std::streamoff(h.data_offset));
  std::uint64_t lines = 0;
  bool blank = true;
  char buf[1 << 16];
  while (f.read(buf, sizeof buf) || f.gcount() > 0) {
    for (std::streamsize i = 0; i < f.gcount(); ++i) {
      if (buf[i] == '\n') {
        lines += !blank;
        blank = true;
      } else if (!std::isspace(static_cast<unsigned char>(buf[i]))) {
        blank = false;
      }
    }
  }
  lines += !blank;
  std::uint64_t before = 0;
  for (const Element& e : elements) {
    if (lines < before + e.count)
      throw ScanReadError(path + ": ascii PLY ends after " + std::to_string(lines - before) +
                          " of " + std::to_string(e.count) + " " +
                          (e.name == "vertex" ? std::string("vertices") : e.name + " rows") +
                          " (truncated, or its element counts are wrong)");
    before += e.count;
  }
}

}  // namespace semioctree::detail
