// `naneye`: the project's command-line tools. Each subcommand prints a clear error and exits
// non-zero on bad input; JSON output goes to stdout, logs to stderr.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "naneye/base/log.hpp"

int main(int argc, char** argv) {
  // Logs go to stderr so that stdout stays machine-readable (JSON lines).
  naneye::base::program_logger("cli");
  CLI::App app{"naneye: NanEye Stereo capture, replay and 3D reconstruction tools"};
  app.require_subcommand(1);
  naneye::tools::add_calib_commands(app);
  naneye::tools::add_calibrate_commands(app);
  naneye::tools::add_devices_commands(app);
  naneye::tools::add_driver_commands(app);
  naneye::tools::add_fixed_pattern_commands(app);
  naneye::tools::add_sim_commands(app);
  naneye::tools::add_recon_commands(app);
  naneye::tools::add_study_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "naneye: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
