// lasercell command line. Exit codes: 0 success, 2 bad input (one line naming the input and the
// problem), 1 internal failure.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "core/error.hpp"
#include "tools/bench.hpp"
#include "tools/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "lasercell: calibrate a laser-triangulation cell, scan and localize parts.\n"
      "Units: millimetres and radians. See README.md."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("lasercell ") + LASERCELL_VERSION);
  lasercell::tools::AddCloudCommands(app);
  lasercell::tools::AddFramesCommands(app);
  lasercell::tools::AddLocalizeCommand(app);
  lasercell::tools::AddReferencePoseCommand(app);
  lasercell::tools::AddJobCommands(app);
  lasercell::tools::AddModelCommands(app);
  lasercell::tools::AddSimulateCommands(app);
  lasercell::tools::AddScanCommands(app);
  lasercell::tools::AddStreamCommands(app);
  lasercell::tools::AddServeCommands(app);
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Calibrate the cell: camera, laser, spheres, hand-eye, joints");
  calibrate->require_subcommand(1);
  lasercell::tools::AddCalibrateSpheresCommand(*calibrate);
  lasercell::tools::AddCalibrateJointsCommands(*calibrate);
  lasercell::tools::AddCalibrateHandEyeCommand(*calibrate);
  lasercell::tools::AddCalibrateCameraCommand(*calibrate);
  lasercell::tools::AddCalibrateLaserCommand(*calibrate);
  lasercell::tools::AddBenchCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "lasercell: %s (see --help)\n", e.what());
    return 2;
  } catch (const lasercell::InternalError& e) {
    std::fprintf(stderr, "lasercell: internal error: %s\n", e.what());
    return 1;
  } catch (const lasercell::Error& e) {
    std::fprintf(stderr, "lasercell: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lasercell: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
