// ctk: calibration and reconstruction of cone-beam CT scans along arbitrary trajectories.
#include <iostream>

#include "commands.hpp"
#include "ctk/geom/error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"ctk — calibrate and reconstruct cone-beam CT scans taken along arbitrary (robot) trajectories"};
  app.require_subcommand(1);
  ctk::tools::register_simulate(app);
  ctk::tools::register_phantom(app);
  ctk::tools::register_geometry(app);
  ctk::tools::register_calibrate(app);
  ctk::tools::register_reconstruct(app);
  ctk::tools::register_bench(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const ctk::InputError& e) {
    std::cerr << "ctk: input error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "ctk: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
