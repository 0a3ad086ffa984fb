// Generated scenes for surveys at scale: a seed and a kind give one valid, varied
// `*.scene.json` (rectangular or L-shaped rooms, halls with columns and a mezzanine, floors
// of rooms joined by doors; doors, windows, furniture, robot and scanner drawn from the
// seed). What is varied and the rules that keep every scene valid:
// docs/generated-scenes.md.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "semioctree/sim/scene.h"

namespace semioctree::sim {

// `any` draws one of the single-room kinds (room, l_shape, hall); a floor is asked for.
enum class GeneratedKind { any, room, l_shape, hall, floor };

const char* to_string(GeneratedKind kind);  // "any", "room", "l-shape", "hall", "floor"
// The names to_string gives, in enum order.
std::vector<std::string> generated_kind_names();
// The kind named `name`; throws std::invalid_argument naming the accepted ones.
GeneratedKind generated_kind_from_string(const std::string& name);
// The kind scene `seed` of `kind` has: `kind` itself, or the one `any` draws from the seed.
GeneratedKind resolve_generated_kind(std::uint64_t seed, GeneratedKind kind);

// Rooms a generated floor may be asked for (FloorRequest::rooms); drawn ones are 3-10.
constexpr int kMinFloorRooms = 2, kMaxFloorRooms = 200;
// Sides of a floor's outline that may be asked for (FloorRequest::width, depth), metres.
constexpr double kMinFloorSide = 6.0, kMaxFloorSide = 120.0;

// What a floor is asked to be; all zero: everything drawn from the seed. Other kinds take
// the default only.
// - rooms: the room count, a corridor counting as one (kMinFloorRooms-kMaxFloorRooms).
// - width × depth: the floor inside the outer walls, along x and y (both or neither, each
//   kMinFloorSide-kMaxFloorSide). Such a floor is one rectangle cut into rooms (no
//   corridor); without `rooms` it has one room per 20 m² (rounded), as drawn floors have
//   on average.
struct FloorRequest {
  int rooms = 0;
  double width = 0, depth = 0;
  bool sized() const { return width > 0 || depth > 0; }
};

// "60x45" (or "60X45") → {60, 45}: a floor's width and depth; throws
// std::invalid_argument naming the text and the range of a side.
std::pair<double, double> floor_size_from_string(const std::string& text);

// The scene file text (format version 1, numbers rounded to the millimetre) of the scene
// `seed` of `kind`. The same seed, kind and request give the same text with any standard
// library and compiler: every random number is derived from std::mt19937_64's raw output
// here, one at a time. A floor asked for the room count its seed draws is the same scene
// but for its name. Throws std::invalid_argument for a request out of range, or one for
// another kind than a floor.
std::string generate_scene_json(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any,
                                const FloorRequest& floor = {});

// The same scene read back through parse_scene_json (as a file holding that text would
// be): its source_file is "generated-<kind>-<seed>".
Scene generate_scene(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any,
                     const FloorRequest& floor = {});

}  // namespace semioctree::sim
