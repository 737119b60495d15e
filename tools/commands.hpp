#pragma once
// Each subcommand group of `naneye` lives in its own cmd_<name>.cpp and adds itself to the app here.
#include <CLI/CLI.hpp>

namespace naneye::tools {

void add_calib_commands(CLI::App& app);
void add_calibrate_commands(CLI::App& app);
void add_devices_commands(CLI::App& app);
void add_driver_commands(CLI::App& app);
void add_fixed_pattern_commands(CLI::App& app);
void add_sim_commands(CLI::App& app);
void add_recon_commands(CLI::App& app);
void add_study_commands(CLI::App& app);

}  // namespace naneye::tools
