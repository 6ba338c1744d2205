// `lasercell calibrate handeye`: eye-in-hand calibration of the camera on the vision robot's
// flange from chessboard images (or committed corner detections) and robot poses
// (calib/hand_eye.hpp). Updates only the vision_flange -> sensor edge of CELL.yaml; writes a
// versioned JSON (poses in the file notation, residuals, 1 sigma) and an HTML report.
#include <glob.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/hand_eye.hpp"
#include "calib/board.hpp"
#include "calib/pose_io.hpp"
#include "calib/target_detection.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

namespace fs = std::filesystem;

constexpr double kDeg = M_PI / 180.0;

struct HandEyeArgs {
  std::string cell, camera, images, corners, board, poses, pose_format = "auto", report, json;
  std::string method = "park-martin";
  std::string flange_frame = "vision_flange", camera_frame = "sensor";
  std::string robot;  // for pose records with joints: the robot (default from the record)
  int threads = 1;
};

// chessboard:COLSxROWS:SQUARE_MM, inner corners (calib/board.hpp parses and checks it; the
// hand-eye solver takes full chessboards only).
calib::BoardSpec ParseBoard(const std::string& spec) {
  const calib::BoardSpec board = calib::ParseBoardSpec(spec);
  if (board.type != calib::BoardType::kChessboard) {
    throw OptionError("--board: calibrate handeye takes a chessboard:COLSxROWS:SQUARE_MM board, "
                      "not '" + spec + "'");
  }
  return board;
}

calib::HandEyeMethod ParseMethod(const std::string& name) {
  for (auto m : {calib::HandEyeMethod::kTsaiLenz, calib::HandEyeMethod::kParkMartin,
                 calib::HandEyeMethod::kDaniilidis}) {
    if (calib::HandEyeMethodName(m) == name) return m;
  }
  throw OptionError("--method must be tsai-lenz, park-martin or daniilidis, not '" + name + "'");
}

std::vector<std::string> Glob(const std::string& pattern) {
  glob_t g{};
  const int rc = ::glob(pattern.c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  if (rc == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
  }
  globfree(&g);
  std::sort(out.begin(), out.end());
  if (out.empty()) throw InputError("--images '" + pattern + "' matches no file");
  return out;
}

nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  const QuaternionPose q = QuaternionPose::FromIsometry(pose);
  return {{"translation_mm",
           {q.translation_mm.x(), q.translation_mm.y(), q.translation_mm.z()}},
          {"rotation_wxyz", {q.rotation.w(), q.rotation.x(), q.rotation.y(), q.rotation.z()}}};
}

nlohmann::json SigmaJson(const Matrix6d& c) {
  nlohmann::json rot = nlohmann::json::array(), trans = nlohmann::json::array();
  for (int k = 0; k < 3; ++k) rot.push_back(std::sqrt(std::max(0.0, c(k, k))) / kDeg);
  for (int k = 3; k < 6; ++k) trans.push_back(std::sqrt(std::max(0.0, c(k, k))));
  return {{"rotation_deg", rot}, {"translation_mm", trans}};
}

nlohmann::json MatrixJson(const Matrix6d& c) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 6; ++r) {
    rows.push_back(nlohmann::json::array());
    for (int k = 0; k < 6; ++k) rows.back().push_back(c(r, k));
  }
  return rows;
}

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

void WriteReport(const HandEyeArgs& args, const calib::HandEyeResult& r,
                 const std::vector<std::string>& used, std::size_t n_views) {
  report::HtmlReport rep("lasercell calibrate handeye");
  rep.AddParagraph(r.Summary());
  for (const auto& w : r.warnings) rep.AddWarning(w);
  rep.AddHeading("Result");
  rep.AddKeyValues({{args.flange_frame + "_from_" + args.camera_frame,
                     PoseToFileNotation(r.flange_from_camera)},
                    {"base_from_board", PoseToFileNotation(r.base_from_board)},
                    {"reprojection RMS", Fmt("%.4f px", r.reprojection_rms_px)},
                    {"residual sigma (scales the covariance)", Fmt("%.4f px", r.residual_sigma_px)},
                    {"AX-XB RMS (consecutive motions)",
                     Fmt("%.4f deg", r.axxb_rms_rotation_deg) + " / " +
                         Fmt("%.4f mm", r.axxb_rms_translation_mm)},
                    {"views / corners", std::to_string(n_views) + " / " +
                                            std::to_string(r.observations)},
                    {"Ceres", r.termination}});
  rep.AddHeading("Per pose");
  std::vector<double> rot, trans;
  for (const auto& c : r.view_closure) {
    rot.push_back(c.rotation_deg);
    trans.push_back(c.translation_mm);
  }
  rep.AddBars("Reprojection RMS per pose", used, r.view_rms_px, "RMS (px)");
  rep.AddBars("Closure |Y^-1 A_i X C_i| rotation per pose", used, rot, "rotation (deg)");
  rep.AddBars("Closure |Y^-1 A_i X C_i| translation per pose", used, trans, "translation (mm)");
  std::vector<std::string> motion_labels;
  std::vector<double> mr, mt;
  for (std::size_t i = 0; i < r.axxb.size(); ++i) {
    motion_labels.push_back(used[i] + "->" + used[i + 1]);
    mr.push_back(r.axxb[i].rotation_deg);
    mt.push_back(r.axxb[i].translation_mm);
  }
  rep.AddBars("AX-XB rotation residual per motion", motion_labels, mr, "rotation (deg)");
  rep.AddBars("AX-XB translation residual per motion", motion_labels, mt, "translation (mm)");
  std::vector<std::vector<std::string>> rows;
  for (std::size_t i = 0; i < used.size(); ++i) {
    rows.push_back({used[i], Fmt("%.4f", r.view_rms_px[i]), Fmt("%.4f", rot[i]),
                    Fmt("%.4f", trans[i])});
  }
  rep.AddTable({"image", "reprojection RMS px", "closure deg", "closure mm"}, rows);
  rep.AddHeading("Residuals");
  std::vector<double> ru, rv;
  for (const auto& e : r.residuals_px) {
    ru.push_back(e.x());
    rv.push_back(e.y());
  }
  rep.AddHistogram("Corner residuals, u", ru, "residual u (px)");
  rep.AddHistogram("Corner residuals, v", rv, "residual v (px)");
  rep.AddScatter("Corner residuals", {{"residual", ru, rv, false}},
                 {"u (px)", "v (px)", true, false, {0, 0, 0, 0}});
  rep.AddHeading("Covariance of " + args.flange_frame + "_from_" + args.camera_frame);
  rep.AddParagraph("6x6 over [rotation vector rad (left perturbation); translation mm], scaled by "
                   "the residual variance; intrinsics and robot poses taken as exact.");
  const char* names[6] = {"rx (rad)", "ry (rad)", "rz (rad)", "tx (mm)", "ty (mm)", "tz (mm)"};
  std::vector<std::vector<std::string>> cov;
  for (int i = 0; i < 6; ++i) {
    std::vector<std::string> row = {names[i]};
    for (int k = 0; k < 6; ++k) row.push_back(Fmt("%.3e", r.flange_from_camera_covariance(i, k)));
    cov.push_back(row);
  }
  rep.AddTable({"", "rx", "ry", "rz", "tx", "ty", "tz"}, cov);
  const Eigen::Vector3d sr = r.SigmaRotationDeg(), st = r.SigmaTranslationMm();
  rep.AddKeyValues({{"1 sigma rotation (deg)", Fmt("%.5f", sr.x()) + ", " + Fmt("%.5f", sr.y()) +
                                                   ", " + Fmt("%.5f", sr.z())},
                    {"1 sigma translation (mm)", Fmt("%.4f", st.x()) + ", " + Fmt("%.4f", st.y()) +
                                                     ", " + Fmt("%.4f", st.z())}});
  report::WriteHtmlReport(args.report, rep);
}

std::string NowIso() {
  const std::time_t t = std::time(nullptr);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return b;
}

// Robot poses for the images, from a kuka/yaml pose file or a simulator record (joints through
// the cell's kinematic model).
calib::RobotPoses LoadPoses(const HandEyeArgs& args, const FrameGraph& graph) {
  const std::string text = io::ReadFileBytes(args.poses);
  if (args.pose_format == "record" ||
      (args.pose_format == "auto" && text.find("lasercell.hand_eye_images") != std::string::npos)) {
    const calib::HandEyeImagesRecord rec = calib::ParseHandEyeImagesRecord(text, args.poses);
    const std::string robot = args.robot.empty() ? rec.robot : args.robot;
    const DynamicEdge* edge = nullptr;
    for (const auto& e : graph.dynamic_edges()) {
      if (e.robot == robot) edge = &e;
    }
    if (!edge) {
      throw FileError(args.cell, "no dynamic edge for robot '" + robot + "' (needed by the joints "
                                 "in " + args.poses + ")");
    }
    calib::RobotPoses out;
    for (std::size_t i = 0; i < rec.images.size(); ++i) {
      out.base_from_flange.push_back(
          graph.Transform(edge->parent, edge->child, {{robot, rec.joints_rad[i]}}));
      out.images.push_back(std::filesystem::path(rec.images[i]).filename().string());
    }
    if (edge->child != args.flange_frame) {
      throw InputError("--poses: the robot's flange frame is '" + edge->child + "', not '" +
                       args.flange_frame + "' (--flange-frame)");
    }
    return out;
  }
  const std::string format = args.pose_format == "auto"
                                 ? (text.find("format:") != std::string::npos ? "yaml" : "kuka")
                                 : args.pose_format;
  if (format == "kuka") return calib::ParseKukaPoses(text, args.poses);
  if (format == "yaml") return calib::ParseYamlPoses(text, args.poses);
  throw OptionError("--pose-format must be auto, kuka, yaml or record, not '" + args.pose_format +
                    "'");
}

void Run(const HandEyeArgs& args) {
  if (args.images.empty() == args.corners.empty()) {
    throw OptionError("give exactly one of --images GLOB and --corners FILE");
  }
  const calib::HandEyeMethod method = ParseMethod(args.method);
  FrameGraph graph = LoadFrameGraph(args.cell);
  const calib::CameraModel camera = calib::LoadCameraModel(args.camera);
  const calib::RobotPoses poses = LoadPoses(args, graph);

  // Detections: from images (OpenCV) or from a committed corners file.
  calib::ChessboardDetections det;
  if (!args.corners.empty()) {
    det = calib::ParseChessboardDetections(io::ReadFileBytes(args.corners), args.corners);
    if (!args.board.empty()) {
      const calib::BoardSpec b = ParseBoard(args.board);
      if (b.cols != det.cols || b.rows != det.rows || b.square_mm != det.square_mm) {
        throw InputError("--board " + args.board + " does not match the board of " + args.corners);
      }
    }
  } else {
    if (args.board.empty()) throw OptionError("--board is required with --images");
    const calib::BoardSpec spec = ParseBoard(args.board);
    det.cols = spec.cols;
    det.rows = spec.rows;
    det.square_mm = spec.square_mm;
    const std::vector<std::string> files = Glob(args.images);
    if (files.size() != poses.base_from_flange.size()) {
      throw InputError("--images matches " + std::to_string(files.size()) + " images but --poses " +
                       args.poses + " has " + std::to_string(poses.base_from_flange.size()) +
                       " poses; give one pose per image, in sorted image order");
    }
    for (const std::string& f : files) {
      // The shared detector (SB, fallback, cornerSubPix sized to the squares, diagnostics).
      const calib::TargetDetection d = calib::DetectTargetInEncodedImage(io::ReadFileBytes(f), spec);
      if (d.status == calib::DetectionStatus::kUnreadable) {
        throw FileError(f, "is not a readable image");
      }
      det.width_px = d.width;
      det.height_px = d.height;
      det.images.push_back(std::filesystem::path(f).filename().string());
      det.corners_px.push_back(d.found() ? d.corners_px : std::vector<Eigen::Vector2d>{});
      if (!d.found()) std::fprintf(stderr, "calibrate handeye: %s: %s\n", f.c_str(), d.message.c_str());
    }
  }
  if (det.images.size() != poses.base_from_flange.size()) {
    throw InputError(std::to_string(det.images.size()) + " images in " + args.corners + " but " +
                     std::to_string(poses.base_from_flange.size()) + " poses in " + args.poses);
  }
  if (det.width_px && (det.width_px != camera.width_px() || det.height_px != camera.height_px())) {
    throw InputError("images are " + std::to_string(det.width_px) + "x" +
                     std::to_string(det.height_px) + " but --camera " + args.camera + " is " +
                     std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()));
  }

  if (!poses.images.empty()) {  // the pose file names its images: they must match, in order
    for (std::size_t i = 0; i < det.images.size(); ++i) {
      if (fs::path(poses.images[i]).filename() != fs::path(det.images[i]).filename()) {
        throw InputError("image " + std::to_string(i + 1) + " is " + det.images[i] + " but pose " +
                         std::to_string(i + 1) + " in " + args.poses + " is for " +
                         poses.images[i]);
      }
    }
  }
  const std::vector<Eigen::Vector3d> board = det.Board().Corners();
  std::vector<calib::HandEyeView> views;
  std::vector<std::string> used;
  for (std::size_t i = 0; i < det.images.size(); ++i) {
    if (det.corners_px[i].empty()) {
      std::fprintf(stderr, "calibrate handeye: %s: board not found, view skipped\n",
                   det.images[i].c_str());
      continue;
    }
    views.push_back({poses.base_from_flange[i], det.corners_px[i], board});
    used.push_back(det.images[i]);
  }
  calib::HandEyeOptions options;
  options.initialisation = method;
  options.threads = args.threads;
  const calib::HandEyeResult r = calib::CalibrateHandEye(views, camera, options);
  std::printf("%s\n", r.Summary().c_str());
  std::printf("%s_from_%s = %s\n", args.flange_frame.c_str(), args.camera_frame.c_str(),
              PoseToFileNotation(r.flange_from_camera).c_str());
  for (const auto& w : r.warnings) std::printf("warning: %s\n", w.c_str());

  // Cell: only the flange -> camera edge.
  StaticEdge edge;
  edge.parent = args.flange_frame;
  edge.child = args.camera_frame;
  edge.SetParentFromChild(r.flange_from_camera);
  if (r.covariance_valid) edge.covariance = r.flange_from_camera_covariance;
  edge.provenance.tool = std::string("lasercell calibrate handeye ") + LASERCELL_VERSION;
  edge.provenance.date = NowIso();
  char summary[200];
  std::snprintf(summary, sizeof summary,
                "reprojection rms %.4f px over %d corners in %zu views; AX-XB rms %.4f deg / %.4f mm",
                r.reprojection_rms_px, r.observations, views.size(), r.axxb_rms_rotation_deg,
                r.axxb_rms_translation_mm);
  edge.provenance.residual_summary = summary;
  graph.SetStaticEdge(edge);
  SaveFrameGraph(args.cell, graph);

  if (!args.report.empty()) WriteReport(args, r, used, views.size());
  if (!args.json.empty()) {
    std::vector<Eigen::Isometry3d> a;
    for (const auto& v : views) a.push_back(v.base_from_flange);
    nlohmann::json closed = nlohmann::json::object();
    for (auto m : {calib::HandEyeMethod::kTsaiLenz, calib::HandEyeMethod::kParkMartin,
                   calib::HandEyeMethod::kDaniilidis}) {
      closed[calib::HandEyeMethodName(m)] =
          PoseJson(calib::SolveHandEyeClosedForm(a, r.camera_from_board, m));
    }
    nlohmann::json per_view = nlohmann::json::array();
    for (std::size_t i = 0; i < views.size(); ++i) {
      per_view.push_back({{"image", used[i]},
                          {"reprojection_rms_px", r.view_rms_px[i]},
                          {"closure_rotation_deg", r.view_closure[i].rotation_deg},
                          {"closure_translation_mm", r.view_closure[i].translation_mm}});
    }
    nlohmann::json motions = nlohmann::json::array();
    for (const auto& e : r.axxb) {
      motions.push_back({{"rotation_deg", e.rotation_deg}, {"translation_mm", e.translation_mm}});
    }
    const nlohmann::json j = {
        {"format", "lasercell.hand_eye"},
        {"version", 1},
        {"tool", edge.provenance.tool},
        {"date", edge.provenance.date},
        {"camera", args.camera},
        {"poses", args.poses},
        {"frames", {{"parent", args.flange_frame}, {"child", args.camera_frame}}},
        {"flange_from_camera", PoseJson(r.flange_from_camera)},
        {"flange_from_camera_sigma", SigmaJson(r.flange_from_camera_covariance)},
        {"flange_from_camera_covariance", MatrixJson(r.flange_from_camera_covariance)},
        {"base_from_board", PoseJson(r.base_from_board)},
        {"base_from_board_sigma", SigmaJson(r.base_from_board_covariance)},
        {"base_from_board_covariance", MatrixJson(r.base_from_board_covariance)},
        {"covariance_note",
         "6x6 over [rotation vector rad (left perturbation); translation mm], scaled by the "
         "residual variance; intrinsics and robot poses taken as exact"},
        {"covariance_valid", r.covariance_valid},
        {"initialisation", calib::HandEyeMethodName(method)},
        {"closed_forms", closed},
        {"converged", r.converged},
        {"iterations", r.iterations},
        {"observations", r.observations},
        {"reprojection_rms_px", r.reprojection_rms_px},
        {"residual_sigma_px", r.residual_sigma_px},
        {"axxb", {{"rms_rotation_deg", r.axxb_rms_rotation_deg},
                  {"rms_translation_mm", r.axxb_rms_translation_mm},
                  {"motions", motions}}},
        {"views", per_view},
        {"warnings", r.warnings}};
    io::WriteFileAtomically(args.json, j.dump(2) + "\n");
  }
}

}  // namespace

void AddCalibrateHandEyeCommand(CLI::App& calibrate) {
  auto args = std::make_shared<HandEyeArgs>();
  CLI::App* cmd = calibrate.add_subcommand(
      "handeye",
      "Eye-in-hand: camera on the robot flange observing a fixed chessboard; updates the "
      "vision_flange -> sensor edge of CELL.yaml");
  cmd->add_option("--cell", args->cell, "Cell file (updated in place)")->required();
  cmd->add_option("--camera", args->camera, "Camera model (.cameramodel)")->required();
  cmd->add_option("--images", args->images, "Image glob (sorted order = pose order)");
  cmd->add_option("--corners", args->corners,
                  "Corner detections instead of images (lasercell-chessboard-corners text)");
  cmd->add_option("--board", args->board,
                  "chessboard:COLSxROWS:SQUARE_MM (inner corners, mm)");
  cmd->add_option("--poses", args->poses,
                  "Robot poses base_from_flange: kuka text (metres), lasercell YAML (mm) or a "
                  "simulator records/hand_eye_images.yaml (joints)")
      ->required();
  cmd->add_option("--pose-format", args->pose_format, "auto, kuka, yaml or record")
      ->capture_default_str();
  cmd->add_option("--method", args->method,
                  "Closed form that starts the refinement: tsai-lenz, park-martin, daniilidis")
      ->capture_default_str();
  cmd->add_option("--flange-frame", args->flange_frame, "Parent frame of the edge")
      ->capture_default_str();
  cmd->add_option("--camera-frame", args->camera_frame, "Child frame of the edge")
      ->capture_default_str();
  cmd->add_option("--robot", args->robot, "Robot of a joint record (default: the record's)");
  cmd->add_option("--threads", args->threads, "Ceres threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_option("--report", args->report, "HTML report");
  cmd->add_option("--json", args->json, "JSON result");
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
