// ctk: calibration and reconstruction of cone-beam CT scans along arbitrary trajectories.
#include <malloc.h>

#include <filesystem>
#include <iostream>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ctk/core/communicator.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "interruption.hpp"
#include "progress.hpp"

namespace {

// What a lab needs to know which build made a result: version and commit, compiler, and the SIMD
// targets compiled in and the one this processor runs.
std::string version_text() {
  std::string targets;
  for (const std::string& t : ctk::JosephProjector::simd_targets()) targets += (targets.empty() ? "" : " ") + t;
  return "ctk " + ctk::build_version() + "\ncompiler: " + __VERSION__ + "\nSIMD targets compiled: " + targets +
         "; chosen at run time: " + ctk::JosephProjector::simd_target();
}

// The commands a run spread over MPI ranks divides between them; any other would do the same
// work on every rank and write the same files at once.
bool spreads_over_ranks(const std::string& command) { return command == "reconstruct" || command == "calibrate"; }

// A failure ends every rank of an MPI run (no rank waits for a dead one); one process just exits.
int fail(int exit_code) {
  const ctk::Communicator& ranks = ctk::world();
  if (ranks.size() > 1) {
    std::cerr.flush();
    ranks.abort(exit_code);
  }
  return exit_code;
}

// No option of ctk takes an empty value: `--out ""` would otherwise reach the end of a run as a
// file system error. Refused at parsing, for every option that takes one.
void refuse_empty_values(CLI::App& app) {
  static const CLI::Validator non_empty(
      [](const std::string& input) -> std::string { return input.empty() ? "expected a value, got an empty string" : ""; }, "",
      "non-empty");
  for (CLI::Option* option : app.get_options([](CLI::Option* o) { return o->get_expected_min() > 0; })) option->check(non_empty);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) refuse_empty_values(*sub);
}

// CLI11 answers a mistyped subcommand ("ctk reconstuct", "ctk import circulr") with "A
// subcommand is required", which hides the typo: follow the words down the subcommands and name
// the first that is none of them, with those there are. False when one was named.
bool subcommands_exist(CLI::App& app, int argc, char** argv) {
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
      return false;
    }
  }
  return true;
}

int run(int argc, char** argv) {
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
  ctk::tools::register_holder(app);
  ctk::tools::register_refine(app);
  ctk::tools::register_plan(app);
  ctk::tools::register_reconstruct(app);
  ctk::tools::register_bench(app);
  refuse_empty_values(app);
  if (!subcommands_exist(app, argc, argv)) return 2;
  // Under mpirun, the first rank speaks for the run; the others report only their errors.
  const ctk::Communicator& ranks = ctk::world();
  const std::string rank_prefix =
      ranks.size() > 1 ? " (rank " + std::to_string(ranks.rank()) + " of " + std::to_string(ranks.size()) + ")" : "";
  if (ranks.size() > 1) {
    const std::string command = argc > 1 ? argv[1] : "";
    if (!spreads_over_ranks(command)) {
      if (ranks.rank() == 0)
        std::cerr << "ctk " << command << ": does not spread over MPI ranks (reconstruct and calibrate do): run it without "
                  << "mpirun\n";
      return fail(2);
    }
    if (ranks.rank() != 0) {
      std::cout.rdbuf(nullptr);
      ctk::tools::Progress::silenced() = true;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (or the help); a malformed command line is bad input like any
    // other, so it exits 2 rather than with CLI11's own codes (105 for a missing file, ...).
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::cerr << ctk::with_long_words_clipped(e.what()) << "\nRun with --help for more information.\n";
    return fail(2);
  } catch (const ctk::tools::Interrupted& e) {
    std::cerr << "ctk" << rank_prefix << ": " << e.what() << "\n";
    return fail(130);
  } catch (const ctk::InputError& e) {
    std::cerr << "ctk" << rank_prefix << ": input error: " << e.what() << "\n";
    return fail(2);
  } catch (const std::invalid_argument& e) {
    // A request refusing a value (every options struct's validate()) is bad input as well.
    std::cerr << "ctk" << rank_prefix << ": input error: " << e.what() << "\n";
    return fail(2);
  } catch (const std::bad_alloc&) {
    std::cerr << "ctk" << rank_prefix << ": error: not enough memory for this run (the volume, the views held at once or "
              << "a size a file declares); the run's plan is printed above when it has one\n";
    return fail(1);
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "ctk" << rank_prefix << ": error: " << e.path1().string()
              << (e.path2().empty() ? "" : " -> " + e.path2().string()) << ": " << e.code().message() << "\n";
    return fail(1);
  } catch (const std::logic_error& e) {
    // A check inside ctk that failed is ctk's fault, not the input's: say so, and keep the detail
    // a report needs.
    std::cerr << "ctk" << rank_prefix << ": internal error (please report it with the command that gave it): " << e.what()
              << "\n";
    return fail(1);
  } catch (const std::exception& e) {
    std::cerr << "ctk" << rank_prefix << ": error: " << ctk::with_long_words_clipped(e.what()) << "\n";
    return fail(1);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes the run's own handlers (building the command line, the MPI start) still ends
  // the process with a message and exit 1, never with std::terminate.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "ctk: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "ctk: error of unknown kind\n";
  }
  return 1;
}
