// libFuzzer target: a *.scene.json text through parse_scene_json, the core of
// load_scene_json. Mesh paths resolve in the scratch directory, which holds one
// small mesh, box.obj, so that a "meshes" entry can reach the mesh reader. A
// SceneError is the reader's clear answer; anything else is a finding.
#include <fstream>
#include <string>

#include "fuzz_input_file.h"
#include "semioctree/sim/scene.h"

namespace {

const std::string& mesh_dir() {
  static const std::string dir = [] {
    const std::string d = semioctree::fuzz::scratch_dir();
    std::ofstream(d + "/box.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n"
                                     "f 1 2 3\nf 1 3 4\nf 1 2 6\nf 1 6 5\n";
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    semioctree::sim::parse_scene_json(text, "fuzz.scene.json", mesh_dir());
  } catch (const semioctree::sim::SceneError&) {
  }
  return 0;
}
