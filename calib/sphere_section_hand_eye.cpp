#include "calib/sphere_section_hand_eye.hpp"

#include <ceres/ceres.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include "calib/cost_functions/kinematic_sphere_cost.hpp"
#include "calib/robot_in_cell.hpp"
#include "core/error.hpp"

namespace lasercell::calib {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Residual of eq. (2) for one section: R_i (R_X s_i(R) + t_X) + t_i - c, mm.
struct SectionCentreCost {
  Eigen::Isometry3d base_from_flange;
  const Eigen::Isometry3d* x0;  // Reference flange_from_sensor of the perturbation.
  Eigen::Vector3d circle;       // (x_c, z_c, r) in the laser plane, mm.
  double side;                  // +1 or -1: eq. (1).

  template <typename T>
  bool operator()(const T* hand_eye, const T* centre, const T* radius, T* residuals) const {
    const T h2 = radius[0] * radius[0] - T(circle[2] * circle[2]);
    if (!(h2 > T(0))) return false;
    const Eigen::Matrix<T, 3, 1> s(T(circle.x()), T(side) * sqrt(h2), T(circle.y()));
    Eigen::Matrix<T, 3, 3> r_fs;
    Eigen::Matrix<T, 3, 1> t_fs;
    PerturbedFlangeFromSensor(*x0, hand_eye, &r_fs, &t_fs);
    const Eigen::Matrix<T, 3, 1> in_base = base_from_flange.linear().cast<T>() * (r_fs * s + t_fs) +
                                           base_from_flange.translation().cast<T>();
    for (int k = 0; k < 3; ++k) residuals[k] = in_base[k] - centre[k];
    return true;
  }
};

struct Section {
  Eigen::Isometry3d base_from_flange;
  Eigen::Vector3d circle;  // (x_c, z_c, r).
};

struct Solution {
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0;
  bool converged = false;
  int iterations = 0;
  Eigen::MatrixXd covariance;  // Over [w; u; c; (R)].
};

Eigen::Vector3d SensorCentre(const Eigen::Vector3d& circle, double radius, double side) {
  const double h = std::sqrt(std::max(radius * radius - circle[2] * circle[2], 0.0));
  return {circle[0], side * h, circle[1]};
}

// Seed of eq. (2): linear in (vec R_X, t_X, c), columns scaled; R_X projected onto SO(3), then
// t_X and c re-solved with it. nullopt when the system is rank deficient.
std::optional<Solution> LinearSeed(const std::vector<Section>& sections, double radius,
                                   double side) {
  const int n = static_cast<int>(sections.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * n, 15);
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d r = sections[i].base_from_flange.linear();
    const Eigen::Vector3d s = SensorCentre(sections[i].circle, radius, side);
    for (int col = 0; col < 3; ++col) a.block<3, 3>(3 * i, 3 * col) = r * s[col];
    a.block<3, 3>(3 * i, 9) = r;
    a.block<3, 3>(3 * i, 12) = -Eigen::Matrix3d::Identity();
    b.segment<3>(3 * i) = -sections[i].base_from_flange.translation();
  }
  const Eigen::VectorXd scale = a.colwise().norm().cwiseMax(1e-12).cwiseInverse();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a * scale.asDiagonal(),
                                              Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  if (!(sv[sv.size() - 1] > 1e-6 * sv[0])) return std::nullopt;
  const Eigen::VectorXd x = scale.asDiagonal() * svd.solve(b);
  const Eigen::Matrix3d m = Eigen::Map<const Eigen::Matrix3d>(x.data());
  const Eigen::JacobiSVD<Eigen::Matrix3d> proj(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (proj.matrixU() * proj.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Solution out;
  out.flange_from_sensor.linear() = proj.matrixU() * d * proj.matrixV().transpose();
  Eigen::MatrixXd a2(3 * n, 6);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d r = sections[i].base_from_flange.linear();
    a2.block<3, 3>(3 * i, 0) = r;
    a2.block<3, 3>(3 * i, 3) = -Eigen::Matrix3d::Identity();
    b.segment<3>(3 * i) -=
        r * out.flange_from_sensor.linear() * SensorCentre(sections[i].circle, radius, side);
  }
  const Eigen::VectorXd tc = a2.colPivHouseholderQr().solve(b);
  out.flange_from_sensor.translation() = tc.head<3>();
  out.centre = tc.tail<3>();
  out.radius = radius;
  return out;
}

// Refines eq. (2) from `seed` in Ceres; the covariance s^2 (J^T J)^-1 at the solution.
Solution Refine(const std::vector<Section>& sections, const Solution& seed, double side,
                bool estimate_radius, int max_iterations) {
  const Eigen::Isometry3d x0 = seed.flange_from_sensor;
  double hand_eye[6] = {0, 0, 0, 0, 0, 0};
  Eigen::Vector3d centre = seed.centre;
  double radius = seed.radius;
  ceres::Problem problem;
  for (const Section& s : sections) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SectionCentreCost, 3, 6, 3, 1>(
                                 new SectionCentreCost{s.base_from_flange, &x0, s.circle, side}),
                             nullptr, hand_eye, centre.data(), &radius);
  }
  if (!estimate_radius) problem.SetParameterBlockConstant(&radius);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = max_iterations;
  solver.function_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-14;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  Solution out;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.iterations = static_cast<int>(summary.iterations.size());
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  PerturbedFlangeFromSensor(x0, hand_eye, &rotation, &translation);
  out.flange_from_sensor.linear() = rotation;
  out.flange_from_sensor.translation() = translation;
  out.centre = centre;
  out.radius = radius;
  // Covariance at the solution; the Jacobian columns are [w; u] at the solution's X because the
  // left perturbation about x0 composes: Exp(dw) Exp(w) R0 ~ Exp(w + dw) R0 to first order in
  // dw only at w = 0, so re-evaluate about the solution.
  const Eigen::Isometry3d x_hat = out.flange_from_sensor;
  const int p = estimate_radius ? 10 : 9;
  const int m = 3 * static_cast<int>(sections.size());
  Eigen::MatrixXd jac(m, p);
  double ssr = 0;
  double zero[6] = {0, 0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const SectionCentreCost cost{sections[i].base_from_flange, &x_hat, sections[i].circle, side};
    ceres::AutoDiffCostFunction<SectionCentreCost, 3, 6, 3, 1> f(new SectionCentreCost(cost));
    const double* params[3] = {zero, centre.data(), &radius};
    double res[3];
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> j0;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j1;
    Eigen::Matrix<double, 3, 1> j2;
    double* jacs[3] = {j0.data(), j1.data(), j2.data()};
    if (!f.Evaluate(params, res, jacs)) {
      out.converged = false;
      return out;
    }
    const int row = 3 * static_cast<int>(i);
    jac.block<3, 6>(row, 0) = j0;
    jac.block<3, 3>(row, 6) = j1;
    if (estimate_radius) jac.block<3, 1>(row, 9) = j2;
    ssr += res[0] * res[0] + res[1] * res[1] + res[2] * res[2];
  }
  const Eigen::MatrixXd jtj = jac.transpose() * jac;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(jtj);
  if (m > p && lu.isInvertible()) {
    out.covariance = ssr / static_cast<double>(m - p) * lu.inverse();
  }
  return out;
}

double RotationSpanDeg(const std::vector<Section>& sections) {
  double span = 0;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    for (std::size_t j = i + 1; j < sections.size(); ++j) {
      const Eigen::AngleAxisd rel(sections[i].base_from_flange.linear().transpose() *
                                  sections[j].base_from_flange.linear());
      span = std::max(span, std::abs(rel.angle()) * kRadToDeg);
    }
  }
  return span;
}

}  // namespace

void SphereSectionHandEyeOptions::Check() const {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw OptionError("SphereSectionHandEyeOptions." + field + " " + problem);
  };
  if (!(sphere_radius_mm > 0)) fail("sphere_radius_mm", "must be > 0 (the nominal radius)");
  if (sphere_side != 1 && sphere_side != -1) {
    fail("sphere_side",
         "must be +1 or -1: the side of the laser plane (sensor +y or -y) the sphere centre "
         "lies on; one profile cannot tell");
  }
  if (!(min_section_radius_ratio > 0 && min_section_radius_ratio < 1)) {
    fail("min_section_radius_ratio", "must be in (0, 1)");
  }
  if (!(max_section_radius_ratio > min_section_radius_ratio && max_section_radius_ratio < 1)) {
    fail("max_section_radius_ratio", "must be in (min_section_radius_ratio, 1)");
  }
  if (max_iterations <= 0) fail("max_iterations", "must be > 0");
  CircleFitOptions c = circle;
  c.min_radius_mm = 1.0;
  c.max_radius_mm = 2.0;
  c.Check();
}

std::string SphereSectionHandEyeResult::Summary() const {
  char buf[320];
  std::snprintf(buf, sizeof(buf),
                "%s, %zu of %zu sections; centre spread %.3f mm RMS (max %.3f), leave-one-out "
                "%.3f mm RMS (max %.3f); radius %.3f mm; 1-sigma %.3f mm / %.4f deg",
                converged ? "converged" : "NOT converged", sections_used, sections.size(),
                spread_rms_mm, spread_max_mm, loo_rms_mm, loo_max_mm, radius_mm,
                std::sqrt(covariance.bottomRightCorner<3, 3>().trace()),
                std::sqrt(covariance.topLeftCorner<3, 3>().trace()) * kRadToDeg);
  return buf;
}

namespace {

// Circle per profile and the reasons a section is not used.
std::vector<SphereSection> FitSections(const std::vector<SphereSectionProfile>& profiles,
                                       const SphereSectionHandEyeOptions& o) {
  std::vector<SphereSection> out;
  const double radius = o.sphere_radius_mm;
  CircleFitOptions circle = o.circle;
  circle.min_radius_mm = o.min_section_radius_ratio * radius;
  circle.max_radius_mm = 1.05 * radius;
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const SphereSectionProfile& p = profiles[i];
    const std::string who = "profile " + std::to_string(i) + " (" + p.name + ")";
    if (!p.base_from_flange.matrix().allFinite()) {
      throw InputError("CalibrateHandEyeFromSphereSections: " + who + " has a non-finite pose");
    }
    std::vector<Eigen::Vector2d> xz;
    for (const Eigen::Vector3d& q : p.points_in_sensor) {
      if (!q.allFinite()) {
        throw InputError("CalibrateHandEyeFromSphereSections: " + who + " has non-finite points");
      }
      if (std::abs(q.y()) > 0.01) {
        throw InputError("CalibrateHandEyeFromSphereSections: " + who +
                         " has a point off the laser plane (y = " + std::to_string(q.y()) +
                         " mm); the points must be calibrated profile points (x, 0, z)");
      }
      xz.emplace_back(q.x(), q.z());
    }
    SphereSection s;
    s.name = p.name;
    if (xz.size() < circle.min_points) {
      s.why_not = std::to_string(xz.size()) + " points";
    } else {
      s.circle = FitCircle(xz, circle);
      const double ratio = s.circle.radius_mm / radius;
      if (!s.circle.success) {
        s.why_not = s.circle.failure;
      } else if (ratio > o.max_section_radius_ratio) {
        s.why_not = "section radius " + std::to_string(s.circle.radius_mm) +
                    " mm is too close to the sphere's: the lift off the plane is unstable";
      } else {
        s.used = true;
      }
    }
    out.push_back(std::move(s));
  }
  return out;
}

// The section's circle as eq. (1) takes it: (x_c, z_c, r).
Eigen::Vector3d CircleOf(const SphereSection& s) {
  return {s.circle.centre.x(), s.circle.centre.y(), s.circle.radius_mm};
}

std::vector<Section> UsedSections(const std::vector<SphereSectionProfile>& profiles,
                                  const std::vector<SphereSection>& sections, int skip = -1) {
  std::vector<Section> out;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    if (!sections[i].used || static_cast<int>(i) == skip) continue;
    out.push_back({profiles[i].base_from_flange, CircleOf(sections[i])});
  }
  return out;
}

Eigen::Vector3d CentreInBase(const Eigen::Isometry3d& base_from_flange,
                             const Eigen::Isometry3d& flange_from_sensor,
                             const Eigen::Vector3d& in_sensor) {
  return base_from_flange * (flange_from_sensor * in_sensor);
}

void LeaveOneOut(const std::vector<SphereSectionProfile>& profiles, const Solution& full,
                 const SphereSectionHandEyeOptions& o, SphereSectionHandEyeResult* r) {
  double sum = 0, worst = 0, dt_max = 0, dr_max = 0;
  int count = 0;
  for (std::size_t k = 0; k < r->sections.size(); ++k) {
    SphereSection& s = r->sections[k];
    if (!s.used) continue;
    const std::vector<Section> rest = UsedSections(profiles, r->sections, static_cast<int>(k));
    if (rest.size() < 5) return;
    const Solution sol = Refine(rest, full, o.sphere_side, o.estimate_radius, o.max_iterations);
    const Eigen::Vector3d circle = CircleOf(s);
    const Eigen::Vector3d predicted =
        CentreInBase(profiles[k].base_from_flange, sol.flange_from_sensor,
                     SensorCentre(circle, sol.radius, o.sphere_side));
    s.loo_distance_mm = (predicted - sol.centre).norm();
    s.loo_translation_change_mm =
        (sol.flange_from_sensor.translation() - full.flange_from_sensor.translation()).norm();
    s.loo_rotation_change_deg =
        RotationDistance(sol.flange_from_sensor, full.flange_from_sensor) * kRadToDeg;
    sum += s.loo_distance_mm * s.loo_distance_mm;
    worst = std::max(worst, s.loo_distance_mm);
    dt_max = std::max(dt_max, s.loo_translation_change_mm);
    dr_max = std::max(dr_max, s.loo_rotation_change_deg);
    ++count;
  }
  r->loo_rms_mm = std::sqrt(sum / count);
  r->loo_max_mm = worst;
  r->loo_translation_change_max_mm = dt_max;
  r->loo_rotation_change_max_deg = dr_max;
}

}  // namespace

SphereSectionHandEyeResult CalibrateHandEyeFromSphereSections(
    const std::vector<SphereSectionProfile>& profiles, const SphereSectionHandEyeOptions& o) {
  o.Check();
  SphereSectionHandEyeResult r;
  r.sections = FitSections(profiles, o);
  const std::vector<Section> used = UsedSections(profiles, r.sections);
  if (used.size() < 5) {
    std::string why;
    for (const SphereSection& s : r.sections) {
      if (!s.used) why += "; " + s.name + ": " + s.why_not;
    }
    throw InputError("CalibrateHandEyeFromSphereSections: " + std::to_string(used.size()) + " of " +
                     std::to_string(profiles.size()) +
                     " profiles give a usable sphere section; need at least 5" + why);
  }
  r.rotation_span_deg = RotationSpanDeg(used);
  const std::optional<Solution> seed = LinearSeed(used, o.sphere_radius_mm, o.sphere_side);
  if (r.rotation_span_deg < 2.0 || !seed) {
    throw InputError(
        "CalibrateHandEyeFromSphereSections: the robot poses do not determine the hand-eye "
        "transform (flange rotations span " +
        std::to_string(r.rotation_span_deg) +
        " deg, or turn about one axis only); take poses tilted by >= 10 deg about two axes");
  }
  const Solution sol = Refine(used, *seed, o.sphere_side, o.estimate_radius, o.max_iterations);
  r.converged = sol.converged && sol.covariance.size() > 0;
  r.iterations = sol.iterations;
  r.flange_from_sensor = sol.flange_from_sensor;
  r.sphere_centre_in_base = sol.centre;
  r.radius_mm = sol.radius;
  if (sol.covariance.size() > 0) {
    r.covariance = sol.covariance.topLeftCorner<6, 6>();
    r.sphere_centre_covariance = sol.covariance.block<3, 3>(6, 6);
    if (o.estimate_radius) r.radius_sigma_mm = std::sqrt(sol.covariance(9, 9));
  } else {
    r.warnings.push_back("the covariance is singular: the poses do not fix every direction");
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < r.sections.size(); ++i) {
    SphereSection& s = r.sections[i];
    if (!s.used) continue;
    const Eigen::Vector3d circle = CircleOf(s);
    s.centre_in_sensor = SensorCentre(circle, sol.radius, o.sphere_side);
    s.centre_in_base =
        CentreInBase(profiles[i].base_from_flange, sol.flange_from_sensor, s.centre_in_sensor);
    s.distance_mm = (s.centre_in_base - sol.centre).norm();
    mean += s.centre_in_base;
    ++r.sections_used;
  }
  mean /= static_cast<double>(r.sections_used);
  double sum = 0;
  for (const SphereSection& s : r.sections) {
    if (!s.used) continue;
    const double d = (s.centre_in_base - mean).norm();
    sum += d * d;
    r.spread_max_mm = std::max(r.spread_max_mm, d);
  }
  r.spread_rms_mm = std::sqrt(sum / static_cast<double>(r.sections_used));
  if (o.leave_one_out) LeaveOneOut(profiles, sol, o, &r);
  if (!r.converged) r.warnings.push_back("the refinement did not converge");
  return r;
}

StaticEdge SphereSectionEdge(const FrameGraph& cell, const std::string& cell_name,
                             const std::string& robot, const std::string& sensor_frame,
                             const SphereSectionHandEyeResult& result) {
  const RobotInCell found = FindRobot(cell, robot, cell_name);
  return FlangeSensorEdge(found.flange, sensor_frame, result.flange_from_sensor, result.covariance,
                          "lasercell calibrate handeye-laser --profiles", result.spread_rms_mm,
                          result.sections_used, result.sections_used);
}

}  // namespace lasercell::calib
