// Eye-in-hand calibration (hand_eye.hpp): closed forms (Tsai-Lenz, Park-Martin, Daniilidis) and
// the joint Ceres refinement of flange_from_camera and base_from_board.
#include "calib/hand_eye.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "calib/camera_uncertainty.hpp"
#include "calib/cost_functions/hand_eye_reprojection.hpp"
#include "calib/internal/board_pose.hpp"
#include "core/error.hpp"

namespace lasercell::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Motion {
  Eigen::Isometry3d a;  // flange_i_from_flange_j
  Eigen::Isometry3d b;  // camera_i_from_camera_j
};

double AngleOf(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle(); }

std::vector<Motion> Motions(const std::vector<Eigen::Isometry3d>& base_from_flange,
                            const std::vector<Eigen::Isometry3d>& camera_from_board,
                            double min_angle_rad) {
  std::vector<Motion> motions;
  for (std::size_t i = 0; i < base_from_flange.size(); ++i) {
    for (std::size_t j = i + 1; j < base_from_flange.size(); ++j) {
      Motion m{base_from_flange[i].inverse() * base_from_flange[j],
               camera_from_board[i] * camera_from_board[j].inverse()};
      if (AngleOf(m.a.linear()) >= min_angle_rad) motions.push_back(m);
    }
  }
  return motions;
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// Translation of X given its rotation, every method but Daniilidis: (R_A - I) t_X = R_X t_B - t_A
// (Tsai & Lenz 1989, eq. 17), least squares over all motions.
Eigen::Vector3d SolveTranslation(const std::vector<Motion>& motions, const Eigen::Matrix3d& rx) {
  Eigen::MatrixXd c(3 * motions.size(), 3);
  Eigen::VectorXd d(3 * motions.size());
  for (std::size_t k = 0; k < motions.size(); ++k) {
    c.block<3, 3>(3 * k, 0) = motions[k].a.linear() - Eigen::Matrix3d::Identity();
    d.segment<3>(3 * k) = rx * motions[k].b.translation() - motions[k].a.translation();
  }
  return c.colPivHouseholderQr().solve(d);
}

// Tsai & Lenz 1989: with P = 2 sin(theta/2) n, skew(P_A + P_B) P' = P_B - P_A, where P' is the
// Cayley vector tan(theta_X/2) n_X (a - b = c x (a + b) for a = R_X b).
Eigen::Matrix3d TsaiRotation(const std::vector<Motion>& motions) {
  Eigen::MatrixXd c(3 * motions.size(), 3);
  Eigen::VectorXd d(3 * motions.size());
  for (std::size_t k = 0; k < motions.size(); ++k) {
    const Eigen::AngleAxisd aa(motions[k].a.linear()), ab(motions[k].b.linear());
    const Eigen::Vector3d pa = 2.0 * std::sin(aa.angle() / 2) * aa.axis();
    const Eigen::Vector3d pb = 2.0 * std::sin(ab.angle() / 2) * ab.axis();
    c.block<3, 3>(3 * k, 0) = Skew(pa + pb);
    d.segment<3>(3 * k) = pb - pa;
  }
  const Eigen::Vector3d cayley = c.colPivHouseholderQr().solve(d);
  const double angle = 2.0 * std::atan(cayley.norm());
  if (cayley.norm() < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, cayley.normalized()).toRotationMatrix();
}

// Park & Martin 1994: alpha = log R_A = R_X log R_B = R_X beta; M = sum beta alpha^T,
// R_X = (M^T M)^-1/2 M^T, computed as the nearest rotation to M^T.
Eigen::Matrix3d ParkRotation(const std::vector<Motion>& motions) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const Motion& mo : motions) {
    const Eigen::Vector3d alpha = RotationVectorFromMatrix(mo.a.linear());
    const Eigen::Vector3d beta = RotationVectorFromMatrix(mo.b.linear());
    m += beta * alpha.transpose();
  }
  return NearestRotation(m.transpose());
}

// Quaternion as (w, x, y, z) with w >= 0.
Eigen::Vector4d Quat(const Eigen::Matrix3d& r) {
  Eigen::Quaterniond q(r);
  q.normalize();
  Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
  return v[0] < 0 ? Eigen::Vector4d(-v) : v;
}

Eigen::Vector4d QuatMul(const Eigen::Vector4d& p, const Eigen::Vector4d& q) {
  const Eigen::Vector3d pv = p.tail<3>(), qv = q.tail<3>();
  Eigen::Vector4d r;
  r[0] = p[0] * q[0] - pv.dot(qv);
  r.tail<3>() = p[0] * qv + q[0] * pv + pv.cross(qv);
  return r;
}

// Daniilidis 1999: a q = q b for the real and dual parts gives per motion the 6x8 block
// [a - b, [a + b]x, 0, 0; a' - b', [a' + b']x, a - b, [a + b]x] (vector parts) acting on (q, q');
// the solution lies in the span of the two smallest right singular vectors, fixed by |q| = 1 and
// q . q' = 0 (eqs. 31-35).
// The SVD weighs the real (rotation) and dual (translation) rows together, so the result depends
// on the length unit; translations are scaled to unit RMS first and the result scaled back.
Eigen::Isometry3d DaniilidisSolve(const std::vector<Motion>& motions) {
  double ss = 0;
  for (const Motion& m : motions) {
    ss += m.a.translation().squaredNorm() + m.b.translation().squaredNorm();
  }
  const double scale = ss > 0 ? std::sqrt(ss / (2.0 * static_cast<double>(motions.size()))) : 1.0;
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(6 * motions.size(), 8);
  for (std::size_t k = 0; k < motions.size(); ++k) {
    const Eigen::Vector4d a = Quat(motions[k].a.linear()), b = Quat(motions[k].b.linear());
    const Eigen::Vector3d ma = motions[k].a.translation() / scale;
    const Eigen::Vector3d mb = motions[k].b.translation() / scale;
    const Eigen::Vector4d ta(0, ma.x(), ma.y(), ma.z());
    const Eigen::Vector4d tb(0, mb.x(), mb.y(), mb.z());
    const Eigen::Vector4d ad = 0.5 * QuatMul(ta, a), bd = 0.5 * QuatMul(tb, b);
    const Eigen::Vector3d av = a.tail<3>(), bv = b.tail<3>(), adv = ad.tail<3>(),
                          bdv = bd.tail<3>();
    const int r = static_cast<int>(6 * k);
    t.block<3, 1>(r, 0) = av - bv;
    t.block<3, 3>(r, 1) = Skew(av + bv);
    t.block<3, 1>(r + 3, 0) = adv - bdv;
    t.block<3, 3>(r + 3, 1) = Skew(adv + bdv);
    t.block<3, 1>(r + 3, 4) = av - bv;
    t.block<3, 3>(r + 3, 5) = Skew(av + bv);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(t, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 8, 1> v7 = svd.matrixV().col(6), v8 = svd.matrixV().col(7);
  const Eigen::Vector4d u1 = v7.head<4>(), w1 = v7.tail<4>(), u2 = v8.head<4>(), w2 = v8.tail<4>();
  // s = lambda1 / lambda2: s^2 u1.w1 + s (u1.w2 + u2.w1) + u2.w2 = 0.
  const double qa = u1.dot(w1), qb = u1.dot(w2) + u2.dot(w1), qc = u2.dot(w2);
  double best_norm = -1, best_s = 0;
  std::vector<double> roots;
  if (std::abs(qa) < 1e-15) {
    roots.push_back(-qc / qb);
  } else {
    const double disc = std::max(0.0, qb * qb - 4 * qa * qc);
    roots.push_back((-qb + std::sqrt(disc)) / (2 * qa));
    roots.push_back((-qb - std::sqrt(disc)) / (2 * qa));
  }
  for (double s : roots) {
    const double n = s * s * u1.squaredNorm() + 2 * s * u1.dot(u2) + u2.squaredNorm();
    if (n > best_norm) {
      best_norm = n;
      best_s = s;
    }
  }
  const double lambda2 = 1.0 / std::sqrt(best_norm), lambda1 = best_s * lambda2;
  const Eigen::Matrix<double, 8, 1> q = lambda1 * v7 + lambda2 * v8;
  const Eigen::Vector4d real = q.head<4>(), dual = q.tail<4>();
  const Eigen::Vector4d conj(real[0], -real[1], -real[2], -real[3]);
  const Eigen::Vector4d tq = 2.0 * QuatMul(dual, conj);
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() =
      Eigen::Quaterniond(real[0], real[1], real[2], real[3]).normalized().toRotationMatrix();
  x.translation() = scale * tq.tail<3>();
  return x;
}

std::string Vec(const Eigen::Vector3d& v) {
  char b[96];
  std::snprintf(b, sizeof b, "[%.3f, %.3f, %.3f]", v.x(), v.y(), v.z());
  return b;
}

Eigen::Isometry3d Perturbed(const Eigen::Isometry3d& pose, const double* d) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d r(d[0], d[1], d[2]);
  out.linear() = PoseFromRotationVector(r, Eigen::Vector3d::Zero()).linear() * pose.linear();
  out.linear() = NearestRotation(out.linear());
  out.translation() = pose.translation() + Eigen::Vector3d(d[3], d[4], d[5]);
  return out;
}

AxXbError ClosureOf(const Eigen::Isometry3d& d) {
  return {AngleOf(d.linear()) / kDeg, d.translation().norm()};
}

// True when listing the board points backwards is the board turned by 180 degrees about its
// centre (p_{N-1-k} = 2c - p_k): then a detector may number the corners from either end.
bool ReversalIsRigid(const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 2) return false;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& q : p) c += q;
  c /= static_cast<double>(p.size());
  double extent = 0;
  for (const auto& q : p) extent = std::max(extent, (q - c).norm());
  for (std::size_t k = 0; k < p.size(); ++k) {
    if ((p[p.size() - 1 - k] - (2 * c - p[k])).norm() > 1e-9 * std::max(1.0, extent)) return false;
  }
  return true;
}

}  // namespace

std::string HandEyeMethodName(HandEyeMethod method) {
  switch (method) {
    case HandEyeMethod::kTsaiLenz:
      return "tsai-lenz";
    case HandEyeMethod::kParkMartin:
      return "park-martin";
    case HandEyeMethod::kDaniilidis:
      return "daniilidis";
  }
  return "unknown";
}

void HandEyeMotionOptions::Check() const {
  if (!(min_rotation_deg > 0 && min_rotation_deg < 90)) {
    throw OptionError("HandEyeMotionOptions.min_rotation_deg must be in (0, 90) deg");
  }
  if (!(min_axis_spread_deg > 0 && min_axis_spread_deg < 90)) {
    throw OptionError("HandEyeMotionOptions.min_axis_spread_deg must be in (0, 90) deg");
  }
}

void HandEyeOptions::Check() const {
  motion.Check();
  if (max_iterations < 1) throw OptionError("HandEyeOptions.max_iterations must be >= 1");
  if (!(function_tolerance > 0)) {
    throw OptionError("HandEyeOptions.function_tolerance must be > 0");
  }
  if (threads < 1) throw OptionError("HandEyeOptions.threads must be >= 1");
}

void CheckHandEyeMotions(const std::vector<Eigen::Isometry3d>& base_from_flange,
                         const HandEyeMotionOptions& options) {
  options.Check();
  if (base_from_flange.size() < 3) {
    throw InputError("hand-eye: " + std::to_string(base_from_flange.size()) +
                     " robot poses given; at least 3 (with rotations about two different axes) "
                     "are needed");
  }
  for (std::size_t i = 0; i < base_from_flange.size(); ++i) {
    CheckRigidTransform(base_from_flange[i], "hand-eye: robot pose " + std::to_string(i + 1));
  }
  double max_angle = 0;
  std::vector<Eigen::Vector3d> axes;
  for (std::size_t i = 0; i < base_from_flange.size(); ++i) {
    for (std::size_t j = i + 1; j < base_from_flange.size(); ++j) {
      const Eigen::AngleAxisd aa((base_from_flange[i].inverse() * base_from_flange[j]).linear());
      max_angle = std::max(max_angle, aa.angle());
      if (aa.angle() >= options.min_rotation_deg * kDeg) axes.push_back(aa.axis());
    }
  }
  if (max_angle < options.min_rotation_deg * kDeg) {
    char b[256];
    std::snprintf(b, sizeof b,
                  "hand-eye: pure-translation robot motions: the largest rotation between two "
                  "poses is %.3g deg (< %.3g deg), so the rotation of flange_from_camera is "
                  "unobservable; add poses that rotate the flange",
                  max_angle / kDeg, options.min_rotation_deg);
    throw InputError(b);
  }
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& n : axes) scatter += n * n.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d principal = eig.eigenvectors().col(2);
  double spread = 0;
  for (const auto& n : axes) {
    spread = std::max(spread, std::acos(std::min(1.0, std::abs(n.dot(principal)))));
  }
  if (spread < options.min_axis_spread_deg * kDeg) {
    char b[320];
    std::snprintf(b, sizeof b,
                  "hand-eye: all robot rotations are about one axis (flange-frame direction %s, "
                  "spread %.3g deg < %.3g deg), so the translation of flange_from_camera along "
                  "it is unobservable; add poses rotating about another axis",
                  Vec(principal).c_str(), spread / kDeg, options.min_axis_spread_deg);
    throw InputError(b);
  }
}

Eigen::Isometry3d SolveHandEyeClosedForm(const std::vector<Eigen::Isometry3d>& base_from_flange,
                                         const std::vector<Eigen::Isometry3d>& camera_from_board,
                                         HandEyeMethod method) {
  if (base_from_flange.size() != camera_from_board.size()) {
    throw InputError("hand-eye: " + std::to_string(base_from_flange.size()) + " robot poses but " +
                     std::to_string(camera_from_board.size()) + " board poses");
  }
  const std::vector<Motion> motions = Motions(base_from_flange, camera_from_board, 1.0 * kDeg);
  if (motions.size() < 2) {
    throw InputError(
        "hand-eye: fewer than 2 robot motions rotate by >= 1 deg; rotation "
        "unobservable");
  }
  if (method == HandEyeMethod::kDaniilidis) return DaniilidisSolve(motions);
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = method == HandEyeMethod::kTsaiLenz ? TsaiRotation(motions) : ParkRotation(motions);
  x.translation() = SolveTranslation(motions, x.linear());
  return x;
}

Eigen::Isometry3d BaseFromBoard(const std::vector<Eigen::Isometry3d>& base_from_flange,
                                const std::vector<Eigen::Isometry3d>& camera_from_board,
                                const Eigen::Isometry3d& flange_from_camera) {
  std::vector<Eigen::Isometry3d> ys;
  for (std::size_t i = 0; i < base_from_flange.size(); ++i) {
    ys.push_back(base_from_flange[i] * flange_from_camera * camera_from_board[i]);
  }
  return AveragePoses(ys);
}

AxXbError AxXbResidual(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                       const Eigen::Isometry3d& x) {
  return ClosureOf((a * x).inverse() * (x * b));
}

Eigen::Isometry3d EstimateCameraFromBoard(const HandEyeView& view, const CameraModel& camera) {
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(view.corners_px);
  std::vector<Eigen::Vector2d> normalised;
  for (const auto& r : rays) normalised.push_back(r.head<2>() / r.z());
  Eigen::Isometry3d camera_from_board =
      internal::SolvePnPNormalised(view.corners_in_board, normalised);
  // Refine over pixels through the lens model (the normalised-plane PnP weights pixels unevenly).
  for (int round = 0; round < 2; ++round) {
    double d[6] = {0, 0, 0, 0, 0, 0};
    ceres::Problem problem;
    for (std::size_t k = 0; k < view.corners_px.size(); ++k) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<BoardPoseReprojectionCost, 2, 6>(
              new BoardPoseReprojectionCost(camera, camera_from_board, view.corners_in_board[k],
                                            view.corners_px[k])),
          nullptr, d);
    }
    ceres::Solver::Options o;
    o.linear_solver_type = ceres::DENSE_QR;
    o.max_num_iterations = 50;
    ceres::Solver::Summary s;
    ceres::Solve(o, &problem, &s);
    camera_from_board = Perturbed(camera_from_board, d);
  }
  return camera_from_board;
}

namespace {

void AddResiduals(const std::vector<HandEyeView>& views, const CameraModel& camera,
                  const Eigen::Isometry3d& x, const Eigen::Isometry3d& y, double* dx, double* dy,
                  ceres::Problem* problem) {
  for (const HandEyeView& v : views) {
    for (std::size_t k = 0; k < v.corners_px.size(); ++k) {
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<HandEyeReprojectionCost, 2, 6, 6>(
              new HandEyeReprojectionCost(camera, v.base_from_flange, x, y, v.corners_in_board[k],
                                          v.corners_px[k])),
          nullptr, dx, dy);
    }
  }
}

Eigen::Vector2d Residual(const CameraModel& camera, const HandEyeView& v, std::size_t k,
                         const Eigen::Isometry3d& x, const Eigen::Isometry3d& y) {
  const Eigen::Vector3d p = (v.base_from_flange * x).inverse() * (y * v.corners_in_board[k]);
  return camera.Project(p) - v.corners_px[k];
}

}  // namespace

Eigen::Vector3d HandEyeResult::SigmaRotationDeg() const {
  return flange_from_camera_covariance.diagonal().head<3>().cwiseSqrt() / kDeg;
}
Eigen::Vector3d HandEyeResult::SigmaTranslationMm() const {
  return flange_from_camera_covariance.diagonal().tail<3>().cwiseSqrt();
}

std::string HandEyeResult::Summary() const {
  char b[512];
  const Eigen::Vector3d sr = SigmaRotationDeg(), st = SigmaTranslationMm();
  std::snprintf(
      b, sizeof b,
      "hand-eye %s after %d iterations: reprojection RMS %.3f px over %d corners, "
      "AX-XB RMS %.4f deg / %.3f mm; 1 sigma rot [%.4f %.4f %.4f] deg, "
      "trans [%.3f %.3f %.3f] mm%s",
      converged ? "converged" : "NOT converged", iterations, reprojection_rms_px, observations,
      axxb_rms_rotation_deg, axxb_rms_translation_mm, sr.x(), sr.y(), sr.z(), st.x(), st.y(),
      st.z(),
      warnings.empty() ? "" : (" (" + std::to_string(warnings.size()) + " warnings)").c_str());
  return std::string(b) + (camera_uncertainty_included ? "; the camera's uncertainty included"
                                                       : "; camera uncertainty not included");
}

namespace {

/// The joint refinement of X and Y over every corner's reprojection error, from *x, *y.
ceres::Solver::Summary Refine(const std::vector<HandEyeView>& views, const CameraModel& camera,
                              const HandEyeOptions& options, Eigen::Isometry3d* x,
                              Eigen::Isometry3d* y) {
  double dx[6] = {0, 0, 0, 0, 0, 0}, dy[6] = {0, 0, 0, 0, 0, 0};
  ceres::Problem problem;
  AddResiduals(views, camera, *x, *y, dx, dy, &problem);
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = options.max_iterations;
  o.function_tolerance = options.function_tolerance;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.num_threads = options.threads;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  *x = Perturbed(*x, dx);
  *y = Perturbed(*y, dy);
  return summary;
}

/// [rotation vector; translation] of `moved` as a left perturbation of `pose` (file comment).
Vector6d LeftPerturbation(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& moved) {
  const Eigen::AngleAxisd r(moved.linear() * pose.linear().transpose());
  Vector6d d;
  d << r.angle() * r.axis(), moved.translation() - pose.translation();
  return d;
}

/// Adds the camera's uncertainty to the covariances: X and Y refined again through perturbed
/// cameras (calib/camera_uncertainty.hpp).
void AddCameraUncertainty(const std::vector<HandEyeView>& views, const CameraModel& camera,
                          const HandEyeOptions& options, HandEyeResult& result) {
  if (const std::string problem = CameraPropagationProblem(camera); !problem.empty()) {
    result.camera_uncertainty_note = "camera uncertainty not included: " + problem;
    return;
  }
  const Eigen::MatrixXd cov = PropagateIntrinsicsCovariance(camera, [&](const CameraModel& c) {
    Eigen::Isometry3d x = result.flange_from_camera, y = result.base_from_board;
    Refine(views, c, options, &x, &y);
    Eigen::VectorXd d(12);
    d << LeftPerturbation(result.flange_from_camera, x),
        LeftPerturbation(result.base_from_board, y);
    return d;
  });
  result.flange_from_camera_camera_covariance = cov.topLeftCorner<6, 6>();
  result.flange_from_camera_covariance += result.flange_from_camera_camera_covariance;
  result.base_from_board_covariance += cov.bottomRightCorner<6, 6>();
  result.camera_uncertainty_included = true;
}

}  // namespace

HandEyeResult CalibrateHandEye(const std::vector<HandEyeView>& views, const CameraModel& camera,
                               const HandEyeOptions& options) {
  options.Check();
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const HandEyeView& v = views[i];
    if (v.corners_px.size() != v.corners_in_board.size()) {
      throw InputError("hand-eye: view " + std::to_string(i + 1) + " has " +
                       std::to_string(v.corners_px.size()) + " corners but " +
                       std::to_string(v.corners_in_board.size()) + " board points");
    }
    if (v.corners_px.size() < 4) {
      throw InputError("hand-eye: view " + std::to_string(i + 1) + " has fewer than 4 corners");
    }
    poses.push_back(v.base_from_flange);
  }
  CheckHandEyeMotions(poses, options.motion);

  HandEyeResult result;
  for (const HandEyeView& v : views) {
    result.camera_from_board.push_back(EstimateCameraFromBoard(v, camera));
  }
  // A 180-degree-symmetric board: make every view's corner numbering agree with view 1's. The
  // rotation angle of a robot motion equals that of the camera motion (A X = X B), whatever X;
  // the wrong numbering turns the board by 180 deg and breaks that equality.
  std::vector<HandEyeView> reordered;
  const std::vector<HandEyeView>* used_views = &views;
  if (options.fix_symmetric_board_order && ReversalIsRigid(views[0].corners_in_board)) {
    bool all_same_board = true;
    for (const HandEyeView& v : views) {
      all_same_board = all_same_board && v.corners_in_board == views[0].corners_in_board;
    }
    if (all_same_board) {
      reordered = views;
      for (std::size_t i = 1; i < views.size(); ++i) {
        const double angle_a = AngleOf((poses[0].inverse() * poses[i]).linear());
        HandEyeView flipped = views[i];
        std::reverse(flipped.corners_px.begin(), flipped.corners_px.end());
        const Eigen::Isometry3d c_flipped = EstimateCameraFromBoard(flipped, camera);
        const double keep = std::abs(
            AngleOf(
                (result.camera_from_board[0] * result.camera_from_board[i].inverse()).linear()) -
            angle_a);
        const double flip = std::abs(
            AngleOf((result.camera_from_board[0] * c_flipped.inverse()).linear()) - angle_a);
        if (flip + 0.5 * kDeg < keep) {
          reordered[i] = flipped;
          result.camera_from_board[i] = c_flipped;
          result.reversed_views.push_back(static_cast<int>(i));
          result.warnings.push_back("view " + std::to_string(i + 1) +
                                    ": corner numbering reversed to match view 1 (the board is "
                                    "symmetric under a 180-degree turn)");
        }
      }
      used_views = &reordered;
    }
  }
  const std::vector<HandEyeView>& vs = *used_views;
  result.initial_flange_from_camera =
      SolveHandEyeClosedForm(poses, result.camera_from_board, options.initialisation);
  Eigen::Isometry3d x = result.initial_flange_from_camera;
  Eigen::Isometry3d y = BaseFromBoard(poses, result.camera_from_board, x);
  result.converged = true;

  if (options.refine) {
    const ceres::Solver::Summary summary = Refine(vs, camera, options, &x, &y);
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.iterations = static_cast<int>(summary.iterations.size()) - 1;
    result.termination = summary.message;
  }
  result.flange_from_camera = x;
  result.base_from_board = y;

  // Residuals at the solution.
  double ss = 0;
  for (const HandEyeView& v : vs) {
    double view_ss = 0;
    for (std::size_t k = 0; k < v.corners_px.size(); ++k) {
      const Eigen::Vector2d r = Residual(camera, v, k, x, y);
      result.residuals_px.push_back(r);
      view_ss += r.squaredNorm();
    }
    ss += view_ss;
    result.view_rms_px.push_back(std::sqrt(view_ss / static_cast<double>(v.corners_px.size())));
    result.observations += static_cast<int>(v.corners_px.size());
  }
  result.reprojection_rms_px = std::sqrt(ss / result.observations);
  const int dof = 2 * result.observations - 12;
  result.residual_sigma_px = dof > 0 ? std::sqrt(ss / dof) : 0.0;
  for (std::size_t i = 0; i < vs.size(); ++i) {
    result.view_closure.push_back(
        ClosureOf(y.inverse() * vs[i].base_from_flange * x * result.camera_from_board[i]));
    if (result.view_rms_px[i] > 3.0 * result.reprojection_rms_px && result.view_rms_px[i] > 0.5) {
      char b[160];
      std::snprintf(b, sizeof b, "view %zu: reprojection RMS %.3f px, > 3x the overall %.3f px",
                    i + 1, result.view_rms_px[i], result.reprojection_rms_px);
      result.warnings.emplace_back(b);
    }
  }
  double sr = 0, st = 0;
  for (std::size_t i = 0; i + 1 < vs.size(); ++i) {
    const AxXbError e =
        AxXbResidual(poses[i].inverse() * poses[i + 1],
                     result.camera_from_board[i] * result.camera_from_board[i + 1].inverse(), x);
    result.axxb.push_back(e);
    sr += e.rotation_deg * e.rotation_deg;
    st += e.translation_mm * e.translation_mm;
  }
  if (!result.axxb.empty()) {
    result.axxb_rms_rotation_deg = std::sqrt(sr / static_cast<double>(result.axxb.size()));
    result.axxb_rms_translation_mm = std::sqrt(st / static_cast<double>(result.axxb.size()));
  }

  if (options.estimate_covariance && dof > 0) {
    // Linearise again at the solution (perturbations 0) and invert J^T J.
    double dx[6] = {0, 0, 0, 0, 0, 0}, dy[6] = {0, 0, 0, 0, 0, 0};
    ceres::Problem problem;
    AddResiduals(vs, camera, x, y, dx, dy, &problem);
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = options.threads;
    ceres::Covariance covariance(co);
    std::vector<std::pair<const double*, const double*>> blocks = {{dx, dx}, {dy, dy}};
    if (covariance.Compute(blocks, &problem)) {
      const double s2 = result.residual_sigma_px * result.residual_sigma_px;
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> c;
      covariance.GetCovarianceBlock(dx, dx, c.data());
      result.flange_from_camera_covariance = s2 * c;
      covariance.GetCovarianceBlock(dy, dy, c.data());
      result.base_from_board_covariance = s2 * c;
      result.covariance_valid = true;
    } else {
      result.warnings.emplace_back("covariance: J^T J is rank deficient");
    }
  }
  if (result.covariance_valid && options.include_camera_uncertainty && options.refine) {
    AddCameraUncertainty(vs, camera, options, result);
  } else if (result.camera_uncertainty_note.empty()) {
    result.camera_uncertainty_note = "camera uncertainty not included (not asked for)";
  }
  return result;
}

}  // namespace lasercell::calib
