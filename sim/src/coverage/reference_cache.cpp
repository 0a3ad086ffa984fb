// The cache of coverage references: key, file layout, reading and writing.
#include "coverage/reference_cache.h"

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>
#include <utility>

#include "atomic_file.h"
#include "coverage/content_hash.h"
#include "semioctree/sim/coverage/visibility.h"

namespace semioctree::sim {

namespace detail {

namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'S', 'O', 'C', 'O', 'V', 'R', 'E', 'F'};

class Writer {
 public:
  template <typename T>
  void value(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    out_.append(p, sizeof v);
  }
  void raw(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(const std::string& in, std::size_t end) : in_(in), end_(end) {}
  template <typename T>
  bool value(T& v) {
    return raw(&v, sizeof v);
  }
  bool raw(void* p, std::size_t n) {
    if (n > end_ - pos_) return false;
    std::memcpy(p, in_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  std::size_t remaining() const { return end_ - pos_; }

 private:
  const std::string& in_;
  std::size_t end_;
  std::size_t pos_ = 0;
};

std::uint64_t checksum(const char* data, std::size_t n) {
  ContentHash h;
  h.bytes(data, n);
  return h.first();
}

// The file: magic, rule version, key (length, bytes), both spacings, sample count,
// positions (count, x y z each), visible indices (count, u32 each), the visible samples'
// positions (x y z each, as many), checksum of all that.
std::string serialize(const CoverageReference& ref) {
  Writer w;
  w.raw(kMagic, sizeof kMagic);
  w.value(kCoverageRuleVersion);
  w.value(static_cast<std::uint32_t>(ref.key.size()));
  w.raw(ref.key.data(), ref.key.size());
  w.value(ref.grid_spacing);
  w.value(ref.sample_spacing);
  w.value(static_cast<std::uint64_t>(ref.sample_count));
  w.value(static_cast<std::uint64_t>(ref.positions.size()));
  for (const auto& p : ref.positions) w.raw(p.data(), 3 * sizeof(double));
  w.value(static_cast<std::uint64_t>(ref.visible.size()));
  w.raw(ref.visible.data(), ref.visible.size() * sizeof(std::uint32_t));
  for (const auto& p : ref.points) w.raw(p.data(), 3 * sizeof(double));
  w.value(checksum(w.str().data(), w.str().size()));
  return std::move(w.str());
}

// Parses a cache file; false (and `ref` unusable) unless every check passes.
bool deserialize(const std::string& data, const std::string& key, double grid_spacing,
                 double sample_spacing, std::size_t sample_count, CoverageReference& ref) {
  constexpr std::size_t kSum = sizeof(std::uint64_t);
  if (data.size() < sizeof kMagic + kSum) return false;
  std::uint64_t stored = 0;
  std::memcpy(&stored, data.data() + data.size() - kSum, kSum);
  if (stored != checksum(data.data(), data.size() - kSum)) return false;
  Reader r(data, data.size() - kSum);
  char magic[sizeof kMagic];
  std::uint32_t version = 0, key_len = 0;
  if (!r.raw(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0) return false;
  if (!r.value(version) || version != kCoverageRuleVersion) return false;
  if (!r.value(key_len) || key_len != key.size()) return false;
  std::string stored_key(key_len, '\0');
  if (!r.raw(stored_key.data(), key_len) || stored_key != key) return false;
  double g = 0, s = 0;
  std::uint64_t count = 0, np = 0, nv = 0;
  if (!r.value(g) || !r.value(s) || g != grid_spacing || s != sample_spacing) return false;
  if (!r.value(count) || count != sample_count) return false;
  if (!r.value(np) || np > r.remaining() / (3 * sizeof(double))) return false;
  ref.positions.resize(np);
  for (auto& p : ref.positions)
    if (!r.raw(p.data(), 3 * sizeof(double))) return false;
  if (!r.value(nv) || nv > count ||
      nv * (sizeof(std::uint32_t) + 3 * sizeof(double)) != r.remaining())
    return false;
  ref.visible.resize(nv);
  if (!r.raw(ref.visible.data(), nv * sizeof(std::uint32_t))) return false;
  ref.points.resize(nv);
  for (auto& p : ref.points)
    if (!r.raw(p.data(), 3 * sizeof(double))) return false;
  for (std::size_t i = 0; i < ref.visible.size(); ++i)
    if (ref.visible[i] >= count || (i > 0 && ref.visible[i] <= ref.visible[i - 1])) return false;
  ref.grid_spacing = g;
  ref.sample_spacing = s;
  ref.sample_count = count;
  return true;
}

bool read_file(const fs::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return false;
  out = ss.str();
  return true;
}

// Writes `data` to a temporary name in the same directory, then renames it over `path`.
bool write_atomically(const fs::path& path, const std::string& data) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  return detail::replace_file_atomically(path.string(), [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    out.flush();
    return bool(out);
  });
}

}  // namespace

SamplesDigest digest_of_samples(const GroundTruth& truth, double sample_spacing) {
  SamplesDigest digest;
  for_each_surface_sample(truth.scene(), sample_spacing,
                          [&](const SurfaceSample& s) { digest.add(s); });
  return digest;
}

SamplesDigest digest_of_samples(const std::vector<SurfaceSample>& samples) {
  SamplesDigest digest;
  for (const SurfaceSample& s : samples) digest.add(s);
  return digest;
}

std::string reference_key(const GroundTruth& truth, const SamplesDigest& samples,
                          double grid_spacing, double sample_spacing) {
  ContentHash h;
  h.text("semioctree-coverage-reference");
  h.value(kCoverageRuleVersion);
  h.value(kCoverageSampleOffset);
  h.value(kCoveragePlanCell);
  h.value(grid_spacing);
  h.value(sample_spacing);
  const Scene& scene = truth.scene();
  const ScannerConfig& s = scene.scanner;
  for (double v : {s.height, s.elevation_min_deg, s.elevation_max_deg, s.min_range, s.max_range})
    h.value(v);
  h.value(scene.robot.start.x());
  h.value(scene.robot.start.y());
  h.value(scene.robot.radius);
  h.value(static_cast<std::uint8_t>(scene.survey_area.has_value()));
  if (scene.survey_area) {
    h.value(static_cast<std::uint64_t>(scene.survey_area->size()));
    for (const auto& p : *scene.survey_area) h.bytes(p.data(), 2 * sizeof(double));
  }
  const SceneTriangles& tri = truth.triangles();
  h.value(static_cast<std::uint64_t>(tri.vertices.size()));
  for (const auto& v : tri.vertices) h.bytes(v.data(), 3 * sizeof(float));
  h.value(static_cast<std::uint64_t>(tri.triangles.size()));
  for (const auto& t : tri.triangles) h.bytes(t.data(), 3 * sizeof(std::uint32_t));
  h.value(static_cast<std::uint64_t>(samples.count()));
  h.text(samples.hex());
  return h.hex();
}

std::filesystem::path cache_file_path(const std::string& cache_dir, const std::string& key) {
  return fs::path(cache_dir) / ("coverage-" + key + ".bin");
}

bool read_cached_reference(const std::filesystem::path& file, const std::string& key,
                           double grid_spacing, double sample_spacing, std::size_t sample_count,
                           CoverageReference& ref) {
  std::string data;
  return read_file(file, data) &&
         deserialize(data, key, grid_spacing, sample_spacing, sample_count, ref);
}

bool write_cached_reference(const std::filesystem::path& file, const CoverageReference& ref) {
  return write_atomically(file, serialize(ref));
}

}  // namespace detail

std::string coverage_cache_key(const GroundTruth& truth, double grid_spacing,
                               double sample_spacing) {
  return detail::reference_key(truth, detail::digest_of_samples(truth, sample_spacing),
                               grid_spacing, sample_spacing);
}

std::string default_cache_dir() {
  namespace fs = std::filesystem;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && xdg[0] == '/') return (fs::path(xdg) / "semioctree").string();
  const char* home = std::getenv("HOME");
  if (home && home[0] != '\0') return (fs::path(home) / ".cache" / "semioctree").string();
  std::error_code ec;
  const fs::path tmp = fs::temp_directory_path(ec);
  return ((ec ? fs::path("/tmp") : tmp) / "semioctree-cache").string();
}

}  // namespace semioctree::sim
