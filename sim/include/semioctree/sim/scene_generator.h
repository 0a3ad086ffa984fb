// Generated single-room scenes for surveys at scale: a seed and a kind give one valid,
// varied `*.scene.json` (rectangular or L-shaped rooms, halls with columns and a
// mezzanine; doors, windows, furniture, robot and scanner drawn from the seed). What is
// varied and the rules that keep every scene valid: docs/generated-scenes.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/sim/scene.h"

namespace semioctree::sim {

enum class GeneratedKind { any, room, l_shape, hall };

const char* to_string(GeneratedKind kind);  // "any", "room", "l-shape", "hall"
// The names to_string gives, in enum order.
std::vector<std::string> generated_kind_names();
// The kind named `name`; throws std::invalid_argument naming the accepted ones.
GeneratedKind generated_kind_from_string(const std::string& name);
// The kind scene `seed` of `kind` has: `kind` itself, or the one `any` draws from the seed.
GeneratedKind resolve_generated_kind(std::uint64_t seed, GeneratedKind kind);

// The scene file text (format version 1, numbers rounded to the millimetre) of the scene
// `seed` of `kind`. The same seed and kind give the same text with any standard library:
// every random number is derived from std::mt19937_64's raw output here.
std::string generate_scene_json(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any);

// The same scene read back through parse_scene_json (as a file holding that text would
// be): its source_file is "generated-<kind>-<seed>".
Scene generate_scene(std::uint64_t seed, GeneratedKind kind = GeneratedKind::any);

}  // namespace semioctree::sim
