// `semioctree export IN.ot [--color OUT.ot] [--bt OUT.bt] [--ply OUT.ply]`
#include <iostream>
#include <memory>

#include "commands.h"
#include "option_checks.h"
#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"

namespace semioctree::cli {

void add_export_command(CLI::App& app) {
  struct Options {
    std::string in, color, bt, ply;
    bool ply_unknown = false;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "export", "Convert a SemiOcTree .ot into files other tools open (at least one output).");
  cmd->add_option("IN", o->in, "SemiOcTree .ot file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--color", o->color,
                  "write a ColorOcTree .ot: every labelled octant as an occupied node in its "
                  "class colour (opens in octovis)");
  cmd->add_option("--bt", o->bt,
                  "write a .bt occupancy map: occupied -> occupied; empty/out/door/window -> "
                  "free; occluded/unknown -> unknown");
  cmd->add_option("--ply", o->ply,
                  "write a binary PLY of octant centres with colour, label, level and size "
                  "(CloudCompare, MeshLab)");
  cmd->add_flag("--ply-unknown", o->ply_unknown, "also write unknown octants to the PLY");
  cmd->callback([o] {
    if (o->color.empty() && o->bt.empty() && o->ply.empty())
      throw std::runtime_error("export: nothing to do, give --color, --bt and/or --ply");
    check_outputs_spare_inputs({{"IN", o->in}},
                               {{"--color", o->color}, {"--bt", o->bt}, {"--ply", o->ply}});
    const auto tree = read_semioctree_file(o->in);
    if (!o->color.empty()) {
      write_color_octree_file(*tree, {}, o->color);
      std::cout << "wrote " << o->color << " (ColorOcTree)\n";
    }
    if (!o->bt.empty()) {
      write_occupancy_binary_file(*tree, {}, o->bt);
      std::cout << "wrote " << o->bt << " (OcTree occupancy)\n";
    }
    if (!o->ply.empty()) {
      PlyOptions po;
      po.include_unknown = o->ply_unknown;
      const std::size_t n = write_octant_ply(*tree, o->ply, po);
      std::cout << "wrote " << o->ply << " (" << n << " octants)\n";
    }
  });
}

}  // namespace semioctree::cli
