// `lasercell calibrate handeye`: eye-in-hand calibration of the camera on the
// vision robot's flange from chessboard images (or committed corner detections)
// and robot poses (calib/hand_eye.hpp; poses, detection, matching and result
// files: calib/hand_eye_session.hpp). Updates only the vision_flange -> sensor
// edge of CELL.yaml (created when missing); writes a versioned JSON (poses in
// the file notation, residuals, 1 sigma) and an HTML report.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/hand_eye.hpp"
#include "calib/hand_eye_session.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/provenance.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct HandEyeArgs {
  std::string cell, camera, images, corners, board, report, json;
  std::string method = "park-martin";
  calib::HandEyePoseSource poses;
  int threads = 1;
};

void Run(const HandEyeArgs& args) {
  if (args.images.empty() == args.corners.empty()) {
    throw OptionError("give exactly one of --images GLOB and --corners FILE");
  }
  if (!args.images.empty() && args.board.empty()) {
    throw OptionError("--board is required with --images");
  }
  FrameGraph graph;
  std::error_code ec;
  if (std::filesystem::exists(args.cell, ec)) graph = LoadFrameGraph(args.cell);
  calib::HandEyeInputs inputs;
  inputs.camera = args.camera;
  if (!args.images.empty()) inputs.images = io::GlobFiles(args.images, "--images");
  inputs.corners = args.corners;
  inputs.board = args.board;
  inputs.poses = args.poses;
  inputs.method = args.method;
  inputs.threads = args.threads;
  inputs.tool = std::string("lasercell calibrate handeye ") + LASERCELL_VERSION;
  const calib::HandEyeSession s =
      calib::CalibrateHandEyeFromFiles(inputs, graph, args.cell, [](const std::string& line) {
        std::fprintf(stderr, "calibrate handeye: %s\n", line.c_str());
      });
  std::printf("%s\n", s.result.Summary().c_str());
  std::printf("%s_from_%s = %s\n", args.poses.flange_frame.c_str(), args.poses.camera_frame.c_str(),
              PoseToFileNotation(s.result.flange_from_camera).c_str());
  for (const auto& w : s.result.warnings) std::printf("warning: %s\n", w.c_str());
  graph.SetStaticEdge(s.edge);  // only the flange -> camera edge
  SaveFrameGraph(args.cell, graph);
  if (!args.report.empty())
    report::WriteHtmlReport(args.report, calib::HandEyeReport(s.result, s.views, s.run));
  json::WriteFile(args.json, calib::HandEyeJson(s.result, s.views, s.run));
}

}  // namespace

void AddCalibrateHandEyeCommand(CLI::App& calibrate) {
  auto args = std::make_shared<HandEyeArgs>();
  CLI::App* cmd =
      calibrate.add_subcommand("handeye",
                               "Eye-in-hand: camera on the robot flange observing a fixed "
                               "chessboard; updates the "
                               "vision_flange -> sensor edge of CELL.yaml");
  cmd->add_option("--cell", args->cell, "Cell file (updated in place; created when missing)")
      ->required();
  cmd->add_option("--camera", args->camera, "Camera model (.cameramodel)")->required();
  cmd->add_option("--images", args->images, "Image glob (sorted order = pose order)");
  cmd->add_option("--corners", args->corners,
                  "Corner detections instead of images "
                  "(lasercell-chessboard-corners text)");
  cmd->add_option("--board", args->board, "chessboard:COLSxROWS:SQUARE_MM (inner corners, mm)");
  cmd->add_option("--poses", args->poses.path,
                  "Robot poses base_from_flange: kuka text (metres), lasercell "
                  "YAML (mm) or a "
                  "simulator records/hand_eye_images.yaml (joints)")
      ->required();
  cmd->add_option(
         "--pose-format", args->poses.format,
         "auto, kuka (4x4, metres), yaml, xyzwpr (Fanuc, deg), xyzabc (KUKA, deg) or record")
      ->capture_default_str();
  cmd->add_option("--method", args->method,
                  "Closed form that starts the refinement: tsai-lenz, "
                  "park-martin, daniilidis")
      ->capture_default_str();
  cmd->add_option("--flange-frame", args->poses.flange_frame, "Parent frame of the edge")
      ->capture_default_str();
  cmd->add_option("--camera-frame", args->poses.camera_frame, "Child frame of the edge")
      ->capture_default_str();
  cmd->add_option("--robot", args->poses.robot, "Robot of a joint record (default: the record's)");
  cmd->add_option("--threads", args->threads, "Ceres threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_option("--report", args->report, "HTML report");
  cmd->add_option("--json", args->json, "JSON result");
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
