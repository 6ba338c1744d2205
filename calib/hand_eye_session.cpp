#include "calib/hand_eye_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "calib/target_detection.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/provenance.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

namespace {

namespace fs = std::filesystem;

constexpr HandEyeMethod kMethods[] = {HandEyeMethod::kTsaiLenz, HandEyeMethod::kParkMartin,
                                      HandEyeMethod::kDaniilidis};

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

void Log(const HandEyeLog& log, const std::string& line) {
  if (log) log(line);
}

// Joints of a simulator record through the robot's dynamic edge of the cell.
RobotPoses PosesFromRecord(const std::string& text, const HandEyePoseSource& source,
                           const FrameGraph& graph, const std::string& cell) {
  const HandEyeImagesRecord rec = ParseHandEyeImagesRecord(text, source.path);
  const std::string robot = source.robot.empty() ? rec.robot : source.robot;
  const DynamicEdge* edge = nullptr;
  for (const auto& e : graph.dynamic_edges()) {
    if (e.robot == robot) edge = &e;
  }
  if (!edge) {
    throw FileError(cell, "no dynamic edge for robot '" + robot +
                              "' (needed by the joints "
                              "in " +
                              source.path + ")");
  }
  RobotPoses out;
  for (std::size_t i = 0; i < rec.images.size(); ++i) {
    out.base_from_flange.push_back(
        graph.Transform(edge->parent, edge->child, {{robot, rec.joints_rad[i]}}));
    out.images.push_back(fs::path(rec.images[i]).filename().string());
  }
  if (edge->child != source.flange_frame) {
    throw InputError("--poses: the robot's flange frame is '" + edge->child + "', not '" +
                     source.flange_frame + "' (--flange-frame)");
  }
  return out;
}

}  // namespace

HandEyeMethod ParseHandEyeMethod(const std::string& name) {
  for (HandEyeMethod m : kMethods) {
    if (HandEyeMethodName(m) == name) return m;
  }
  throw OptionError("--method must be tsai-lenz, park-martin or daniilidis, not '" + name + "'");
}

BoardSpec ParseHandEyeBoard(const std::string& spec) {
  const BoardSpec board = ParseBoardSpec(spec);
  if (board.type != BoardType::kChessboard) {
    throw OptionError(
        "--board: calibrate handeye takes a chessboard:COLSxROWS:SQUARE_MM board, "
        "not '" +
        spec + "'");
  }
  return board;
}

RobotPoses LoadHandEyePoses(const HandEyePoseSource& source, const FrameGraph& graph,
                            const std::string& cell) {
  const std::string text = io::ReadFileBytes(source.path);
  if (source.format == "record" ||
      (source.format == "auto" && text.find("lasercell.hand_eye_images") != std::string::npos)) {
    return PosesFromRecord(text, source, graph, cell);
  }
  return ParseRobotPoses(text, source.path, source.format);
}

ChessboardDetections DetectHandEyeImages(const std::vector<std::string>& files,
                                         const BoardSpec& board, const RobotPoses& poses,
                                         const std::string& poses_path, const HandEyeLog& log,
                                         const ProgressCallback& progress) {
  if (files.size() != poses.base_from_flange.size()) {
    throw InputError("--images matches " + std::to_string(files.size()) + " images but --poses " +
                     poses_path + " has " + std::to_string(poses.base_from_flange.size()) +
                     " poses; give one pose per image, in sorted image order");
  }
  ChessboardDetections det;
  det.board = board;
  for (const std::string& f : files) {
    // The shared detector (SB, fallback, cornerSubPix sized to the squares, diagnostics).
    const TargetDetection d = DetectTargetInEncodedImage(io::ReadFileBytes(f), board);
    if (d.status == DetectionStatus::kUnreadable) throw FileError(f, "is not a readable image");
    det.width_px = d.width;
    det.height_px = d.height;
    det.images.push_back(fs::path(f).filename().string());
    det.corners_px.push_back(d.found() ? d.corners_px : std::vector<Eigen::Vector2d>{});
    if (!d.found()) Log(log, f + ": " + d.message);
    ReportProgress(progress, "detect", static_cast<double>(det.images.size()) / files.size());
  }
  return det;
}

ChessboardDetections LoadHandEyeCorners(const std::string& path, const std::string& board_spec) {
  ChessboardDetections det = ParseChessboardDetections(io::ReadFileBytes(path), path);
  if (!board_spec.empty()) {
    const BoardSpec b = ParseHandEyeBoard(board_spec);
    if (b.cols != det.board.cols || b.rows != det.board.rows ||
        b.square_mm != det.board.square_mm) {
      throw InputError("--board " + board_spec + " does not match the board of " + path);
    }
  }
  return det;
}

HandEyeViews MatchHandEyeViews(const ChessboardDetections& det, const RobotPoses& poses,
                               const CameraModel& camera, const std::string& corners_path,
                               const std::string& poses_path, const std::string& camera_path,
                               const HandEyeLog& log) {
  if (det.images.size() != poses.base_from_flange.size()) {
    throw InputError(std::to_string(det.images.size()) + " images in " + corners_path + " but " +
                     std::to_string(poses.base_from_flange.size()) + " poses in " + poses_path);
  }
  if (det.width_px && (det.width_px != camera.width_px() || det.height_px != camera.height_px())) {
    throw InputError("images are " + std::to_string(det.width_px) + "x" +
                     std::to_string(det.height_px) + " but --camera " + camera_path + " is " +
                     std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()));
  }
  if (!poses.images.empty()) {  // the pose file names its images: they must match, in order
    for (std::size_t i = 0; i < det.images.size(); ++i) {
      if (fs::path(poses.images[i]).filename() != fs::path(det.images[i]).filename()) {
        throw InputError("image " + std::to_string(i + 1) + " is " + det.images[i] + " but pose " +
                         std::to_string(i + 1) + " in " + poses_path + " is for " +
                         poses.images[i]);
      }
    }
  }
  const std::vector<Eigen::Vector3d> board = det.board.Corners();
  HandEyeViews out;
  for (std::size_t i = 0; i < det.images.size(); ++i) {
    if (det.corners_px[i].empty()) {
      Log(log, det.images[i] + ": board not found, view skipped");
      continue;
    }
    out.views.push_back({poses.base_from_flange[i], det.corners_px[i], board});
    out.images.push_back(det.images[i]);
  }
  return out;
}

StaticEdge HandEyeEdge(const HandEyeResult& r, const HandEyeViews& views, const HandEyeRun& run) {
  StaticEdge edge;
  edge.parent = run.flange_frame;
  edge.child = run.camera_frame;
  edge.SetParentFromChild(r.flange_from_camera);
  if (r.covariance_valid) edge.covariance = r.flange_from_camera_covariance;
  edge.provenance.tool = run.tool;
  edge.provenance.date = run.date;
  char summary[200];
  std::snprintf(
      summary, sizeof summary,
      "reprojection rms %.4f px over %d corners in %zu views; AX-XB rms %.4f deg / %.4f mm",
      r.reprojection_rms_px, r.observations, views.views.size(), r.axxb_rms_rotation_deg,
      r.axxb_rms_translation_mm);
  edge.provenance.residual_summary = summary;
  return edge;
}

nlohmann::json HandEyeJson(const HandEyeResult& r, const HandEyeViews& v, const HandEyeRun& run) {
  std::vector<Eigen::Isometry3d> a;
  for (const HandEyeView& view : v.views) a.push_back(view.base_from_flange);
  nlohmann::json closed = nlohmann::json::object();
  for (HandEyeMethod m : kMethods) {
    closed[HandEyeMethodName(m)] = json::Pose(SolveHandEyeClosedForm(a, r.camera_from_board, m));
  }
  nlohmann::json per_view = nlohmann::json::array();
  for (std::size_t i = 0; i < v.views.size(); ++i) {
    per_view.push_back({{"image", v.images[i]},
                        {"reprojection_rms_px", r.view_rms_px[i]},
                        {"closure_rotation_deg", r.view_closure[i].rotation_deg},
                        {"closure_translation_mm", r.view_closure[i].translation_mm}});
  }
  nlohmann::json motions = nlohmann::json::array();
  for (const auto& e : r.axxb) {
    motions.push_back({{"rotation_deg", e.rotation_deg}, {"translation_mm", e.translation_mm}});
  }
  return {
      {"format", "lasercell.hand_eye"},
      {"version", 1},
      {"tool", run.tool},
      {"date", run.date},
      {"camera", run.camera_path},
      {"poses", run.poses_path},
      {"frames", {{"parent", run.flange_frame}, {"child", run.camera_frame}}},
      {"flange_from_camera", json::Pose(r.flange_from_camera)},
      {"flange_from_camera_sigma", json::Sigma(r.flange_from_camera_covariance)},
      {"flange_from_camera_covariance", json::Rows(r.flange_from_camera_covariance)},
      {"base_from_board", json::Pose(r.base_from_board)},
      {"base_from_board_sigma", json::Sigma(r.base_from_board_covariance)},
      {"base_from_board_covariance", json::Rows(r.base_from_board_covariance)},
      {"covariance_note",
       std::string("6x6 over [rotation vector rad (left perturbation); translation mm], "
                   "scaled by the residual variance; ") +
           (r.camera_uncertainty_included
                ? "plus the camera's intrinsics uncertainty; robot poses taken as exact"
                : "intrinsics (" + r.camera_uncertainty_note + ") and robot poses taken as exact")},
      {"camera_uncertainty_included", r.camera_uncertainty_included},
      {"flange_from_camera_sigma_camera_part", json::Sigma(r.flange_from_camera_camera_covariance)},
      {"covariance_valid", r.covariance_valid},
      {"initialisation", HandEyeMethodName(run.method)},
      {"closed_forms", closed},
      {"converged", r.converged},
      {"iterations", r.iterations},
      {"observations", r.observations},
      {"reprojection_rms_px", r.reprojection_rms_px},
      {"residual_sigma_px", r.residual_sigma_px},
      {"axxb",
       {{"rms_rotation_deg", r.axxb_rms_rotation_deg},
        {"rms_translation_mm", r.axxb_rms_translation_mm},
        {"motions", motions}}},
      {"views", per_view},
      {"warnings", r.warnings}};
}

report::HtmlReport HandEyeReport(const HandEyeResult& r, const HandEyeViews& v,
                                 const HandEyeRun& run) {
  const std::vector<std::string>& used = v.images;
  const std::string edge_name = run.flange_frame + "_from_" + run.camera_frame;
  report::HtmlReport rep("lasercell calibrate handeye");
  rep.AddParagraph(r.Summary());
  for (const auto& w : r.warnings) rep.AddWarning(w);
  rep.AddHeading("Result");
  rep.AddKeyValues(
      {{edge_name, PoseToFileNotation(r.flange_from_camera)},
       {"base_from_board", PoseToFileNotation(r.base_from_board)},
       {"reprojection RMS", Fmt("%.4f px", r.reprojection_rms_px)},
       {"residual sigma (scales the covariance)", Fmt("%.4f px", r.residual_sigma_px)},
       {"AX-XB RMS (consecutive motions)", Fmt("%.4f deg", r.axxb_rms_rotation_deg) + " / " +
                                               Fmt("%.4f mm", r.axxb_rms_translation_mm)},
       {"views / corners", std::to_string(v.views.size()) + " / " + std::to_string(r.observations)},
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
    rows.push_back(
        {used[i], Fmt("%.4f", r.view_rms_px[i]), Fmt("%.4f", rot[i]), Fmt("%.4f", trans[i])});
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
  rep.AddHeading("Covariance of " + edge_name);
  rep.AddParagraph(
      "6x6 over [rotation vector rad (left perturbation); translation mm], scaled by "
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
  rep.AddKeyValues({{"1 sigma rotation (deg)",
                     Fmt("%.5f", sr.x()) + ", " + Fmt("%.5f", sr.y()) + ", " + Fmt("%.5f", sr.z())},
                    {"1 sigma translation (mm)", Fmt("%.4f", st.x()) + ", " + Fmt("%.4f", st.y()) +
                                                     ", " + Fmt("%.4f", st.z())}});
  return rep;
}

HandEyeSession CalibrateHandEyeFromFiles(const HandEyeInputs& inputs, const FrameGraph& cell,
                                         const std::string& cell_name, const HandEyeLog& log) {
  if (inputs.images.empty() == inputs.corners.empty()) {
    throw OptionError("hand-eye inputs: give either board images or a corners file, not " +
                      std::string(inputs.images.empty() ? "neither" : "both"));
  }
  const HandEyeMethod method = ParseHandEyeMethod(inputs.method);
  const CameraModel camera = LoadCameraModel(inputs.camera);
  const RobotPoses poses = LoadHandEyePoses(inputs.poses, cell, cell_name);
  ChessboardDetections detections;
  if (!inputs.corners.empty()) {
    detections = LoadHandEyeCorners(inputs.corners, inputs.board);
  } else {
    if (inputs.board.empty()) throw OptionError("hand-eye inputs: images need a board spec");
    detections = DetectHandEyeImages(inputs.images, ParseHandEyeBoard(inputs.board), poses,
                                     inputs.poses.path, log, inputs.progress);
  }
  HandEyeSession session;
  session.views = MatchHandEyeViews(detections, poses, camera, inputs.corners, inputs.poses.path,
                                    inputs.camera, log);
  HandEyeOptions options;
  options.initialisation = method;
  options.threads = inputs.threads;
  session.result = CalibrateHandEye(session.views.views, camera, options);
  session.run = HandEyeRun{
      inputs.camera, inputs.poses.path, inputs.poses.flange_frame, inputs.poses.camera_frame,
      method,        inputs.tool,       UtcTimestampIso()};
  session.edge = HandEyeEdge(session.result, session.views, session.run);
  ReportProgress(inputs.progress, "solve", 1.0);
  return session;
}

}  // namespace lasercell::calib
