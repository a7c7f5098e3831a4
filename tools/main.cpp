// ctk: calibration and reconstruction of cone-beam CT scans along arbitrary trajectories.
#include <malloc.h>

#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "interruption.hpp"

namespace {

// What a lab needs to know which build made a result: version and commit, compiler, and the SIMD
// targets compiled in and the one this processor runs.
std::string version_text() {
  std::string targets;
  for (const std::string& t : ctk::JosephProjector::simd_targets()) targets += (targets.empty() ? "" : " ") + t;
  return "ctk " + ctk::build_version() + "\ncompiler: " + __VERSION__ + "\nSIMD targets compiled: " + targets +
         "; chosen at run time: " + ctk::JosephProjector::simd_target();
}

}  // namespace

int main(int argc, char** argv) {
  // Every view passes through a few image-sized buffers (2 MB at 720 x 720). By default glibc maps
  // each from the kernel and unmaps it when freed, so the pages are faulted in and zeroed again
  // for every view (15 % of a calibration's time); keep such blocks in the heap instead.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  ctk::set_invocation(argc, argv);
  CLI::App app{"ctk — calibrate and reconstruct cone-beam CT scans taken along arbitrary (robot) trajectories"};
  app.set_version_flag("--version", version_text());
  app.require_subcommand(1);
  ctk::tools::register_simulate(app);
  ctk::tools::register_phantom(app);
  ctk::tools::register_import(app);
  ctk::tools::register_geometry(app);
  ctk::tools::register_calibrate(app);
  ctk::tools::register_diagnose(app);
  ctk::tools::register_refine(app);
  ctk::tools::register_plan(app);
  ctk::tools::register_reconstruct(app);
  ctk::tools::register_bench(app);
  // CLI11 answers a mistyped subcommand ("ctk reconstuct", "ctk import circulr") with "A
  // subcommand is required", which hides the typo: follow the words down the subcommands and
  // name the first that is none of them, with those there are.
  std::string path = "ctk";
  CLI::App* level = &app;
  for (int i = 1; i < argc && argv[i][0] != '-'; ++i) {
    const std::vector<CLI::App*> subs = level->get_subcommands([](CLI::App*) { return true; });
    if (subs.empty()) break;  // the words from here on are this subcommand's arguments
    try {
      level = level->get_subcommand(argv[i]);
      path += " " + level->get_name();
    } catch (const CLI::OptionNotFound&) {
      std::cerr << path << ": unknown subcommand '" << argv[i] << "'; the subcommands are:";
      for (const CLI::App* sub : subs) std::cerr << " " << sub->get_name();
      std::cerr << "\nRun with --help for more information.\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (or the help); a malformed command line is bad input like any
    // other, so it exits 2 rather than with CLI11's own codes (105 for a missing file, ...).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const ctk::tools::Interrupted& e) {
    std::cerr << "ctk: " << e.what() << "\n";
    return 130;
  } catch (const ctk::InputError& e) {
    std::cerr << "ctk: input error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "ctk: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
