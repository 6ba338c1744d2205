#pragma once
// Subcommand registration. Each Add*Commands adds its subcommands with callbacks that run
// during app.parse() and throw lasercell errors on bad input.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "core/progress.hpp"
#include "triangulation/gige_source.hpp"

namespace lasercell::tools {
/// Progress on stderr: the stage padded to `width` columns and the percentage, rewritten in
/// place, a new line when a stage completes (tool_util.cpp).
ProgressCallback StderrProgress(int width = 60);
void AddCloudCommands(CLI::App& app);         ///< cloud info, cloud convert
void AddFramesCommands(CLI::App& app);        ///< frames show, frames get
void AddLocalizeCommand(CLI::App& app);       ///< localize
void AddReferencePoseCommand(CLI::App& app);  ///< reference-pose
void AddJobCommands(CLI::App& app);           ///< job run
void AddModelCommands(CLI::App& app);         ///< model info, model build
void AddSimulateCommands(CLI::App& app);      ///< simulate cell, simulate seat
/// calibrate spheres (under the `calibrate` parent created in main.cpp)
void AddCalibrateSpheresCommand(CLI::App& calibrate);
void AddScanCommands(CLI::App& app);  ///< scan triangulate, scan record
/// scan record (cmd_stream.cpp), under the `scan` parent given.
void AddScanRecordCommand(CLI::App& scan);
void AddStreamCommands(CLI::App& app);  ///< stream send
/// The options of a GigE Vision line-profiler source (--gige DEVICE, --line-rate, ...), shared by
/// scan record, job run and serve.
void AddGigeOptions(CLI::App* app, triangulation::GigeSourceOptions* options);
/// The sweep source of `job run` and `serve`: UDP when udp_port >= 0, the GigE device when
/// gige.device is set, nullptr for neither (the job's file); NextSweep waits up to wait_s.
/// Throws OptionError naming the flag for both, a bad port or wait.
std::shared_ptr<triangulation::ProfileSource> MakeLiveSource(
    int udp_port, const std::string& udp_bind, const triangulation::GigeSourceOptions& gige,
    double wait_s, const std::string& wait_flag);
void AddServeCommands(CLI::App& app);  ///< serve, robot-client
/// calibrate joints, calibrate handeye-laser (under the `calibrate` parent given).
void AddCalibrateJointsCommands(CLI::App& calibrate);
/// calibrate handeye (cmd_calibrate_handeye.cpp); `calibrate` is the parent subcommand.
void AddCalibrateHandEyeCommand(CLI::App& calibrate);
/// calibrate camera (added to the `calibrate` parent subcommand).
void AddCalibrateCameraCommand(CLI::App& calibrate);
/// calibrate laser; `calibrate` is the parent subcommand (created once in main.cpp).
void AddCalibrateLaserCommand(CLI::App& calibrate);
}  // namespace lasercell::tools
