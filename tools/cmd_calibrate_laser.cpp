// `lasercell calibrate laser --camera CAMERA.cameramodel (--planes DIR --heights-mm H1,H2,... |
//  --stripe-images 'GLOB' --board chessboard:COLSxROWS:SQUARE_MM) --cell CELL.yaml
//  --report LASER.html --json LASER.json`: the laser plane in the sensor frame
//  (calib/laser_plane.hpp),
// written as the `laser` plane of CELL.yaml (only that entry changes; the file is created when
// missing), a versioned JSON summary and a self-contained HTML report
// (calib/laser_plane_report.hpp). The white-plane sweeps are read by
// triangulation/laser_plane_captures.hpp.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_model.hpp"
#include "calib/laser_plane.hpp"
#include "calib/laser_plane_report.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/number_list.hpp"
#include "core/provenance.hpp"
#include "tools/commands.hpp"
#include "triangulation/laser_plane_captures.hpp"

namespace lasercell::tools {
namespace {

struct LaserArgs {
  std::string camera, planes, heights, stripe_glob, board, cell, report, json;
  std::string plate_normal = "0,0,-1";
  double plate_distance_mm = std::nan("");
  std::string laser_color = "green";
  bool quiet = false;
  bool fixed_plate_normal = false;
};

calib::LaserPlaneResult FromPlanes(const LaserArgs& args, const calib::CameraModel& camera,
                                   InputDigest& digest) {
  if (args.heights.empty())
    throw OptionError("--planes needs --heights-mm H1,H2,... (one per plane_<i>.lcp)");
  const std::vector<std::string> files = triangulation::FindPlaneProfileFiles(args.planes);
  const std::vector<double> heights = ParseNumberList(args.heights, "--heights-mm", files.size());
  calib::HeightPlaneOptions options;
  const auto m = ParseNumberList(args.plate_normal, "--plate-normal", 3);
  options.plate_normal_in_sensor = Eigen::Vector3d(m[0], m[1], m[2]);
  if (std::isfinite(args.plate_distance_mm)) options.zero_distance_mm = args.plate_distance_mm;
  options.estimate_plate_tilt = !args.fixed_plate_normal;
  const auto captures = triangulation::LoadHeightCaptures(files, heights, camera, &digest);
  return calib::CalibrateLaserPlaneFromHeights(camera, captures, options);
}

calib::LaserPlaneResult FromStripes(const LaserArgs& args, const calib::CameraModel& camera,
                                    InputDigest& digest) {
  if (args.board.empty())
    throw OptionError("--stripe-images needs --board chessboard:COLSxROWS:SQUARE_MM");
  const calib::BoardSpec board = calib::ParseBoardSpec(args.board);
  calib::StripeOptions options;
  options.laser_color = args.laser_color;
  return triangulation::CalibrateLaserPlaneFromStripeFiles(
      camera, io::GlobFiles(args.stripe_glob, "--stripe-images"), board, options, &digest);
}

void Run(const LaserArgs& args) {
  const bool by_planes = !args.planes.empty();
  if (by_planes == !args.stripe_glob.empty()) {
    throw OptionError(
        "give either --planes DIR --heights-mm H1,H2,... or --stripe-images 'GLOB' --board ...");
  }
  InputDigest digest;
  digest.AddFile(args.camera);
  const calib::CameraModel camera = calib::LoadCameraModel(args.camera);
  const calib::LaserPlaneResult result =
      by_planes ? FromPlanes(args, camera, digest) : FromStripes(args, camera, digest);
  // Outputs: the JSON and the report always (they explain a failure), the cell only for a
  // usable plane.
  json::WriteFile(args.json, calib::LaserPlaneJson(result, args.camera));
  if (!args.report.empty())
    report::WriteHtmlReport(args.report, calib::LaserPlaneReport(result, camera));
  const std::string refusal = result.RefusalReason();
  if (!refusal.empty())
    throw InputError("laser plane not written to " + args.cell + ": " + refusal);
  FrameGraph graph;
  std::error_code ec;
  if (std::filesystem::exists(args.cell, ec)) graph = LoadFrameGraph(args.cell);
  EdgeProvenance provenance;
  provenance.tool = std::string("lasercell calibrate laser ") + LASERCELL_VERSION;
  provenance.date = UtcTimestampIso();
  provenance.input_digest = digest.Text();
  graph.SetLaserPlane("laser", calib::LaserPlaneCellEntry(result, provenance));
  SaveFrameGraph(args.cell, graph);
  if (!args.quiet) std::printf("%s -> %s\n", result.Summary().c_str(), args.cell.c_str());
}

}  // namespace

void AddCalibrateLaserCommand(CLI::App& calibrate) {
  CLI::App* cmd = calibrate.add_subcommand(
      "laser",
      "Laser plane in the sensor frame from white-plane sweeps at known heights, or from "
      "a laser stripe on a chessboard of unknown pose; updates the cell's `laser` plane");
  auto args = std::make_shared<LaserArgs>();
  cmd->add_option("--camera", args->camera, "Camera model (.cameramodel)")->required();
  cmd->add_option("--planes", args->planes,
                  "Folder of white-plane sweeps plane_<i>.lcp (or a folder holding profiles/)");
  cmd->add_option("--heights-mm", args->heights,
                  "Plate heights along the plate normal, one per plane_<i>.lcp, mm");
  cmd->add_option("--plate-normal", args->plate_normal,
                  "Unit normal of the white plate in the sensor frame, pointing towards the sensor "
                  "(default 0,0,-1)");
  cmd->add_option(
      "--plate-distance-mm", args->plate_distance_mm,
      "Distance from the sensor origin to the height-0 plate along the plate normal (default: "
      "estimated, needs >= 3 heights)");
  cmd->add_flag("--fixed-plate-normal", args->fixed_plate_normal,
                "Keep --plate-normal exactly (default: estimate its tilt towards the laser line)");
  cmd->add_option("--stripe-images", args->stripe_glob,
                  "Images of a laser stripe on a chessboard (quoted glob)");
  cmd->add_option("--board", args->board, "chessboard:COLSxROWS:SQUARE_MM (inner corners, mm)");
  cmd->add_option("--laser-color", args->laser_color,
                  "Laser colour in the stripe images: green, red or gray");
  cmd->add_option("--cell", args->cell, "Cell file to update (created when missing)")->required();
  cmd->add_option("--report", args->report, "HTML report to write");
  cmd->add_option("--json", args->json, "JSON summary to write");
  cmd->add_flag("--quiet", args->quiet, "No summary line");
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
