// Generated scenes for surveys at scale: a seed and a kind give one valid, varied
// `*.scene.json` (rectangular or L-shaped rooms, halls with columns and a mezzanine, floors
// of rooms joined by doors; doors, windows, furniture, robot and scanner drawn from the
// seed). What is varied and the rules that keep every scene valid:
// docs/generated-scenes.md.
#pragma once

#include <cstdint>
#include <string>
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

// Rooms a generated floor may be asked for (`rooms` below); drawn ones are 3-10.
constexpr int kMinFloorRooms = 2, kMaxFloorRooms = 16;

// The scene file text (format version 1, numbers rounded to the millimetre) of the scene
// `seed` of `kind`. The same seed, kind and rooms give the same text with any standard
// library and compiler: every random number is derived from std::mt19937_64's raw output
// here, one at a time. `rooms`: a floor's room count (corridor included), 0 to draw it
// from the seed (a floor asked for the count its seed draws is the same scene); any other
// kind takes 0 only. Throws std::invalid_argument for a count out of range.
std::string generate_scene_json(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any,
                                int rooms = 0);

// The same scene read back through parse_scene_json (as a file holding that text would
// be): its source_file is "generated-<kind>-<seed>".
Scene generate_scene(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any, int rooms = 0);

}  // namespace semioctree::sim
