#pragma once
// Each ctk subcommand registers itself on the application; one file per subcommand.
#include <CLI/CLI.hpp>

namespace ctk::tools {

void register_geometry(CLI::App& app);
void register_bench(CLI::App& app);
void register_simulate(CLI::App& app);
void register_phantom(CLI::App& app);
void register_reconstruct(CLI::App& app);
void register_calibrate(CLI::App& app);
void register_diagnose(CLI::App& app);
void register_holder(CLI::App& app);
void register_import(CLI::App& app);
void register_refine(CLI::App& app);
void register_plan(CLI::App& app);

}  // namespace ctk::tools
