// `semioctree`: the command-line tool (git-style subcommands).
#include <pcl/console/print.h>

#include <exception>
#include <iostream>
#include <new>
#include <string>

#include "commands.h"
#include "semioctree/timing.h"
#include "semioctree/version.h"

int main(int argc, char** argv) {
  semioctree::map_large_allocations();
  const std::string name = std::string("semioctree ") + semioctree::version();
  CLI::App app{name +
               " — Next-Best-View planning for indoor laser-scanning surveys on a semioctree\n"
               "(a world-aligned coarse voxel grid refined as OctoMap octrees where needed)."};
  app.set_version_flag("--version", name);
  app.require_subcommand(1);
  app.fallthrough(false);
  semioctree::cli::add_info_command(app);
  semioctree::cli::add_export_command(app);
  semioctree::cli::add_discretize_command(app);
  semioctree::cli::add_compare_command(app);
  semioctree::cli::add_classify_command(app);
  semioctree::cli::add_nbv_command(app);
  semioctree::cli::add_map_nbv_command(app);
  semioctree::cli::add_report_command(app);
#ifdef SEMIOCTREE_HAVE_SIM
  semioctree::cli::add_scan_command(app);
  semioctree::cli::add_scene_info_command(app);
  semioctree::cli::add_make_scene_command(app);
  semioctree::cli::add_survey_command(app);
  semioctree::cli::add_coverage_bound_command(app);
#endif
  // PCL's console warnings (RANSAC on a degenerate cloud, elements it skips)
  // name neither the file nor the cause: the commands check their input and
  // say both in their own error.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::bad_alloc&) {
    // Allocation sizes follow the inputs: a leaf far finer than intended, or a
    // scene or option value far larger (a typo of a few orders of magnitude).
    std::cerr << "semioctree: error: out of memory: the map or scan asked for is larger than "
                 "this machine can hold; check the resolution (--leaf, --coarse, --leaves, "
                 "--cell, scan steps) and the extent of the input\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "semioctree: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
