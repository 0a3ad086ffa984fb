// Octant classes of the semioctree and their colours (the paper's figures).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace semioctree {

enum class Label : std::uint8_t {
  kUnknown = 0,
  kEmpty = 1,
  kOccupied = 2,
  kOccluded = 3,
  kDoor = 4,
  kWindow = 5,
  kOut = 6,
  kScan = 7,  // a past scanner position
  kNbv = 8,   // the next best view
};

inline constexpr int kLabelCount = 9;

struct Rgb {
  std::uint8_t r, g, b;
};

inline constexpr std::array<std::string_view, kLabelCount> kLabelNames = {
    "unknown", "empty", "occupied", "occluded", "door", "window", "out", "scan", "nbv"};

// Never white: ColorOcTree treats white as "no colour".
inline constexpr std::array<Rgb, kLabelCount> kLabelColors = {{
    {128, 128, 128},  // unknown (not exported to colour trees)
    {150, 200, 255},  // empty: light blue
    {0, 0, 139},      // occupied: dark blue
    {160, 160, 160},  // occluded: grey
    {0, 170, 0},      // door: green
    {230, 0, 230},    // window: magenta
    {240, 220, 0},    // out: yellow
    {0, 0, 0},        // scan: black
    {230, 0, 0},      // nbv: red
}};

// A value outside the enumeration (a cast from bad data) is "invalid", drawn black.
inline std::string_view label_name(Label l) {
  const auto i = static_cast<std::size_t>(l);
  return i < std::size_t(kLabelCount) ? kLabelNames[i] : std::string_view("invalid");
}
inline Rgb label_color(Label l) {
  const auto i = static_cast<std::size_t>(l);
  return i < std::size_t(kLabelCount) ? kLabelColors[i] : Rgb{0, 0, 0};
}
inline bool is_valid_label(std::uint8_t v) {
  return v < kLabelCount;
}
std::optional<Label> label_from_name(std::string_view name);

// How a label maps to OctoMap occupancy in .bt exports.
enum class Occupancy { kOccupied, kFree, kUnknown };
inline Occupancy label_occupancy(Label l) {
  switch (l) {
    case Label::kOccupied:
      return Occupancy::kOccupied;
    case Label::kEmpty:
    case Label::kOut:
    case Label::kDoor:
    case Label::kWindow:
    case Label::kScan:
    case Label::kNbv:
      return Occupancy::kFree;
    default:
      return Occupancy::kUnknown;
  }
}

}  // namespace semioctree
