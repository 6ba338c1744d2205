#include "calib/intrinsics.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <sstream>

#include "calib/cost_functions/reprojection.hpp"
#include "core/error.hpp"
#include "core/format.hpp"

namespace lasercell::calib {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Pose6 {
  double v[6] = {0, 0, 0, 0, 0, 0};  // angle-axis (rad), translation (mm)
};

Eigen::Isometry3d ToIsometry(const Pose6& p) {
  double R[9];
  ceres::AngleAxisToRotationMatrix(p.v, R);  // column-major
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Map<const Eigen::Matrix3d>(R);
  T.translation() = Eigen::Vector3d(p.v[3], p.v[4], p.v[5]);
  return T;
}

// State of the optimisation shared by the stages.
struct State {
  const BoardSpec* board = nullptr;
  const IntrinsicsOptions* options = nullptr;
  int width = 0, height = 0;
  std::unique_ptr<CameraModel> lens;  // lens model (intrinsics values unused by the costs)
  IntrinsicsLayout layout;
  std::vector<double> free;       // optimised intrinsics
  std::vector<Pose6> poses;       // per used view
  std::vector<int> view_of_pose;  // index into the input views
  double warp[2] = {0, 0};
  Eigen::MatrixXd regularization;  // rows x NumFree (splined), empty otherwise
  // Observations of the used views: (pose index, corner id, pixel), inlier flag.
  struct Obs {
    int pose;
    int id;
    Eigen::Vector2d px;
    bool outlier = false;
  };
  std::vector<Obs> obs;
};

std::vector<double> FullIntrinsics(const State& s) {
  std::vector<double> full(s.layout.num_full);
  s.layout.ToFull(s.free.data(), full.data());
  return full;
}

Eigen::Vector2d Residual(const State& s, const std::vector<double>& full, const State::Obs& o) {
  const Eigen::Vector3d p_in_board =
      s.board->Corner(o.id) +
      Eigen::Vector3d(0, 0,
                      BoardWarpBasis(s.board->Corner(o.id), s.board->Extent())
                          .dot(Eigen::Vector2d(s.warp[0], s.warp[1])));
  const Eigen::Vector3d p_in_camera = ToIsometry(s.poses[o.pose]) * p_in_board;
  return s.lens->ProjectWithIntrinsics(full.data(), p_in_camera, nullptr, nullptr) - o.px;
}

struct SolveReport {
  bool converged = false;
  std::string message;
  int iterations = 0;
};

// Marginal covariance of the intrinsics and pose blocks (in that order), (J'J)^-1 restricted to
// them (marginal over the warp), unscaled. The
// columns are scaled to unit norm first (fx ~ 1e3 px and k6 ~ 1e-3 differ by orders of
// magnitude; unscaled, J'J looks rank deficient when it is not), then inverted through the SVD
// of the scaled J; empty when its condition number (> 1e15, rounding level) shows a true rank
// deficiency; OPENCV8's rational distortion alone reaches 1e13-1e14 on ordinary data.
Eigen::MatrixXd MarginalCovariance(State& s, ceres::Problem& problem) {
  std::vector<double*> blocks = {s.free.data()};
  for (Pose6& p : s.poses) {
    if (problem.HasParameterBlock(p.v) && !problem.IsParameterBlockConstant(p.v)) {
      blocks.push_back(p.v);
    }
  }
  if (problem.HasParameterBlock(s.warp)) blocks.push_back(s.warp);
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = blocks;
  eo.apply_loss_function = false;
  eo.num_threads = s.options->threads;
  ceres::CRSMatrix crs;
  if (!problem.Evaluate(eo, nullptr, nullptr, nullptr, &crs)) return {};
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) j(r, crs.cols[k]) = crs.values[k];
  }
  Eigen::VectorXd scale(crs.num_cols);
  for (int c = 0; c < crs.num_cols; ++c) {
    const double n = j.col(c).norm();
    scale(c) = n > 0 ? 1.0 / n : 0.0;
  }
  const Eigen::MatrixXd js = j * scale.asDiagonal();
  // SVD of the scaled Jacobian (not of J'J: its squared condition number would lose the weakly
  // determined directions of, e.g., OPENCV8's rational distortion to rounding).
  // QR first, then a Jacobi SVD of the small triangular factor: accurate down to the smallest
  // singular values (Eigen's BDCSVD deflates them to exact zeros).
  if (js.rows() < js.cols()) return {};
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(js);
  const Eigen::MatrixXd rfac = qr.matrixQR().topRows(js.cols()).triangularView<Eigen::Upper>();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(rfac, Eigen::ComputeFullV);
  const Eigen::VectorXd sv = svd.singularValues();
  if (sv.size() == 0 || !(sv(sv.size() - 1) > 1e-15 * sv(0))) return {};
  // Columns of the intrinsics and the poses (a held pose has none; then only the intrinsics).
  int n = s.layout.NumFree();
  if (static_cast<int>(blocks.size()) >= 1 + static_cast<int>(s.poses.size())) {
    n += 6 * static_cast<int>(s.poses.size());
  }
  const Eigen::MatrixXd vi = svd.matrixV().topRows(n);
  const Eigen::MatrixXd inv = vi * sv.cwiseAbs2().cwiseInverse().asDiagonal() * vi.transpose();
  return scale.head(n).asDiagonal() * inv * scale.head(n).asDiagonal();
}

// Builds the Ceres problem over the inliers and solves it. hold_poses: poses constant.
// covariance: when non-null, filled with the marginal covariance of `free` (unscaled), or left
// empty when Ceres cannot compute it (rank deficient).
SolveReport Solve(State& s, bool hold_poses, Eigen::MatrixXd* covariance) {
  const IntrinsicsOptions& opt = *s.options;
  ceres::Problem problem;
  const bool warp = opt.estimate_board_warp;
  for (const State::Obs& o : s.obs) {
    if (o.outlier) continue;
    auto* cost = new ReprojectionCost(s.lens.get(), s.layout, s.board->Corner(o.id), o.px, warp,
                                      s.board->Extent());
    if (warp) {
      problem.AddResidualBlock(cost, nullptr, s.free.data(), s.poses[o.pose].v, s.warp);
    } else {
      problem.AddResidualBlock(cost, nullptr, s.free.data(), s.poses[o.pose].v);
    }
  }
  if (s.regularization.size() > 0) {
    problem.AddResidualBlock(new LinearRegularizationCost(s.regularization), nullptr,
                             s.free.data());
  }
  if (hold_poses) {
    for (Pose6& p : s.poses) {
      if (problem.HasParameterBlock(p.v)) problem.SetParameterBlockConstant(p.v);
    }
  }
  ceres::Solver::Options so;
  // Few intrinsics: dense QR of the whole Jacobian, robust to the near-degenerate directions of
  // OPENCV8's rational distortion (the normal equations of a Schur solver lose them and make
  // Ceres log Cholesky failures). Splined models (hundreds of knots): Schur elimination of the
  // poses, the regularisation keeps the reduced system definite.
  so.linear_solver_type = s.regularization.size() > 0 ? ceres::DENSE_SCHUR : ceres::DENSE_QR;
  so.max_num_iterations = opt.max_iterations;
  so.num_threads = opt.threads;
  so.function_tolerance = 1e-10;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  SolveReport report;
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  report.message = summary.message;
  report.iterations = static_cast<int>(summary.iterations.size());
  if (covariance != nullptr) *covariance = MarginalCovariance(s, problem);
  return report;
}

// Zhang 2000 sec. 3.1 with the principal point at the image centre and fx = fy = f: each
// homography H = [h1 h2 h3] gives h1' B h2 = 0 and h1' B h1 = h2' B h2 with B = diag(a, a, 1),
// a = 1 / f^2 (pixels relative to the centre). Returns 0 when the views do not determine f.
double FocalFromHomographies(const std::vector<Eigen::Matrix3d>& homographies) {
  double num = 0, den = 0;
  for (Eigen::Matrix3d h : homographies) {
    h /= h.norm();
    const Eigen::Vector3d h1 = h.col(0), h2 = h.col(1);
    const double a1 = h1.x() * h2.x() + h1.y() * h2.y();
    const double b1 = h1.z() * h2.z();
    const double a2 = h1.x() * h1.x() + h1.y() * h1.y() - h2.x() * h2.x() - h2.y() * h2.y();
    const double b2 = h1.z() * h1.z() - h2.z() * h2.z();
    num += a1 * b1 + a2 * b2;
    den += a1 * a1 + a2 * a2;
  }
  if (!(den > 0)) return 0;
  const double a = -num / den;
  return a > 0 ? 1.0 / std::sqrt(a) : 0.0;
}

Eigen::MatrixXd SplineRegularization(const State& s, int nx, int ny, double f) {
  const IntrinsicsOptions& opt = *s.options;
  const int n_free = s.layout.NumFree();
  const int first_knot = n_free - 2 * nx * ny;  // knots follow the core in mrcal's vector
  auto col = [&](int ix, int iy, int k) { return first_knot + 2 * (iy * nx + ix) + k; };
  std::vector<Eigen::RowVectorXd> rows;
  const double wv = opt.spline_value_weight * f;
  const double ws = opt.spline_smoothness_weight * f;
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      for (int k = 0; k < 2; ++k) {
        if (wv > 0) {
          Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(n_free);
          r(col(ix, iy, k)) = wv;
          rows.push_back(r);
        }
        if (ws > 0 && ix > 0 && ix + 1 < nx) {
          Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(n_free);
          r(col(ix - 1, iy, k)) = ws;
          r(col(ix, iy, k)) = -2 * ws;
          r(col(ix + 1, iy, k)) = ws;
          rows.push_back(r);
        }
        if (ws > 0 && iy > 0 && iy + 1 < ny) {
          Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(n_free);
          r(col(ix, iy - 1, k)) = ws;
          r(col(ix, iy, k)) = -2 * ws;
          r(col(ix, iy + 1, k)) = ws;
          rows.push_back(r);
        }
      }
    }
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), n_free);
  for (std::size_t i = 0; i < rows.size(); ++i) a.row(static_cast<Eigen::Index>(i)) = rows[i];
  return a;
}

// Solve, drop outliers, re-solve until none is new. Returns the last report.
SolveReport SolveWithOutliers(State& s, IntrinsicsResult& result) {
  SolveReport report = Solve(s, false, nullptr);
  result.iterations += report.iterations;
  for (int round = 0; round < s.options->max_outlier_rounds; ++round) {
    const std::vector<double> full = FullIntrinsics(s);
    double ssr = 0;
    int n = 0;
    std::vector<double> norms(s.obs.size(), 0.0);
    for (std::size_t i = 0; i < s.obs.size(); ++i) {
      norms[i] = Residual(s, full, s.obs[i]).norm();
      if (!s.obs[i].outlier) {
        ssr += norms[i] * norms[i];
        ++n;
      }
    }
    const int dof = 2 * n - s.layout.NumFree() - 6 * static_cast<int>(s.poses.size());
    if (dof <= 0) break;
    const double sigma = std::sqrt(ssr / dof);
    bool changed = false;
    for (std::size_t i = 0; i < s.obs.size(); ++i) {
      const bool out = norms[i] > s.options->outlier_threshold_sigma * sigma;
      if (out && !s.obs[i].outlier) changed = true;
      s.obs[i].outlier = s.obs[i].outlier || out;
    }
    if (!changed) break;
    ++result.outlier_rounds;
    report = Solve(s, false, nullptr);
    result.iterations += report.iterations;
  }
  return report;
}

void SetLens(State& s, const std::string& name, const std::vector<double>& full) {
  s.lens = std::make_unique<CameraModel>(name, full, s.width, s.height);
  s.layout.num_full = s.lens->NumIntrinsics();
  s.free = s.layout.FromFull(full);
}

std::vector<std::string> IntrinsicNames(const IntrinsicsOptions& o, int n_full) {
  std::vector<std::string> names = {"fx", "fy", "cx", "cy"};
  if (o.model == LensModelKind::kSplined) {
    for (int i = 4; i < n_full; ++i) {
      names.push_back("knot" + std::to_string((i - 4) / 2) + ((i - 4) % 2 == 0 ? "_ux" : "_uy"));
    }
    return names;
  }
  const char* d[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"};
  for (int i = 4; i < n_full; ++i) names.push_back(d[i - 4]);
  return names;
}

}  // namespace

void IntrinsicsOptions::Check() const {
  if (spline_order != 2 && spline_order != 3) {
    throw OptionError("IntrinsicsOptions.spline_order must be 2 or 3");
  }
  if (spline_nx < 4 || spline_ny < 4 || spline_nx > 60 || spline_ny > 60) {
    throw OptionError("IntrinsicsOptions.spline_nx and spline_ny must be in [4, 60]");
  }
  if (spline_fov_x_deg < 0 || spline_fov_x_deg >= 179) {
    throw OptionError("IntrinsicsOptions.spline_fov_x_deg must be in [0, 179) deg (0: automatic)");
  }
  if (spline_value_weight < 0 || spline_smoothness_weight < 0 ||
      (spline_value_weight == 0 && spline_smoothness_weight == 0)) {
    throw OptionError(
        "IntrinsicsOptions.spline_value_weight / spline_smoothness_weight must be >= 0 and not "
        "both 0 (a splined model needs regularisation)");
  }
  if (!(outlier_threshold_sigma >= 2)) {
    throw OptionError("IntrinsicsOptions.outlier_threshold_sigma must be >= 2");
  }
  if (max_outlier_rounds < 0)
    throw OptionError("IntrinsicsOptions.max_outlier_rounds must be >= 0");
  if (min_views < 2) throw OptionError("IntrinsicsOptions.min_views must be >= 2");
  if (min_corners_per_view < 4) {
    throw OptionError("IntrinsicsOptions.min_corners_per_view must be >= 4");
  }
  if (max_iterations < 1) throw OptionError("IntrinsicsOptions.max_iterations must be >= 1");
  if (uncertainty_grid_x < 1 || uncertainty_grid_y < 1) {
    throw OptionError("IntrinsicsOptions.uncertainty_grid_x/y must be >= 1");
  }
  if (uncertainty_range_mm < 0) {
    throw OptionError("IntrinsicsOptions.uncertainty_range_mm must be >= 0 (0: median distance)");
  }
  if (!(max_focal_relative_sigma > 0)) {
    throw OptionError("IntrinsicsOptions.max_focal_relative_sigma must be > 0");
  }
  if (min_tilt_spread_deg < 0)
    throw OptionError("IntrinsicsOptions.min_tilt_spread_deg must be >= 0");
  if (threads < 1) throw OptionError("IntrinsicsOptions.threads must be >= 1");
}

LensModelKind ParseLensModelKind(const std::string& name, const std::string& field) {
  if (name == "opencv5") return LensModelKind::kOpenCV5;
  if (name == "opencv8") return LensModelKind::kOpenCV8;
  if (name == "splined") return LensModelKind::kSplined;
  throw OptionError(field + " '" + name + "' is not one of opencv5, opencv8, splined");
}

std::string MrcalLensModelName(const IntrinsicsOptions& options, double fov_x_deg) {
  switch (options.model) {
    case LensModelKind::kOpenCV5:
      return "LENSMODEL_OPENCV5";
    case LensModelKind::kOpenCV8:
      return "LENSMODEL_OPENCV8";
    case LensModelKind::kSplined:
      return "LENSMODEL_SPLINED_STEREOGRAPHIC_order=" + std::to_string(options.spline_order) +
             "_Nx=" + std::to_string(options.spline_nx) +
             "_Ny=" + std::to_string(options.spline_ny) +
             "_fov_x_deg=" + std::to_string(static_cast<int>(std::ceil(fov_x_deg)));
  }
  return "";
}

namespace {

// Validate and select views: a ViewResult per view (used, or why not); InputError for
// inconsistent inputs and for fewer than min_views usable views.
void SelectViews(const std::vector<BoardView>& views, const BoardSpec& board, int width_px,
                 int height_px, const IntrinsicsOptions& options, IntrinsicsResult& result) {
  std::vector<std::string> problems;
  for (std::size_t v = 0; v < views.size(); ++v) {
    const BoardView& view = views[v];
    ViewResult vr;
    vr.name = view.name.empty() ? "view " + std::to_string(v) : view.name;
    if (view.corners_px.size() != view.corner_ids.size()) {
      throw InputError("camera calibration: " + vr.name + " has " +
                       std::to_string(view.corners_px.size()) + " corners but " +
                       std::to_string(view.corner_ids.size()) + " corner ids");
    }
    for (std::size_t i = 0; i < view.corners_px.size(); ++i) {
      const Eigen::Vector2d& q = view.corners_px[i];
      if (view.corner_ids[i] < 0 || view.corner_ids[i] >= board.NumCorners()) {
        throw InputError("camera calibration: " + vr.name + " has corner id " +
                         std::to_string(view.corner_ids[i]) + " outside the board " +
                         board.ToString());
      }
      if (!q.allFinite() || q.x() < -0.5 || q.y() < -0.5 || q.x() > width_px - 0.5 ||
          q.y() > height_px - 0.5) {
        throw InputError("camera calibration: " + vr.name + " has a corner at (" +
                         FormatFixed(q.x(), 3) + ", " + FormatFixed(q.y(), 3) + ") outside the " +
                         std::to_string(width_px) + "x" + std::to_string(height_px) + " image");
      }
    }
    if (static_cast<int>(view.corners_px.size()) < options.min_corners_per_view) {
      vr.rejection_reason = "only " + std::to_string(view.corners_px.size()) + " corners (need " +
                            std::to_string(options.min_corners_per_view) + ")";
      problems.push_back(vr.name + ": " + vr.rejection_reason);
    } else {
      vr.used = true;
    }
    result.views.push_back(vr);
  }
  int num_used = 0;
  for (const ViewResult& v : result.views) num_used += v.used ? 1 : 0;
  if (num_used < options.min_views) {
    std::string msg = "camera calibration needs at least " + std::to_string(options.min_views) +
                      " views with a detected board, got " + std::to_string(num_used) + " of " +
                      std::to_string(views.size());
    if (!problems.empty()) {
      msg += " (";
      for (std::size_t i = 0; i < problems.size() && i < 8; ++i) {
        msg += (i ? "; " : "") + problems[i];
      }
      if (problems.size() > 8) msg += "; ...";
      msg += ")";
    }
    throw InputError(msg + ": add views of the board at varied tilts covering the image");
  }
}

// Initial focal length and poses (pinhole, principal point at the centre): fills the poses
// and observations of `s`; returns the focal length.
double InitialPoses(const std::vector<BoardView>& views, const BoardSpec& board, int width_px,
                    int height_px, const IntrinsicsOptions& options, State& s,
                    IntrinsicsResult& result) {
  const double cx0 = 0.5 * (width_px - 1), cy0 = 0.5 * (height_px - 1);
  std::vector<Eigen::Matrix3d> homographies;
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (!result.views[v].used) continue;
    std::vector<cv::Point2f> src, dst;
    for (std::size_t i = 0; i < views[v].corners_px.size(); ++i) {
      const Eigen::Vector3d c = board.Corner(views[v].corner_ids[i]);
      src.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
      dst.emplace_back(static_cast<float>(views[v].corners_px[i].x() - cx0),
                       static_cast<float>(views[v].corners_px[i].y() - cy0));
    }
    const cv::Mat h = cv::findHomography(src, dst, 0);
    if (h.empty()) continue;
    Eigen::Matrix3d he;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) he(r, c) = h.at<double>(r, c);
    }
    homographies.push_back(he);
  }
  double f0 = FocalFromHomographies(homographies);
  const double size = std::max(width_px, height_px);
  if (!(f0 > 0.1 * size && f0 < 50 * size)) {
    result.warnings.push_back(
        "the board homographies do not determine an initial focal length (views nearly "
        "parallel?); started from f = image size");
    f0 = size;
  }
  const cv::Matx33d K(f0, 0, cx0, 0, f0, cy0, 0, 0, 1);
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (!result.views[v].used) continue;
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;
    for (std::size_t i = 0; i < views[v].corners_px.size(); ++i) {
      const Eigen::Vector3d c = board.Corner(views[v].corner_ids[i]);
      obj.emplace_back(c.x(), c.y(), 0.0);
      img.emplace_back(views[v].corners_px[i].x(), views[v].corners_px[i].y());
    }
    cv::Vec3d rvec, tvec;
    bool ok = false;
    try {
      ok = cv::solvePnP(obj, img, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_IPPE);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || tvec[2] <= 0) {
      result.views[v].used = false;
      result.views[v].rejection_reason = "no initial board pose (corners degenerate?)";
      continue;
    }
    Pose6 p;
    for (int k = 0; k < 3; ++k) {
      p.v[k] = rvec[k];
      p.v[3 + k] = tvec[k];
    }
    const int pose_index = static_cast<int>(s.poses.size());
    s.poses.push_back(p);
    s.view_of_pose.push_back(static_cast<int>(v));
    for (std::size_t i = 0; i < views[v].corners_px.size(); ++i) {
      s.obs.push_back({pose_index, views[v].corner_ids[i], views[v].corners_px[i], false});
    }
  }
  if (static_cast<int>(s.poses.size()) < options.min_views) {
    throw InputError("camera calibration: only " + std::to_string(s.poses.size()) +
                     " views have a usable board pose (need " + std::to_string(options.min_views) +
                     ")");
  }

  return f0;
}

// Stage 1: OpenCV-family model (the final one, or the start of a splined fit); then, for a
// splined model, the knots from the OPENCV8 fit.
void FitLens(State& s, const IntrinsicsOptions& options, double f0, double cx0, double cy0,
             IntrinsicsResult& result) {
  const int width_px = s.width, height_px = s.height;
  const LensModelKind first =
      options.model == LensModelKind::kSplined ? LensModelKind::kOpenCV8 : options.model;
  IntrinsicsOptions first_options = options;
  first_options.model = first;
  {
    const int n_dist = first == LensModelKind::kOpenCV5 ? 5 : 8;
    std::vector<double> full = {f0, f0, cx0, cy0};
    full.resize(4 + n_dist, 0.0);
    SetLens(s, MrcalLensModelName(first_options, 0), full);
  }
  SolveWithOutliers(s, result);

  if (options.model == LensModelKind::kSplined) {
    const std::vector<double> cv8 = FullIntrinsics(s);
    double fov = options.spline_fov_x_deg;
    if (fov == 0) {
      // Horizontal field of view of the OPENCV8 camera (unprojected image edges), +20 %.
      const CameraModel cam(s.lens->lensmodel(), cv8, width_px, height_px);
      const Eigen::Vector3d l = cam.Unproject({0, cy0}), r = cam.Unproject({width_px - 1.0, cy0});
      fov = 1.2 * (std::atan2(std::abs(l.x()), l.z()) + std::atan2(std::abs(r.x()), r.z())) *
            180.0 / kPi;
      fov = std::min(fov, 170.0);
    }
    const std::string name = MrcalLensModelName(options, fov);
    mrcal_lensmodel_t lens;
    if (!mrcal_lensmodel_from_name(&lens, name.c_str())) {
      throw InternalError("mrcal does not parse its lens model name " + name);
    }
    std::vector<double> full = {cv8[0], cv8[1], cv8[2], cv8[3]};
    full.resize(mrcal_lensmodel_num_params(&lens), 0.0);  // knots at zero: pure stereographic
    SetLens(s, name, full);
    s.regularization = SplineRegularization(s, options.spline_nx, options.spline_ny, cv8[0]);
    const SolveReport held = Solve(s, true, nullptr);  // knots with the OPENCV8 poses
    result.iterations += held.iterations;
    SolveWithOutliers(s, result);
  }
}

// Final statistics and covariance: the last solve (covariance of [free intrinsics, poses],
// unscaled, in *cov_all), the camera, residuals per corner and view, RMS and sigma.
void FinalStatistics(State& s, std::size_t num_views, const IntrinsicsOptions& options,
                     Eigen::MatrixXd* cov_all, IntrinsicsResult& result) {
  const SolveReport final_report = Solve(s, false, cov_all);
  result.iterations += final_report.iterations;
  result.converged = final_report.converged;
  result.termination = final_report.message;
  const std::vector<double> full = FullIntrinsics(s);
  result.camera.emplace(s.lens->lensmodel(), full, s.width, s.height);
  result.intrinsic_names = IntrinsicNames(options, s.layout.num_full);
  result.board_warp_mm = Eigen::Vector2d(s.warp[0], s.warp[1]);

  double ssr = 0;
  std::vector<double> view_ssr(num_views, 0.0);
  std::vector<int> view_n(num_views, 0), view_out(num_views, 0);
  for (const State::Obs& o : s.obs) {
    const int v = s.view_of_pose[o.pose];
    const Eigen::Vector2d r = Residual(s, full, o);
    CornerResidual cr;
    cr.view = v;
    cr.corner_id = o.id;
    cr.observed_px = o.px;
    cr.residual_px = r;
    cr.outlier = o.outlier;
    result.corners.push_back(cr);
    if (o.outlier) {
      ++view_out[v];
      ++result.num_outliers;
      continue;
    }
    ssr += r.squaredNorm();
    view_ssr[v] += r.squaredNorm();
    ++view_n[v];
    ++result.num_corners;
  }
  result.num_parameters = s.layout.NumFree() + 6 * static_cast<int>(s.poses.size()) +
                          (options.estimate_board_warp ? 2 : 0);
  const int dof = 2 * result.num_corners - result.num_parameters;
  result.rms_px = result.num_corners > 0 ? std::sqrt(ssr / result.num_corners) : 0.0;
  result.residual_sigma_px = dof > 0 ? std::sqrt(ssr / dof) : 0.0;
  if (dof <= 0) {
    result.warnings.push_back(
        "as many parameters as measurements: no residual to estimate "
        "the noise from");
  }
  for (std::size_t p = 0; p < s.poses.size(); ++p) {
    ViewResult& vr = result.views[s.view_of_pose[p]];
    const int v = s.view_of_pose[p];
    vr.num_corners = view_n[v];
    vr.num_outliers = view_out[v];
    vr.rms_px = view_n[v] > 0 ? std::sqrt(view_ssr[v] / view_n[v]) : 0.0;
  }
}

// The focal length is not observable: flagged, the first reason kept, every reason warned.
void MarkFocalUnobservable(const std::string& why, IntrinsicsResult* result) {
  result->focal_observable = false;
  if (result->focal_problem.empty()) result->focal_problem = why;
  result->warnings.push_back(why);
}

// Views: pose, tilt and the spread of the board normals (parallel views leave the focal length
// unobservable). Returns the board distances.
std::vector<double> ViewGeometry(const State& s, const IntrinsicsOptions& options,
                                 IntrinsicsResult& result) {
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> distances;
  for (std::size_t p = 0; p < s.poses.size(); ++p) {
    ViewResult& vr = result.views[s.view_of_pose[p]];
    vr.camera_from_board = ToIsometry(s.poses[p]);
    Eigen::Vector3d n = vr.camera_from_board.linear().col(2);
    if (n.z() < 0) n = -n;
    vr.tilt_deg = std::acos(std::clamp(n.z(), -1.0, 1.0)) * 180.0 / kPi;
    normals.push_back(n);
    distances.push_back(vr.camera_from_board.translation().norm());
  }
  Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
  for (const auto& n : normals) mean_normal += n;
  mean_normal.normalize();
  for (const auto& n : normals) {
    result.tilt_spread_deg = std::max(
        result.tilt_spread_deg, std::acos(std::clamp(n.dot(mean_normal), -1.0, 1.0)) * 180.0 / kPi);
  }
  if (result.tilt_spread_deg < options.min_tilt_spread_deg) {
    MarkFocalUnobservable("all views nearly parallel: every board normal lies within " +
                              FormatFixed(result.tilt_spread_deg, 1) + " deg of their mean (need " +
                              FormatFixed(options.min_tilt_spread_deg, 1) +
                              "); the focal length is not observable from parallel views: tilt "
                              "the board",
                          &result);
  }
  return distances;
}

// Covariance of the full intrinsics (scaled by the residual variance), the focal length's
// observability, and the remaining warnings.
void IntrinsicsCovariance(const State& s, const Eigen::MatrixXd& cov_all,
                          const IntrinsicsOptions& options, IntrinsicsResult& result) {
  const int n_free_params = s.layout.NumFree();
  const Eigen::MatrixXd cov_free =
      cov_all.rows() >= n_free_params
          ? Eigen::MatrixXd(cov_all.topLeftCorner(n_free_params, n_free_params))
          : Eigen::MatrixXd();
  const int dof = 2 * result.num_corners - result.num_parameters;
  const std::vector<double> full = FullIntrinsics(s);
  const int n_full = s.layout.num_full, n_free = s.layout.NumFree();
  if (cov_free.rows() == n_free && dof > 0) {
    Eigen::MatrixXd jf = Eigen::MatrixXd::Zero(n_full, n_free);  // d full / d free
    for (int c = 0; c < n_free; ++c) {
      for (int r = 0; r < n_full; ++r) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(n_full);
        e(r) = 1;
        jf(r, c) = s.layout.FreeDerivative(e.data(), c);
      }
    }
    result.intrinsics_covariance =
        jf * cov_free * jf.transpose() * (result.residual_sigma_px * result.residual_sigma_px);
    // The model carries it, so a calibration downstream can propagate it.
    if (result.camera) result.camera->SetIntrinsicsCovariance(result.intrinsics_covariance);
    for (int i = 0; i < n_full; ++i) {
      result.intrinsics_sigma.push_back(
          std::sqrt(std::max(0.0, result.intrinsics_covariance(i, i))));
    }
    const double rel = result.intrinsics_sigma[0] / std::abs(full[0]);
    if (!(rel <= options.max_focal_relative_sigma)) {
      MarkFocalUnobservable("focal length poorly observed: 1-sigma " + FormatFixed(100 * rel, 2) +
                                " % of fx (limit " +
                                FormatFixed(100 * options.max_focal_relative_sigma, 2) +
                                " %); add views with the board tilted in different directions",
                            &result);
    }
  } else {
    MarkFocalUnobservable(
        "parameter covariance not computable: the calibration problem is rank deficient (the "
        "views do not constrain every intrinsic; nearly parallel views make the focal length "
        "unobservable)",
        &result);
  }
  if (!result.converged) {
    result.warnings.push_back("the solver did not converge: " + result.termination);
  }
  for (const ViewResult& vr : result.views) {
    if (vr.used && vr.num_corners < options.min_corners_per_view) {
      result.warnings.push_back(vr.name + ": only " + std::to_string(vr.num_corners) +
                                " inlier corners left after outlier rejection");
    }
  }
}

// Projection uncertainty over the image (header: mrcal's mean-frames idea).
void ProjectionUncertainty(const State& s, const Eigen::MatrixXd& cov_all,
                           std::vector<double> distances, const IntrinsicsOptions& options,
                           IntrinsicsResult& result) {
  const int n_full = s.layout.num_full, n_free = s.layout.NumFree();
  const int width_px = s.width, height_px = s.height;
  const std::vector<double> full = FullIntrinsics(s);
  std::vector<double>& sorted = distances;
  std::sort(sorted.begin(), sorted.end());
  result.uncertainty_range_mm =
      options.uncertainty_range_mm > 0 ? options.uncertainty_range_mm : sorted[sorted.size() / 2];
  result.uncertainty_px =
      Eigen::MatrixXd::Constant(options.uncertainty_grid_y, options.uncertainty_grid_x,
                                std::numeric_limits<double>::quiet_NaN());
  const int num_poses = static_cast<int>(s.poses.size());
  if (result.intrinsics_covariance.size() > 0 && cov_all.rows() == n_free + 6 * num_poses) {
    const CameraModel& cam = *result.camera;
    const Eigen::MatrixXd cov = cov_all * (result.residual_sigma_px * result.residual_sigma_px);
    for (int gy = 0; gy < options.uncertainty_grid_y; ++gy) {
      for (int gx = 0; gx < options.uncertainty_grid_x; ++gx) {
        const Eigen::Vector2d q((gx + 0.5) * width_px / options.uncertainty_grid_x - 0.5,
                                (gy + 0.5) * height_px / options.uncertainty_grid_y - 0.5);
        Eigen::Vector3d p;
        try {
          p = cam.Unproject(q) * result.uncertainty_range_mm;
        } catch (const InternalError&) {
          continue;
        }
        Eigen::Matrix<double, 2, 3> dq_dp;
        std::vector<double> dq_dfull(2 * n_full);
        cam.ProjectWithIntrinsics(full.data(), p, &dq_dp, dq_dfull.data());
        Eigen::MatrixXd g(2, n_free + 6 * num_poses);
        for (int row = 0; row < 2; ++row) {
          for (int c = 0; c < n_free; ++c) {
            g(row, c) = s.layout.FreeDerivative(&dq_dfull[row * n_full], c);
          }
        }
        // p = mean_i camera_from_board_i * (board_i_from_camera * p): each pose moves it.
        for (int i = 0; i < num_poses; ++i) {
          const Eigen::Vector3d p_in_board = ToIsometry(s.poses[i]).inverse() * p;
          using Jet3 = ceres::Jet<double, 3>;
          const Jet3 r[3] = {Jet3(s.poses[i].v[0], 0), Jet3(s.poses[i].v[1], 1),
                             Jet3(s.poses[i].v[2], 2)};
          const Jet3 pb[3] = {Jet3(p_in_board.x()), Jet3(p_in_board.y()), Jet3(p_in_board.z())};
          Jet3 pr[3];
          ceres::AngleAxisRotatePoint(r, pb, pr);
          Eigen::Matrix<double, 3, 6> dp_dpose;
          for (int k = 0; k < 3; ++k) dp_dpose.block<1, 3>(k, 0) = pr[k].v.transpose();
          dp_dpose.rightCols<3>() = Eigen::Matrix3d::Identity();
          g.block(0, n_free + 6 * i, 2, 6) = dq_dp * dp_dpose / num_poses;
        }
        const Eigen::Matrix2d cq = g * cov * g.transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cq);
        result.uncertainty_px(gy, gx) = std::sqrt(std::max(0.0, es.eigenvalues()(1)));
      }
    }
  }
}

}  // namespace

IntrinsicsResult CalibrateIntrinsics(const std::vector<BoardView>& views, const BoardSpec& board,
                                     int width_px, int height_px,
                                     const IntrinsicsOptions& options) {
  options.Check();
  board.Check();
  if (width_px <= 0 || height_px <= 0) {
    throw InputError("camera calibration: image size " + std::to_string(width_px) + " x " +
                     std::to_string(height_px) + " px must be positive");
  }
  IntrinsicsResult result;
  State s;
  s.board = &board;
  s.options = &options;
  s.width = width_px;
  s.height = height_px;
  s.layout.fix_aspect = options.fix_aspect_ratio;
  SelectViews(views, board, width_px, height_px, options, result);
  const double f0 = InitialPoses(views, board, width_px, height_px, options, s, result);
  FitLens(s, options, f0, 0.5 * (width_px - 1), 0.5 * (height_px - 1), result);
  Eigen::MatrixXd cov_all;  // [free intrinsics, poses], unscaled
  FinalStatistics(s, views.size(), options, &cov_all, result);
  std::vector<double> distances = ViewGeometry(s, options, result);
  IntrinsicsCovariance(s, cov_all, options, result);
  AssessLensInversion(&result);
  ProjectionUncertainty(s, cov_all, std::move(distances), options, result);
  return result;
}

}  // namespace lasercell::calib
