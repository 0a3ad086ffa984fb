// `semioctree make-scene --seed N [--kind K] [--rooms R] [--size WxD] --out F.scene.json`: writes
// the generated scene of a seed (sim/include/semioctree/sim/scene_generator.h) to a file.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "commands.h"
#include "option_checks.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim/scene_generator.h"

namespace semioctree::cli {

namespace {

struct MakeSceneOptions {
  std::uint64_t seed = 1;
  std::string kind = "any";
  int rooms = 0;
  std::string size;  // "WxD", metres
  std::string out;
  bool force = false;
};

void run_make_scene(const MakeSceneOptions& o) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(o.out, ec))
    throw std::invalid_argument("--out " + o.out + " is a directory: name the scene file");
  if (fs::exists(o.out, ec) && !o.force)
    throw std::invalid_argument("--out " + o.out +
                                " exists: it is not replaced (it may be a scene of your own); "
                                "write elsewhere or add --force");
  const sim::GeneratedKind kind = sim::generated_kind_from_string(o.kind);
  if (o.rooms != 0 && kind != sim::GeneratedKind::floor)
    throw std::invalid_argument("--rooms is for --kind floor, not " + o.kind);
  if (!o.size.empty() && kind != sim::GeneratedKind::floor)
    throw std::invalid_argument("--size is for --kind floor, not " + o.kind);
  sim::FloorRequest floor;
  floor.rooms = o.rooms;
  if (!o.size.empty()) {
    try {
      std::tie(floor.width, floor.depth) = sim::floor_size_from_string(o.size);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--size: ") + e.what());
    }
  }
  const std::string text = sim::generate_scene_json(o.seed, kind, floor);
  // What is written is what the reader accepts: a generator bug is reported, not saved.
  const sim::Scene scene = sim::parse_scene_json(text, o.out, ".");
  const fs::path dir = fs::path(o.out).parent_path();
  remove_stale_temporaries(dir.empty() ? "." : dir.string());
  write_file_atomically(o.out, [&](std::ostream& file) { file << text; });
  std::size_t doors = 0, windows = 0;
  for (const sim::Wall& w : scene.walls)
    for (const sim::Opening& op : w.openings)
      ++(op.kind == sim::OpeningKind::door ? doors : windows);
  std::printf("wrote %s: %s, %zu walls, %zu doors, %zu windows, %zu boxes, %zu cylinders\n",
              o.out.c_str(), scene.name.c_str(), scene.walls.size(), doors, windows,
              scene.boxes.size(), scene.cylinders.size());
  std::printf("%s\n", scene.description.c_str());
}

}  // namespace

void add_make_scene_command(CLI::App& app) {
  auto o = std::make_shared<MakeSceneOptions>();
  auto* cmd = app.add_subcommand(
      "make-scene",
      "Write a generated scene (.scene.json, format version 1): a rectangular or L-shaped room "
      "or a hall with columns and a mezzanine, 0-4 doors and 0-4 windows; or a floor of rooms "
      "joined by doors (along a corridor, or cut from one rectangle); furniture, a robot and a "
      "scanner; all drawn from the seed, valid by construction (docs/generated-scenes.md). "
      "The same seed, kind, room count and size give the same file.");
  cmd->add_option("--seed", o->seed, "the scene's seed: any whole number from 0")
      ->required()
      ->check(seed_value());
  cmd->add_option("--kind", o->kind,
                  "room (rectangular, 4-14 m), l-shape (6-18 m, a corner cut off), hall (12-20 "
                  "m, 4.5-6 m high, columns, a mezzanine, machines), any (one of those three, "
                  "drawn from the seed) or floor (3-10 rooms of 3-6 m joined by doors, the robot "
                  "starting in one of them; its survey area is the whole floor)")
      ->check(CLI::IsMember(sim::generated_kind_names()))
      ->capture_default_str();
  cmd->add_option("--rooms", o->rooms,
                  "with --kind floor: the number of rooms, a corridor counting as one (" +
                      std::to_string(sim::kMinFloorRooms) + "-" +
                      std::to_string(sim::kMaxFloorRooms) +
                      "; default: drawn from the seed, 3-10, or one per 20 m² with --size)")
      ->check(CLI::Range(sim::kMinFloorRooms, sim::kMaxFloorRooms));
  cmd->add_option("--size", o->size,
                  "with --kind floor: the floor inside the outer walls, WxD metres along x and y "
                  "(each side 6-120, "
                  "e.g. 60x45); the rectangle is cut into rooms (no corridor); default: drawn "
                  "from the seed");
  cmd->add_option("--out", o->out, "the scene file to write (e.g. gen-7.scene.json)")->required();
  cmd->add_flag("--force", o->force, "replace --out if it exists (refused without)");
  cmd->callback([o] { run_make_scene(*o); });
}

}  // namespace semioctree::cli
