// `lasercell bench calibration`: eye-in-hand (camera on the flange, fixed chessboard) — OpenCV
// calibrateHandEye (TSAI, PARK, HORAUD, ANDREFF, DANIILIDIS) and calibrateRobotWorldHandEye
// (SHAH, LI) against lasercell's closed forms and Ceres refinement, on the same detections and
// the same per-view board poses (our PnP through the same camera model):
//  - simulated: the simulator's eye-in-hand chessboard plan (datasets/calibration_captures.hpp),
//    robot poses from the TRUE kinematics, corners = true projections + N(0, sigma) and, when
//    asked, corners detected in rendered images; error against the true flange_from_camera;
//  - real kuka2 (Ali et al. 2019): 28 images, 24x17 inner corners (25 x 18 squares of 15 mm; not
//    the 13x9 of PROVENANCE.md, which the SB detector finds as a sub-board in 3 images); no ground
//    truth, so
//    consistency: AX - XB residuals and reprojection RMS. Intrinsics: OpenCV calibrateCamera on
//    the same images (a documented stand-in), the same for every method. The set has no stated
//    licence, so it is never bundled: it is read from $LASERCELL_SHARED_DATA/handeye_kuka2 or
//    <source>/../shared/data/handeye_kuka2 (or --kuka2), and the table is skipped with a message
//    when absent.
// Debian's OpenCV 4.6 predates opencv#24871 (fixes of its Tsai, Horaud, Daniilidis).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/hand_eye.hpp"
#include "calib/kuka2_set.hpp"
#include "calib/pose_io.hpp"
#include "calib/target_detection.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/random.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/sim_profile.hpp"
#include "datasets/simulate.hpp"
#include "tools/bench.hpp"

namespace lasercell::tools {
namespace {

constexpr double kDeg = M_PI / 180.0;
namespace fs = std::filesystem;

// $LASERCELL_SHARED_DATA/handeye_kuka2, else <source>/../shared/data/handeye_kuka2.
std::string DefaultKuka2Dir() {
  const char* env = std::getenv("LASERCELL_SHARED_DATA");
  const std::string root = env != nullptr && *env != '\0'
                               ? std::string(env)
                               : std::string(LASERCELL_SOURCE_DIR) + "/../shared/data";
  return root + "/handeye_kuka2";
}

struct CalibrationBenchArgs {
  std::string kuka2_dir = DefaultKuka2Dir();
  std::string profile = "realistic";  // simulation profile (datasets/sim_profile.hpp)
  double sim_noise_px = -1;           // corner noise sigma, px; < 0: the profile's corner_sigma_px
  bool sim_render = true;
  int sim_draws = 50;
  unsigned seed = 1;
  std::string json_out;
};

struct Row {
  std::string method;
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();  // flange_from_camera
  Eigen::Isometry3d y = Eigen::Isometry3d::Identity();  // base_from_board
  bool has_y = false;                                   // the method estimates Y itself
  std::string note;
};

cv::Mat Mat3(const Eigen::Matrix3d& r) {
  cv::Mat m(3, 3, CV_64F);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.at<double>(i, j) = r(i, j);
  }
  return m;
}
cv::Mat Vec3(const Eigen::Vector3d& t) {
  cv::Mat m(3, 1, CV_64F);
  for (int i = 0; i < 3; ++i) m.at<double>(i) = t[i];
  return m;
}
Eigen::Isometry3d Pose(const cv::Mat& r, const cv::Mat& t) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) p.linear()(i, j) = r.at<double>(i, j);
    p.translation()[i] = t.at<double>(i);
  }
  return p;
}

// Every method on the same views and per-view board poses. Views whose corner numbering our
// calibration reversed (180-degree-symmetric boards) are reversed in `views` too, so that every
// method and the evaluation see the same numbering.
std::vector<Row> RunMethods(std::vector<calib::HandEyeView>& views,
                            const calib::CameraModel& camera, calib::HandEyeResult* ours) {
  *ours = calib::CalibrateHandEye(views, camera);
  for (int i : ours->reversed_views) {
    auto& c = views[static_cast<std::size_t>(i)].corners_px;
    std::reverse(c.begin(), c.end());
  }
  const std::vector<Eigen::Isometry3d>& c = ours->camera_from_board;
  std::vector<Eigen::Isometry3d> a;
  for (const auto& v : views) a.push_back(v.base_from_flange);
  std::vector<Row> rows;
  std::vector<cv::Mat> r_g2b, t_g2b, r_t2c, t_t2c, r_b2g, t_b2g;
  for (std::size_t i = 0; i < a.size(); ++i) {
    r_g2b.push_back(Mat3(a[i].linear()));
    t_g2b.push_back(Vec3(a[i].translation()));
    r_t2c.push_back(Mat3(c[i].linear()));
    t_t2c.push_back(Vec3(c[i].translation()));
    const Eigen::Isometry3d inv = a[i].inverse();
    r_b2g.push_back(Mat3(inv.linear()));
    t_b2g.push_back(Vec3(inv.translation()));
  }
  const std::pair<cv::HandEyeCalibrationMethod, const char*> he[] = {
      {cv::CALIB_HAND_EYE_TSAI, "OpenCV 4.6 calibrateHandEye TSAI (pre-#24871)"},
      {cv::CALIB_HAND_EYE_PARK, "OpenCV 4.6 calibrateHandEye PARK"},
      {cv::CALIB_HAND_EYE_HORAUD, "OpenCV 4.6 calibrateHandEye HORAUD (pre-#24871)"},
      {cv::CALIB_HAND_EYE_ANDREFF, "OpenCV 4.6 calibrateHandEye ANDREFF"},
      {cv::CALIB_HAND_EYE_DANIILIDIS, "OpenCV 4.6 calibrateHandEye DANIILIDIS (pre-#24871)"}};
  const std::pair<cv::RobotWorldHandEyeCalibrationMethod, const char*> rw[] = {
      {cv::CALIB_ROBOT_WORLD_HAND_EYE_SHAH, "OpenCV 4.6 calibrateRobotWorldHandEye SHAH"},
      {cv::CALIB_ROBOT_WORLD_HAND_EYE_LI, "OpenCV 4.6 calibrateRobotWorldHandEye LI"}};
  // OpenCV is unit-agnostic in principle, but ANDREFF and LI mix rotation and translation in one
  // linear system: run every OpenCV method with translations in mm and again in metres.
  for (const double scale : {1.0, 1e-3}) {
    const std::string unit = scale == 1.0 ? ", mm" : ", m";
    std::vector<cv::Mat> tg, tt, tb;
    for (std::size_t i = 0; i < a.size(); ++i) {
      tg.push_back(t_g2b[i] * scale);
      tt.push_back(t_t2c[i] * scale);
      tb.push_back(t_b2g[i] * scale);
    }
    for (const auto& [m, name] : he) {
      cv::Mat r, t;
      try {
        cv::calibrateHandEye(r_g2b, tg, r_t2c, tt, r, t, m);
      } catch (const cv::Exception&) {
        rows.push_back({name + unit, {}, {}, false, "threw"});
        continue;
      }
      rows.push_back({name + unit, Pose(r, t / scale), {}, false, ""});
    }
    for (const auto& [m, name] : rw) {
      cv::Mat r_b2w, t_b2w, r_g2c, t_g2c;
      try {
        cv::calibrateRobotWorldHandEye(r_t2c, tt, r_b2g, tb, r_b2w, t_b2w, r_g2c, t_g2c, m);
      } catch (const cv::Exception&) {
        rows.push_back({name + unit, {}, {}, false, "threw"});
        continue;
      }
      // base2world = board_from_base, gripper2cam = camera_from_flange.
      rows.push_back({name + unit, Pose(r_g2c, t_g2c / scale).inverse(),
                      Pose(r_b2w, t_b2w / scale).inverse(), true, ""});
    }
  }
  for (auto m : {calib::HandEyeMethod::kTsaiLenz, calib::HandEyeMethod::kParkMartin,
                 calib::HandEyeMethod::kDaniilidis}) {
    rows.push_back({"lasercell closed form " + calib::HandEyeMethodName(m),
                    calib::SolveHandEyeClosedForm(a, c, m),
                    {},
                    false,
                    ""});
  }
  rows.push_back({"lasercell Ceres refinement (X and Y, reprojection)", ours->flange_from_camera,
                  ours->base_from_board, true, ""});
  return rows;
}

struct Consistency {
  double axxb_rot_deg = 0, axxb_trans_mm = 0, reproj_rms_px = 0;
};

// AX - XB RMS over consecutive motions (PnP board poses) and reprojection RMS of every corner
// with X and Y (Y = chordal average of A_i X C_i unless the method estimated it).
Consistency Evaluate(const Row& row, const std::vector<calib::HandEyeView>& views,
                     const std::vector<Eigen::Isometry3d>& c, const calib::CameraModel& camera) {
  std::vector<Eigen::Isometry3d> a;
  for (const auto& v : views) a.push_back(v.base_from_flange);
  Consistency out;
  double sr = 0, st = 0;
  for (std::size_t i = 0; i + 1 < a.size(); ++i) {
    const calib::AxXbError e =
        calib::AxXbResidual(a[i].inverse() * a[i + 1], c[i] * c[i + 1].inverse(), row.x);
    sr += e.rotation_deg * e.rotation_deg;
    st += e.translation_mm * e.translation_mm;
  }
  out.axxb_rot_deg = std::sqrt(sr / static_cast<double>(a.size() - 1));
  out.axxb_trans_mm = std::sqrt(st / static_cast<double>(a.size() - 1));
  const Eigen::Isometry3d y = row.has_y ? row.y : calib::BaseFromBoard(a, c, row.x);
  double ss = 0;
  int n = 0;
  for (const auto& v : views) {
    const Eigen::Isometry3d camera_from_base = (v.base_from_flange * row.x).inverse();
    for (std::size_t k = 0; k < v.corners_px.size(); ++k) {
      ss += (camera.Project(camera_from_base * (y * v.corners_in_board[k])) - v.corners_px[k])
                .squaredNorm();
      ++n;
    }
  }
  out.reproj_rms_px = std::sqrt(ss / n);
  return out;
}

nlohmann::json PrintSimTable(const std::string& title, const std::vector<Row>& rows,
                             const std::vector<calib::HandEyeView>& views,
                             const calib::HandEyeResult& ours, const calib::CameraModel& camera,
                             const Eigen::Isometry3d& x_true) {
  std::printf("\n### %s\n\n", title.c_str());
  std::printf(
      "| method | rot err deg | trans err mm | AX-XB RMS deg | AX-XB RMS mm | reproj RMS px |\n"
      "|---|---|---|---|---|---|\n");
  nlohmann::json j = nlohmann::json::array();
  for (const Row& r : rows) {
    if (r.note == "threw") {
      std::printf("| %s | threw (cv::Exception) | | | | |\n", r.method.c_str());
      j.push_back({{"method", r.method}, {"threw", true}});
      continue;
    }
    const Consistency c = Evaluate(r, views, ours.camera_from_board, camera);
    const double er = RotationDistance(r.x, x_true) / kDeg;
    const double et = TranslationDistance(r.x, x_true);
    std::printf("| %s | %.5f | %.4f | %.5f | %.4f | %.4f |\n", r.method.c_str(), er, et,
                c.axxb_rot_deg, c.axxb_trans_mm, c.reproj_rms_px);
    j.push_back({{"method", r.method},
                 {"rotation_error_deg", er},
                 {"translation_error_mm", et},
                 {"axxb_rms_deg", c.axxb_rot_deg},
                 {"axxb_rms_mm", c.axxb_trans_mm},
                 {"reprojection_rms_px", c.reproj_rms_px}});
  }
  const Eigen::Vector3d sr = ours.SigmaRotationDeg(), st = ours.SigmaTranslationMm();
  std::printf(
      "\nlasercell reported 1 sigma: rotation [%.5f %.5f %.5f] deg, translation "
      "[%.4f %.4f %.4f] mm; %s\n",
      sr.x(), sr.y(), sr.z(), st.x(), st.y(), st.z(), ours.Summary().c_str());
  return j;
}

// Sanity: the truth chain closes (A_i X C_i is one board pose).
void CheckTruthChain(const std::vector<calib::HandEyeView>& views, const Eigen::Isometry3d& x_true,
                     const datasets::HandEyeImageSet& set) {
  const Eigen::Isometry3d y0 = views[0].base_from_flange * x_true * set.images[0].camera_from_board;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const Eigen::Isometry3d yi =
        views[i].base_from_flange * x_true * set.images[i].camera_from_board;
    if (TranslationDistance(yi, y0) > 1e-6) {
      throw InternalError("bench calibration: simulator truth chain does not close");
    }
  }
}

// Monte Carlo over the corner noise: RMS error per method, and the coverage of our 1 sigma.
// Draws continue `rng` / `noise` after the first table's corners.
nlohmann::json RunMonteCarlo(const CalibrationBenchArgs& args,
                             const std::vector<calib::HandEyeView>& views,
                             const datasets::HandEyeImageSet& set, const calib::CameraModel& camera,
                             const Eigen::Isometry3d& x_true, std::mt19937_64& rng,
                             std::normal_distribution<double>& noise) {
  std::vector<double> ss_r, ss_t;
  std::vector<int> threw;
  std::vector<std::string> names;
  int inside = 0, total = 0;
  for (int draw = 0; draw < args.sim_draws; ++draw) {
    std::vector<calib::HandEyeView> noisy = views;
    for (std::size_t i = 0; i < noisy.size(); ++i) {
      for (std::size_t k = 0; k < noisy[i].corners_px.size(); ++k) {
        noisy[i].corners_px[k] = set.images[i].corners_px[k] + Draws<2>(noise, rng);
      }
    }
    calib::HandEyeResult r;
    const std::vector<Row> draw_rows = RunMethods(noisy, camera, &r);
    if (names.empty()) {
      for (const Row& row : draw_rows) names.push_back(row.method);
      ss_r.assign(names.size(), 0.0);
      ss_t.assign(names.size(), 0.0);
      threw.assign(names.size(), 0);
    }
    for (std::size_t m = 0; m < draw_rows.size(); ++m) {
      if (draw_rows[m].note == "threw") {
        ++threw[m];
        continue;
      }
      ss_r[m] += std::pow(RotationDistance(draw_rows[m].x, x_true) / kDeg, 2);
      ss_t[m] += std::pow(TranslationDistance(draw_rows[m].x, x_true), 2);
    }
    const Eigen::Vector3d dr =
        RotationVectorFromMatrix(x_true.linear() * r.flange_from_camera.linear().transpose());
    const Eigen::Vector3d dt = x_true.translation() - r.flange_from_camera.translation();
    for (int k = 0; k < 6; ++k) {
      const double e = k < 3 ? dr[k] : dt[k - 3];
      inside += std::abs(e) <= std::sqrt(r.flange_from_camera_covariance(k, k)) ? 1 : 0;
      ++total;
    }
  }
  std::printf(
      "\n### Simulated cell, %d draws of N(0, %.2f px) on the true projections (same "
      "poses): RMS error over the draws\n\n| method | RMS rot err deg | RMS trans err mm "
      "| draws that threw |\n|---|---|---|---|\n",
      args.sim_draws, args.sim_noise_px);
  nlohmann::json mc = nlohmann::json::array();
  for (std::size_t m = 0; m < names.size(); ++m) {
    const int ok = args.sim_draws - threw[m];
    if (ok == 0) {
      std::printf("| %s | - | - | %d |\n", names[m].c_str(), threw[m]);
      mc.push_back({{"method", names[m]}, {"threw", threw[m]}});
      continue;
    }
    const double rr = std::sqrt(ss_r[m] / ok), rt = std::sqrt(ss_t[m] / ok);
    std::printf("| %s | %.5f | %.4f | %d |\n", names[m].c_str(), rr, rt, threw[m]);
    mc.push_back({{"method", names[m]},
                  {"rms_rotation_error_deg", rr},
                  {"rms_translation_error_mm", rt},
                  {"threw", threw[m]}});
  }
  std::printf(
      "\nlasercell 1-sigma coverage: truth inside the reported 1 sigma for %.1f %% of "
      "%d components (68.3 %% expected)\n",
      100.0 * inside / std::max(total, 1), total);
  return {{"draws", args.sim_draws},
          {"rows", mc},
          {"coverage_1sigma", static_cast<double>(inside) / std::max(total, 1)}};
}

// The detector's corner order can differ from the board's by a reversal of rows and/or
// columns (its own board frame); relabel to the simulator's order, chosen from truth. Returns
// the variant (0: as detected; bit 0 rows, bit 1 columns reversed), the relabelled corners in
// *best and their squared distance sum to the truth in *best_ss.
int RelabelCorners(const std::vector<Eigen::Vector2d>& found_px,
                   const std::vector<Eigen::Vector2d>& truth_px, int cols, int rows_n,
                   std::vector<Eigen::Vector2d>* best, double* best_ss) {
  *best_ss = 1e300;
  int best_variant = 0;
  for (int variant = 0; variant < 4; ++variant) {
    std::vector<Eigen::Vector2d> cand(found_px.size());
    double ss = 0;
    for (int rr = 0; rr < rows_n; ++rr) {
      for (int cc = 0; cc < cols; ++cc) {
        const int sr = (variant & 1) ? rows_n - 1 - rr : rr;
        const int sc = (variant & 2) ? cols - 1 - cc : cc;
        cand[static_cast<std::size_t>(rr * cols + cc)] =
            found_px[static_cast<std::size_t>(sr * cols + sc)];
      }
    }
    for (std::size_t k = 0; k < cand.size(); ++k) ss += (cand[k] - truth_px[k]).squaredNorm();
    if (ss < *best_ss) {
      *best_ss = ss;
      *best = cand;
      best_variant = variant;
    }
  }
  return best_variant;
}

// The same views with corners detected in rendered images; null when fewer than 3 boards are
// found.
nlohmann::json RunRendered(const CalibrationBenchArgs& args, const datasets::SimConfig& config,
                           const datasets::CellTruth& truth,
                           const datasets::ChessboardTarget& target,
                           const datasets::HandEyeImageSet& set,
                           const std::vector<calib::HandEyeView>& views,
                           const Eigen::Isometry3d& x_true) {
  const calib::CameraModel& camera = truth.sensor.camera;
  const datasets::ImageRenderer renderer(truth.sensor.camera);
  const calib::BoardSpec& board = target.board;
  std::vector<calib::HandEyeView> detected;
  int flipped = 0;
  double det_ss = 0, mean_ss = 0;  // all errors; each view's mean error vector, per corner
  int det_n = 0;
  for (std::size_t i = 0; i < set.images.size(); ++i) {
    const Image8 img = renderer.RenderChessboard(target, set.images[i].camera_from_board,
                                                 config.images, args.seed * 1000 + i);
    const calib::TargetDetection found = calib::DetectTarget(img, board);
    if (!found.found()) continue;
    std::vector<Eigen::Vector2d> best;
    double best_ss = 0;
    const int variant = RelabelCorners(found.corners_px, set.images[i].corners_px, board.cols,
                                       board.rows, &best, &best_ss);
    if (variant != 0) ++flipped;
    det_ss += best_ss;
    det_n += static_cast<int>(best.size());
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (std::size_t k = 0; k < best.size(); ++k) mean += best[k] - set.images[i].corners_px[k];
    mean /= static_cast<double>(best.size());
    mean_ss += mean.squaredNorm() * static_cast<double>(best.size());
    calib::HandEyeView v = views[i];
    v.corners_px = std::move(best);
    detected.push_back(v);
  }
  char title[400];
  std::snprintf(title, sizeof title,
                "Simulated cell, rendered images (the profile's image noise/blur), corners by "
                "calib::DetectTarget (findChessboardCornersSB + cornerSubPix): %zu of %zu boards "
                "found, detection "
                "error vs true projections %.3f px RMS (each view's mean shift %.3f px RMS, "
                "the rest %.3f px), %d corner orderings relabelled from truth",
                detected.size(), set.images.size(), std::sqrt(det_ss / std::max(det_n, 1)),
                std::sqrt(mean_ss / std::max(det_n, 1)),
                std::sqrt(std::max(0.0, det_ss - mean_ss) / std::max(det_n, 1)), flipped);
  if (detected.size() < 3) return nullptr;
  calib::HandEyeResult ours;
  const std::vector<Row> rows = RunMethods(detected, camera, &ours);
  return PrintSimTable(title, rows, detected, ours, camera, x_true);
}

nlohmann::json RunSimulated(CalibrationBenchArgs args) {
  datasets::SimConfig config = datasets::SimConfigForProfile(args.profile);
  config.seed = args.seed;
  if (args.sim_noise_px < 0) args.sim_noise_px = config.corner_sigma_px;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  datasets::ChessboardTarget target = config.chessboard;
  target.dark_albedo = config.albedo.chessboard_dark;
  target.light_albedo = config.albedo.chessboard_light;
  const calib::BoardSpec& board = target.board;
  const datasets::HandEyeImageSet set =
      datasets::PlanHandEyeImages(config, truth, target, args.seed * 7919 + 3);
  const calib::CameraModel& camera = truth.sensor.camera;
  const Eigen::Isometry3d x_true = truth.vision_flange_from_sensor;
  const std::vector<Eigen::Vector3d> corners = target.CornersInTarget();
  std::mt19937_64 rng(args.seed);
  std::normal_distribution<double> noise(0.0, args.sim_noise_px);
  std::vector<calib::HandEyeView> views, nominal_views;
  for (const auto& im : set.images) {
    calib::HandEyeView v;
    v.base_from_flange = truth.true_vision_robot.BaseFromFlange(im.joints_rad);
    v.corners_in_board = corners;
    for (const auto& q : im.corners_px) v.corners_px.push_back(q + Draws<2>(noise, rng));
    views.push_back(v);
    v.base_from_flange = truth.nominal_vision_robot.BaseFromFlange(im.joints_rad);
    nominal_views.push_back(v);
  }
  CheckTruthChain(views, x_true, set);
  nlohmann::json out;
  char title[400];
  std::snprintf(title, sizeof title,
                "Simulated cell (%s profile, seed %u): %zu views of a %dx%d-inner-corner board "
                "(%.0f mm), true robot poses, true projections + N(0, %.2f px)",
                config.profile.c_str(), args.seed, views.size(), board.cols, board.rows,
                board.square_mm, args.sim_noise_px);
  calib::HandEyeResult ours;
  std::vector<Row> rows = RunMethods(views, camera, &ours);
  out["synthetic_noise"] = PrintSimTable(title, rows, views, ours, camera, x_true);
  if (args.sim_draws > 0) {
    out["monte_carlo"] = RunMonteCarlo(args, views, set, camera, x_true, rng, noise);
  }
  if (args.sim_render) {
    nlohmann::json rendered = RunRendered(args, config, truth, target, set, views, x_true);
    if (!rendered.is_null()) out["rendered"] = std::move(rendered);
  }
  // What the controller reports: nominal kinematics at the commanded joints.
  std::snprintf(title, sizeof title,
                "Simulated cell, robot poses from the NOMINAL kinematics (uncalibrated joint "
                "offsets), same noisy corners as the first table");
  rows = RunMethods(nominal_views, camera, &ours);
  out["nominal_kinematics"] = PrintSimTable(title, rows, nominal_views, ours, camera, x_true);
  return out;
}

// kuka2: detections + intrinsics from the images when present; otherwise the table is skipped
// with a message (the set is not redistributable: no licence stated).
nlohmann::json RunKuka2(const CalibrationBenchArgs& args) {
  if (!calib::HasKuka2Set(args.kuka2_dir)) {
    const std::string why = "real data set handeye_kuka2 not found at " + args.kuka2_dir +
                            " (not redistributable: no licence); put the development data at "
                            "../shared/data, set LASERCELL_SHARED_DATA or pass --kuka2";
    std::printf("\n### Real kuka2: SKIPPED: %s\n", why.c_str());
    return {{"skipped", why}};
  }
  const std::string source = args.kuka2_dir + " (images; corners detected now)";
  const calib::Kuka2Set set = calib::LoadKuka2Set(args.kuka2_dir);
  if (set.error_status == calib::DetectionStatus::kUnreadable) {
    throw FileError(args.kuka2_dir, set.error);
  }
  if (!set.error.empty()) throw InputError(set.error);
  const calib::ChessboardDetections& det = set.detections;
  const calib::CameraModel& camera = *set.camera;
  const std::vector<double>& intr = camera.intrinsics();
  std::printf(
      "\nkuka2 intrinsics (stand-in): OpenCV calibrateCamera on the same 28 images, "
      "k1 k2 p1 p2 k3, RMS %.3f px: fx %.2f fy %.2f cx %.2f cy %.2f\n",
      set.calibration_rms_px, intr[0], intr[1], intr[2], intr[3]);
  const calib::RobotPoses poses =
      calib::LoadRobotPoses(args.kuka2_dir + "/RobotPosesVec.txt", "kuka");
  if (poses.base_from_flange.size() != det.images.size()) {
    throw InputError("kuka2: " + std::to_string(poses.base_from_flange.size()) + " poses but " +
                     std::to_string(det.images.size()) + " images");
  }
  const std::vector<Eigen::Vector3d> board = det.board.Corners();
  std::vector<calib::HandEyeView> views;
  for (std::size_t i = 0; i < det.images.size(); ++i) {
    views.push_back({poses.base_from_flange[i], det.corners_px[i], board});
  }
  calib::HandEyeResult ours;
  const std::vector<Row> rows = RunMethods(views, camera, &ours);
  std::printf(
      "\n### Real kuka2 (%s): %zu views, 24x17 inner corners (25x18 squares), 15 mm; "
      "no ground truth\n\n",
      source.c_str(), views.size());
  std::printf(
      "| method | AX-XB RMS deg | AX-XB RMS mm | reproj RMS px | t_X mm |\n"
      "|---|---|---|---|---|\n");
  nlohmann::json j = nlohmann::json::array();
  for (const Row& r : rows) {
    if (r.note == "threw") {
      std::printf("| %s | threw (cv::Exception) | | | |\n", r.method.c_str());
      j.push_back({{"method", r.method}, {"threw", true}});
      continue;
    }
    const Consistency c = Evaluate(r, views, ours.camera_from_board, camera);
    const Eigen::Vector3d t = r.x.translation();
    std::printf("| %s | %.4f | %.3f | %.3f | [%.1f, %.1f, %.1f] |\n", r.method.c_str(),
                c.axxb_rot_deg, c.axxb_trans_mm, c.reproj_rms_px, t.x(), t.y(), t.z());
    j.push_back({{"method", r.method},
                 {"axxb_rms_deg", c.axxb_rot_deg},
                 {"axxb_rms_mm", c.axxb_trans_mm},
                 {"reprojection_rms_px", c.reproj_rms_px}});
  }
  const Eigen::Vector3d sr = ours.SigmaRotationDeg(), st = ours.SigmaTranslationMm();
  std::printf(
      "\nlasercell reported 1 sigma: rotation [%.4f %.4f %.4f] deg, translation "
      "[%.3f %.3f %.3f] mm; %s\n",
      sr.x(), sr.y(), sr.z(), st.x(), st.y(), st.z(), ours.Summary().c_str());
  return j;
}

void RunCalibrationBench(const CalibrationBenchArgs& args) {
  datasets::ParseSimProfile(args.profile);  // bad input before any output
  std::printf(
      "lasercell bench calibration (eye-in-hand). Same detections and the same per-view "
      "PnP board poses for every method. OpenCV is Debian's 4.6, which predates the fixes "
      "of its Tsai, Horaud and Daniilidis implementations (opencv#24871). reproj RMS: "
      "every corner reprojected with the method's X and Y (Y = average of A_i X C_i for "
      "hand-eye-only methods).\n");
  nlohmann::json j = {{"format", "lasercell.bench_calibration"}, {"version", 1}};
  j["simulated"] = RunSimulated(args);
  j["kuka2"] = RunKuka2(args);
  if (!args.json_out.empty()) io::WriteFileAtomically(args.json_out, j.dump(2) + "\n");
}

}  // namespace

void AddCalibrationBenchCommand(CLI::App& bench) {
  auto args = std::make_shared<CalibrationBenchArgs>();
  CLI::App* cmd = bench.add_subcommand(
      "calibration",
      "Eye-in-hand: OpenCV calibrateHandEye / calibrateRobotWorldHandEye vs lasercell "
      "(simulated and real kuka2)");
  cmd->add_option("--kuka2", args->kuka2_dir,
                  "kuka2 images + RobotPosesVec.txt (not bundled: no licence; skipped if absent)")
      ->capture_default_str();
  cmd->add_option("--profile", args->profile,
                  "Simulation profile: realistic (corner noise 0.15 px, noisier images, DH "
                  "errors) or ideal")
      ->capture_default_str();
  cmd->add_option("--sim-noise", args->sim_noise_px,
                  "Simulated corner noise sigma, px (default: the profile's corner_sigma_px, "
                  "realistic 0.15, ideal 0.03)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", args->seed, "Simulator seed")->capture_default_str();
  cmd->add_option("--draws", args->sim_draws, "Monte-Carlo noise draws (0: none)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_flag("!--no-render", args->sim_render, "Skip the rendered-image simulated table");
  cmd->add_option("--json", args->json_out, "Also write every row as JSON");
  cmd->callback([args] { RunCalibrationBench(*args); });
}

}  // namespace lasercell::tools
