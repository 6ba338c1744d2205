#include "calib/joint_identification.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <string>

#include "calib/cost_functions/kinematic_sphere_cost.hpp"
#include "calib/internal/kinematic_sphere_seed.hpp"
#include "calib/robot_positioning.hpp"
#include "calib/sweep_bias.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/stats.hpp"

namespace lasercell::calib {

namespace {

constexpr int kJoints = KinematicChainReference::kJoints;
constexpr int kRobotParams = KinematicChainReference::kParameters;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

/// All points of one sweep, flattened, with the profile each came from.
struct FlatSweep {
  std::vector<Eigen::Vector3d> p_in_sensor;
  std::vector<int> profile;
  std::vector<int> selected;  // indices used in the solve
  std::vector<int> seed_inliers;
};

/// The current model: reference chain, hand-eye and spheres, plus the solver's blocks.
struct State {
  KinematicChainReference chain;
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> centres;
  double radius = 0;
  std::array<double, kRobotParams> robot_delta{};
  std::array<double, 6> hand_eye{};
  std::vector<std::array<double, 3>> centre_blocks;

  Eigen::Isometry3d BaseFromSensor(const std::vector<double>& q) const {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    const std::array<double, kRobotParams> zero{};
    chain.BaseFromFlange(q.data(), zero.data(), &r, &t);
    Eigen::Isometry3d base_from_flange = Eigen::Isometry3d::Identity();
    base_from_flange.linear() = r;
    base_from_flange.translation() = t;
    return base_from_flange * flange_from_sensor;
  }
};

/// Column layout of the parameters the Jacobian/covariance talk about.
struct Columns {
  std::vector<std::string> names;
  std::vector<bool> fixable;
  std::vector<int> robot;  // robot parameter index -> column (-1 when not estimated)
  int hand_eye = -1;       // first of 6 columns
  int centres = -1;        // first of 3 S columns
  int radius = -1;
  int count = 0;
};

Columns MakeColumns(const JointIdentificationOptions& o, const std::vector<bool>& robot_estimated,
                    int spheres) {
  Columns c;
  c.robot.assign(kRobotParams, -1);
  for (int k = 0; k < kRobotParams; ++k) {
    if (!robot_estimated[k]) continue;
    c.robot[k] = c.count++;
    c.names.push_back(DhParameterName(k, kJoints));
    c.fixable.push_back(true);
  }
  if (o.estimate_hand_eye) {
    c.hand_eye = c.count;
    for (const char* n : kHandEyeParameterNames) {
      c.names.emplace_back(n);
      c.fixable.push_back(false);
      ++c.count;
    }
  }
  c.centres = c.count;
  for (int s = 0; s < spheres; ++s) {
    for (const char* axis : {"x", "y", "z"}) {
      c.names.push_back("centre_" + std::to_string(s) + "_" + axis);
      c.fixable.push_back(false);
      ++c.count;
    }
  }
  if (o.estimate_radius) {
    c.radius = c.count++;
    c.names.emplace_back("radius");
    c.fixable.push_back(false);
  }
  return c;
}

/// One residual block as the Jacobian assembly needs it.
struct Block {
  ceres::CostFunction* cost;  // owned by the problem
  int sphere;
  bool prior;  // KinematicCentrePrior (centre block only)
  int sweep;
};

/// A Ceres problem over the state, with every residual block remembered.
struct BuiltProblem {
  std::unique_ptr<ceres::Problem> problem;
  std::vector<Block> blocks;
  int rows = 0;
};

BuiltProblem Build(State& st, const std::vector<SphereSweep>& sweeps,
                   const std::vector<FlatSweep>& flat, const JointIdentificationOptions& o,
                   const std::vector<bool>& robot_free, bool robust) {
  BuiltProblem b;
  b.problem = std::make_unique<ceres::Problem>();
  st.robot_delta.fill(0);
  st.hand_eye.fill(0);
  st.centre_blocks.resize(st.centres.size());
  for (std::size_t s = 0; s < st.centres.size(); ++s) {
    for (int i = 0; i < 3; ++i) st.centre_blocks[s][i] = st.centres[s][i];
  }
  ceres::LossFunction* loss = nullptr;
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    const FlatSweep& f = flat[w];
    std::map<int, std::vector<Eigen::Vector3d>> by_profile;
    for (int i : f.selected) by_profile[f.profile[i]].push_back(f.p_in_sensor[i]);
    const int s = sweeps[w].sphere;
    for (auto& [profile, points] : by_profile) {
      std::array<double, kJoints> q{};
      for (int j = 0; j < kJoints; ++j) q[j] = sweeps[w].profiles[profile].joints_rad[j];
      const int n = static_cast<int>(points.size());
      ceres::CostFunction* cost = KinematicSphereCost::Create(&st.chain, &st.flange_from_sensor, q,
                                                              std::move(points), o.point_sigma_mm);
      if (robust) loss = new ceres::HuberLoss(3.0);
      b.problem->AddResidualBlock(cost, loss, st.robot_delta.data(), st.hand_eye.data(),
                                  st.centre_blocks[s].data(), &st.radius);
      b.blocks.push_back({cost, s, false, static_cast<int>(w)});
      b.rows += n;
    }
  }
  for (std::size_t s = 0; s < o.known_centres_in_base.size() && s < st.centres.size(); ++s) {
    ceres::CostFunction* cost =
        KinematicCentrePrior::Create(o.known_centres_in_base[s], o.known_centre_sigma_mm);
    b.problem->AddResidualBlock(cost, nullptr, st.centre_blocks[s].data());
    b.blocks.push_back({cost, static_cast<int>(s), true, -1});
    b.rows += 3;
  }
  std::vector<int> fixed;
  for (int k = 0; k < kRobotParams; ++k) {
    if (!robot_free[k]) fixed.push_back(k);
  }
  if (static_cast<int>(fixed.size()) == kRobotParams) {
    b.problem->SetParameterBlockConstant(st.robot_delta.data());
  } else if (!fixed.empty()) {
    b.problem->SetManifold(st.robot_delta.data(), new ceres::SubsetManifold(kRobotParams, fixed));
  }
  if (!o.estimate_hand_eye) b.problem->SetParameterBlockConstant(st.hand_eye.data());
  if (!o.estimate_radius) b.problem->SetParameterBlockConstant(&st.radius);
  return b;
}

/// Dense Jacobian (rows = residuals in sigma units) over `cols`, and the residuals.
void Evaluate(State& st, const BuiltProblem& b, const Columns& cols, Eigen::MatrixXd* jacobian,
              Eigen::VectorXd* residuals, std::vector<int>* row_sweep) {
  jacobian->setZero(b.rows, cols.count);
  residuals->setZero(b.rows);
  row_sweep->assign(static_cast<std::size_t>(b.rows), -1);
  int row = 0;
  std::vector<double> jr, jh, jc, jrad;
  for (const Block& blk : b.blocks) {
    const int n = blk.cost->num_residuals();
    double* centre = st.centre_blocks[blk.sphere].data();
    if (blk.prior) {
      double* params[] = {centre};
      jc.resize(static_cast<std::size_t>(n) * 3);
      double* jac[] = {jc.data()};
      blk.cost->Evaluate(params, residuals->data() + row, jac);
      for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k)
          (*jacobian)(row + i, cols.centres + 3 * blk.sphere + k) = jc[i * 3 + k];
      }
      row += n;
      continue;
    }
    const double* params[] = {st.robot_delta.data(), st.hand_eye.data(), centre, &st.radius};
    jr.resize(static_cast<std::size_t>(n) * kRobotParams);
    jh.resize(static_cast<std::size_t>(n) * 6);
    jc.resize(static_cast<std::size_t>(n) * 3);
    jrad.resize(static_cast<std::size_t>(n));
    double* jac[] = {jr.data(), jh.data(), jc.data(), jrad.data()};
    blk.cost->Evaluate(params, residuals->data() + row, jac);
    for (int i = 0; i < n; ++i) {
      (*row_sweep)[static_cast<std::size_t>(row + i)] = blk.sweep;
      for (int k = 0; k < kRobotParams; ++k) {
        if (cols.robot[k] >= 0) (*jacobian)(row + i, cols.robot[k]) = jr[i * kRobotParams + k];
      }
      if (cols.hand_eye >= 0) {
        for (int k = 0; k < 6; ++k) (*jacobian)(row + i, cols.hand_eye + k) = jh[i * 6 + k];
      }
      for (int k = 0; k < 3; ++k)
        (*jacobian)(row + i, cols.centres + 3 * blk.sphere + k) = jc[i * 3 + k];
      if (cols.radius >= 0) (*jacobian)(row + i, cols.radius) = jrad[i];
    }
    row += n;
  }
}

/// Folds the solved corrections into the reference (chain parameters, hand-eye, centres).
void Fold(State& st) {
  for (int k = 0; k < kRobotParams; ++k) st.chain.parameters[k] += st.robot_delta[k];
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  PerturbedFlangeFromSensor(st.flange_from_sensor, st.hand_eye.data(), &r, &t);
  // Re-orthonormalize through a quaternion (AngleAxisToRotationMatrix is orthonormal to
  // rounding; this keeps it so over passes).
  st.flange_from_sensor.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  st.flange_from_sensor.translation() = t;
  for (std::size_t s = 0; s < st.centres.size(); ++s) {
    st.centres[s] =
        Eigen::Vector3d(st.centre_blocks[s][0], st.centre_blocks[s][1], st.centre_blocks[s][2]);
  }
  st.robot_delta.fill(0);
  st.hand_eye.fill(0);
}

/// Picks at most `max` indices evenly from `from`.
std::vector<int> Thin(const std::vector<int>& from, int max) {
  if (static_cast<int>(from.size()) <= max) return from;
  std::vector<int> out;
  out.reserve(static_cast<std::size_t>(max));
  for (int k = 0; k < max; ++k) {
    out.push_back(from[static_cast<std::size_t>(
        (static_cast<long long>(k) * static_cast<long long>(from.size())) / max)]);
  }
  return out;
}

/// Rejects motions that leave the hand-eye rotation/translation unobservable: all flange
/// rotations equal (pure translations) or all relative rotations about one axis.
void CheckMotion(const DhChain& robot, const std::vector<SphereSweep>& sweeps) {
  std::vector<Eigen::Matrix3d> rotations;
  for (const SphereSweep& s : sweeps) {
    const SweptProfile& mid = s.profiles[s.profiles.size() / 2];
    rotations.push_back(robot.BaseFromFlange(mid.joints_rad).linear());
  }
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  double largest_deg = 0;
  int pairs = 0;
  for (std::size_t a = 0; a < rotations.size(); ++a) {
    for (std::size_t b = a + 1; b < rotations.size(); ++b) {
      const Eigen::AngleAxisd rel(rotations[a].transpose() * rotations[b]);
      largest_deg = std::max(largest_deg, std::abs(rel.angle()) * kRadToDeg);
      if (std::abs(rel.angle()) * kRadToDeg < 2) continue;
      // Axis in the flange frame (AX = XB: the axes of relative flange motions must span 3-D).
      scatter += rel.axis() * rel.axis().transpose();
      ++pairs;
    }
  }
  if (largest_deg < 2) {
    throw InputError("robot poses: the flange rotates by at most " + std::to_string(largest_deg) +
                     " deg between the sweeps (pure translations): the hand-eye rotation "
                     "and translation are not observable; record poses rotated about "
                     "several axes by >= 10 deg");
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter / pairs);
  if (eig.eigenvalues()[1] < 1e-3) {
    throw InputError(
        "robot poses: every relative flange rotation is about one axis (axis "
        "scatter eigenvalues " +
        std::to_string(eig.eigenvalues()[0]) + ", " + std::to_string(eig.eigenvalues()[1]) +
        "): the hand-eye translation along it is not observable; record poses "
        "rotated about at least two different axes");
  }
}

}  // namespace

void JointIdentificationOptions::Check() const {
  const auto positive = [](double v, const char* field) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw OptionError(std::string("JointIdentificationOptions.") + field +
                        " must be a positive number");
    }
  };
  positive(point_sigma_mm, "point_sigma_mm");
  positive(known_centre_sigma_mm, "known_centre_sigma_mm");
  positive(seed_gate_mm, "seed_gate_mm");
  positive(gate_sigmas, "gate_sigmas");
  positive(min_gate_mm, "min_gate_mm");
  positive(min_radius_mm, "min_radius_mm");
  positive(seed_consistency_mm, "seed_consistency_mm");
  if (!(max_radius_mm > min_radius_mm)) {
    throw OptionError("JointIdentificationOptions.max_radius_mm must exceed min_radius_mm");
  }
  if (!(radius_mm >= 0) || !std::isfinite(radius_mm)) {
    throw OptionError("JointIdentificationOptions.radius_mm must be >= 0 (0: from the data)");
  }
  if (!estimate_radius && radius_mm <= 0) {
    throw OptionError(
        "JointIdentificationOptions.radius_mm must be given (> 0) when "
        "estimate_radius is false");
  }
  if (max_points_per_sweep < 10) {
    throw OptionError("JointIdentificationOptions.max_points_per_sweep must be >= 10");
  }
  if (max_iterations < 1)
    throw OptionError("JointIdentificationOptions.max_iterations must be >= 1");
  if (estimate_dh_deltas && !estimate_joint_offsets) {
    throw OptionError("JointIdentificationOptions.estimate_dh_deltas needs estimate_joint_offsets");
  }
  observability.Check();
}

std::string JointIdentificationResult::Summary() const {
  std::string s = converged ? "converged" : "NOT converged";
  char buf[160];
  std::snprintf(buf, sizeof(buf),
                ", rms %.4f mm over %zu points, %zu sweeps; offsets (deg):", rms_mm, points_used,
                sweeps.size());
  s += buf;
  const int n = static_cast<int>(robot.joints().size());
  for (int j = 0; j < n; ++j) {
    std::snprintf(buf, sizeof(buf), " %.4f", robot.joints()[j].joint_offset_rad * kRadToDeg);
    s += buf;
  }
  if (positioning.poses > 0) {
    std::snprintf(buf, sizeof(buf), "; positioning 1-sigma %.4f mm (RMS over %d poses)",
                  positioning.rms_mm, positioning.poses);
    s += buf;
  }
  const std::vector<std::string> fixed = observability.Fixed();
  if (!fixed.empty()) {
    s += "; fixed (not identifiable):";
    for (const std::string& f : fixed) s += " " + f;
  }
  return s;
}

namespace {

/// Input checks of IdentifyRobot; returns the number of spheres (largest index + 1).
int CheckSweeps(const DhChain& robot, const Eigen::Isometry3d& flange_from_sensor,
                const std::vector<SphereSweep>& sweeps, const JointIdentificationOptions& o) {
  if (robot.NumJoints() != kJoints) {
    throw InputError("robot model: joint identification supports 6-joint chains, got " +
                     std::to_string(robot.NumJoints()) + " joints");
  }
  CheckRigidTransform(flange_from_sensor, "flange_from_sensor");
  if (sweeps.empty()) throw InputError("sphere sweeps: none given; record sweeps from many poses");
  int spheres = 0;
  for (const SphereSweep& s : sweeps) {
    if (s.sphere < 0) {
      throw InputError("sweep '" + s.name + "': sphere index " + std::to_string(s.sphere) +
                       " is negative");
    }
    spheres = std::max(spheres, s.sphere + 1);
    if (s.profiles.empty()) throw InputError("sweep '" + s.name + "' has no profiles");
    for (std::size_t p = 0; p < s.profiles.size(); ++p) {
      const SweptProfile& prof = s.profiles[p];
      if (prof.joints_rad.size() != static_cast<std::size_t>(kJoints)) {
        throw InputError("sweep '" + s.name + "' profile " + std::to_string(p) + ": " +
                         (prof.joints_rad.empty()
                              ? std::string("no joint values recorded")
                              : std::to_string(prof.joints_rad.size()) + " joint values") +
                         "; every profile needs the robot's 6 joint values (rad)");
      }
      for (double q : prof.joints_rad) {
        if (!std::isfinite(q)) {
          throw InputError("sweep '" + s.name + "' profile " + std::to_string(p) +
                           ": a joint value is not finite");
        }
      }
      for (const Eigen::Vector3d& pt : prof.points_in_sensor) {
        if (!pt.allFinite()) {
          throw InputError("sweep '" + s.name + "' profile " + std::to_string(p) +
                           ": a point is not finite");
        }
      }
    }
  }
  if (!o.known_centres_in_base.empty() &&
      static_cast<int>(o.known_centres_in_base.size()) != spheres) {
    throw InputError("known sphere centres: " + std::to_string(o.known_centres_in_base.size()) +
                     " given but the sweeps aim at " + std::to_string(spheres) +
                     " spheres; give one centre per sphere");
  }
  std::vector<int> sweeps_per_sphere(static_cast<std::size_t>(spheres), 0);
  for (const SphereSweep& s : sweeps) ++sweeps_per_sphere[static_cast<std::size_t>(s.sphere)];
  for (int s = 0; s < spheres; ++s) {
    if (sweeps_per_sphere[static_cast<std::size_t>(s)] == 0) {
      throw InputError("sphere sweeps: no sweep aims at sphere " + std::to_string(s) +
                       " (sphere indices must be 0 .. count-1 without gaps)");
    }
  }
  return spheres;
}

// Seed: the initial model places each sweep's points in the base; a local RANSAC finds the
// sphere candidates per sweep (a short sweep sees a nearly rigid copy of it even with model
// errors). Fills `flat` with every point and returns the candidates per sweep.
std::vector<std::vector<internal::SeedSphere>> SeedCandidates(
    const State& st, const std::vector<SphereSweep>& sweeps, const JointIdentificationOptions& o,
    std::vector<FlatSweep>& flat) {
  std::vector<std::vector<internal::SeedSphere>> candidates(sweeps.size());
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    std::vector<Eigen::Vector3d> in_base;
    for (std::size_t p = 0; p < sweeps[w].profiles.size(); ++p) {
      const Eigen::Isometry3d base_from_sensor =
          st.BaseFromSensor(sweeps[w].profiles[p].joints_rad);
      for (const Eigen::Vector3d& pt : sweeps[w].profiles[p].points_in_sensor) {
        flat[w].p_in_sensor.push_back(pt);
        flat[w].profile.push_back(static_cast<int>(p));
        in_base.push_back(base_from_sensor * pt);
      }
    }
    internal::FindSphereOptions fo;
    fo.min_radius_mm = o.radius_mm > 0 ? 0.8 * o.radius_mm : o.min_radius_mm;
    fo.max_radius_mm = o.radius_mm > 0 ? 1.2 * o.radius_mm : o.max_radius_mm;
    fo.inlier_gate_mm = o.seed_gate_mm;
    fo.neighbourhood_mm = 2.5 * (o.radius_mm > 0 ? o.radius_mm : 30.0);
    fo.seed = static_cast<unsigned>(w + 1);
    if (!o.known_centres_in_base.empty()) {
      fo.near_centre = o.known_centres_in_base[static_cast<std::size_t>(sweeps[w].sphere)];
      fo.near_distance_mm = (o.radius_mm > 0 ? o.radius_mm : o.max_radius_mm) + 15;
    }
    candidates[w] = internal::FindSpheres(in_base, fo, o.known_centres_in_base.empty() ? 4 : 1);
    if (candidates[w].empty()) {
      throw InputError("sweep '" + sweeps[w].name + "': no sphere found among its " +
                       std::to_string(in_base.size()) + " points (radius " +
                       std::to_string(o.min_radius_mm) + " .. " + std::to_string(o.max_radius_mm) +
                       " mm); check the sweep and the "
                       "initial robot model / hand-eye transform");
    }
  }
  return candidates;
}

// Each sweep may see several spheres (or a stand); per sphere index, the candidate that most
// sweeps agree on (within seed_consistency_mm: the initial model's error) is the sphere. Sets
// the seed centres and radius of `st` and the seed inliers and selected points of `flat`.
void SeedSpheres(const std::vector<std::vector<internal::SeedSphere>>& candidates,
                 const std::vector<SphereSweep>& sweeps, const JointIdentificationOptions& o,
                 int spheres, State& st, std::vector<FlatSweep>& flat) {
  std::vector<internal::SeedSphere> seeds(sweeps.size());
  st.centres.assign(static_cast<std::size_t>(spheres), Eigen::Vector3d::Zero());
  std::vector<double> radii;
  for (int s = 0; s < spheres; ++s) {
    std::vector<std::size_t> group;
    for (std::size_t w = 0; w < sweeps.size(); ++w) {
      if (sweeps[w].sphere == s) group.push_back(w);
    }
    Eigen::Vector3d consensus = Eigen::Vector3d::Zero();
    int best_support = -1;
    std::size_t best_inliers = 0;
    for (std::size_t w : group) {
      for (const internal::SeedSphere& c : candidates[w]) {
        int support = 0;
        for (std::size_t v : group) {
          for (const internal::SeedSphere& d : candidates[v]) {
            if ((d.centre - c.centre).norm() < o.seed_consistency_mm) {
              ++support;
              break;
            }
          }
        }
        if (support > best_support ||
            (support == best_support && c.inliers.size() > best_inliers)) {
          best_support = support;
          best_inliers = c.inliers.size();
          consensus = c.centre;
        }
      }
    }
    std::vector<double> xs, ys, zs;
    for (std::size_t w : group) {
      const internal::SeedSphere* chosen = nullptr;
      for (const internal::SeedSphere& c : candidates[w]) {
        if (!chosen || (c.centre - consensus).norm() < (chosen->centre - consensus).norm()) {
          chosen = &c;
        }
      }
      if ((chosen->centre - consensus).norm() >= o.seed_consistency_mm) {
        throw InputError("sweep '" + sweeps[w].name + "': the sphere it sees is " +
                         std::to_string((chosen->centre - consensus).norm()) +
                         " mm from where most sweeps of sphere " + std::to_string(s) +
                         " see it; check its aimed_at_sphere index or the initial model");
      }
      seeds[w] = *chosen;
      xs.push_back(chosen->centre.x());
      ys.push_back(chosen->centre.y());
      zs.push_back(chosen->centre.z());
      radii.push_back(chosen->radius_mm);
    }
    st.centres[static_cast<std::size_t>(s)] = Eigen::Vector3d(Median(xs), Median(ys), Median(zs));
  }
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    flat[w].seed_inliers = seeds[w].inliers;
    flat[w].selected = Thin(seeds[w].inliers, o.max_points_per_sweep);
  }
  if (!o.known_centres_in_base.empty()) st.centres = o.known_centres_in_base;
  st.radius = o.radius_mm > 0 ? o.radius_mm : Median(radii);
}

// Observability at the seed decides what is fixed: clears robot_free of every robot parameter
// the analysis fixes; a direction no robot parameter resolves is degenerate data (InputError).
ObservabilityReport FixUnobservable(State& st, const std::vector<SphereSweep>& sweeps,
                                    const std::vector<FlatSweep>& flat,
                                    const JointIdentificationOptions& o, const Columns& all_cols,
                                    std::vector<bool>& robot_free) {
  BuiltProblem b = Build(st, sweeps, flat, o, robot_free, false);
  Eigen::MatrixXd j;
  Eigen::VectorXd r;
  std::vector<int> row_sweep;
  Evaluate(st, b, all_cols, &j, &r, &row_sweep);
  ObservabilityReport seed_obs =
      AnalyzeObservability(j, all_cols.names, all_cols.fixable, o.observability);
  if (seed_obs.degenerate) {
    std::string names;
    for (const std::string& n : seed_obs.directions.back().parameters) {
      names += (names.empty() ? "" : ", ") + n;
    }
    throw InputError("sphere sweeps: the poses cannot separate " + names +
                     " (a direction of the identification Jacobian with relative singular "
                     "value " +
                     std::to_string(seed_obs.directions.back().relative_singular_value) +
                     "); record poses that rotate about several axes and see several spheres");
  }
  for (int k = 0; k < kRobotParams; ++k) {
    if (all_cols.robot[k] >= 0 && !seed_obs.identifiable[all_cols.robot[k]]) robot_free[k] = false;
  }
  return seed_obs;
}

// Re-gate: residuals of every point of every sweep against the model; keeps the points within
// gate_sigmas robust sigmas. Counts the seed inliers dropped when `count_rejected`.
void Regate(const State& st, const std::vector<SphereSweep>& sweeps,
            const JointIdentificationOptions& o, bool count_rejected, std::vector<FlatSweep>& flat,
            JointIdentificationResult& result) {
  std::vector<double> abs_res;
  std::vector<std::vector<double>> res(sweeps.size());
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    const Eigen::Vector3d& c = st.centres[static_cast<std::size_t>(sweeps[w].sphere)];
    std::vector<Eigen::Isometry3d> poses;
    for (const SweptProfile& p : sweeps[w].profiles)
      poses.push_back(st.BaseFromSensor(p.joints_rad));
    res[w].resize(flat[w].p_in_sensor.size());
    for (std::size_t i = 0; i < flat[w].p_in_sensor.size(); ++i) {
      res[w][i] = (poses[static_cast<std::size_t>(flat[w].profile[i])] * flat[w].p_in_sensor[i] - c)
                      .norm() -
                  st.radius;
    }
    for (int i : flat[w].selected) abs_res.push_back(std::abs(res[w][static_cast<std::size_t>(i)]));
  }
  const double gate_mm = std::max(o.min_gate_mm, o.gate_sigmas * 1.4826 * Median(abs_res));
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    std::vector<int> in;
    for (std::size_t i = 0; i < res[w].size(); ++i) {
      if (std::abs(res[w][i]) < gate_mm) in.push_back(static_cast<int>(i));
    }
    if (in.size() < 10) {
      throw InputError("sweep '" + sweeps[w].name + "': only " + std::to_string(in.size()) +
                       " points lie within " + std::to_string(gate_mm) +
                       " mm of its sphere after calibration; drop the sweep or check it");
    }
    flat[w].selected = Thin(in, o.max_points_per_sweep);
    if (count_rejected) {
      std::size_t dropped = 0;
      for (int i : flat[w].seed_inliers) {
        if (std::abs(res[w][static_cast<std::size_t>(i)]) >= gate_mm) ++dropped;
      }
      result.points_rejected += dropped;
    }
  }
}

// Pass 1 robust on the seed inliers; then re-gate every point against the model and solve
// without a robust loss (so the covariance is the plain Gauss-Newton one).
void Solve(State& st, const std::vector<SphereSweep>& sweeps, const JointIdentificationOptions& o,
           const std::vector<bool>& robot_free, std::vector<FlatSweep>& flat,
           JointIdentificationResult& result) {
  for (int pass = 0; pass < 3; ++pass) {
    BuiltProblem b = Build(st, sweeps, flat, o, robot_free, pass == 0);
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = o.max_iterations;
    so.function_tolerance = 1e-12;
    so.parameter_tolerance = 1e-12;
    so.gradient_tolerance = 1e-12;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, b.problem.get(), &summary);
    result.iterations += static_cast<int>(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.termination = summary.message;
    Fold(st);
    if (pass == 2) break;
    Regate(st, sweeps, o, pass == 1, flat, result);
  }
}

/// The Jacobian at the solution and the columns still estimated.
struct FinalJacobian {
  Eigen::MatrixXd j;
  Eigen::VectorXd r;
  std::vector<int> row_sweep;
  std::vector<int> active;  // columns of all_cols that are parameters (not fixed)
};

// Final Jacobian at the solution (all corrections zero: left perturbation at the estimate);
// observability of the active columns and the covariance of every estimated parameter.
FinalJacobian Uncertainty(State& st, const std::vector<SphereSweep>& sweeps,
                          const std::vector<FlatSweep>& flat, const JointIdentificationOptions& o,
                          const Columns& all_cols, const std::vector<bool>& robot_free,
                          const ObservabilityReport& seed_obs, JointIdentificationResult& result) {
  FinalJacobian f;
  BuiltProblem b = Build(st, sweeps, flat, o, robot_free, false);
  Evaluate(st, b, all_cols, &f.j, &f.r, &f.row_sweep);
  // Fixed robot columns are not parameters any more: analyse the rest (and report the earlier
  // decisions).
  for (int c = 0; c < all_cols.count; ++c) {
    bool fixed = false;
    for (int k = 0; k < kRobotParams; ++k) fixed |= (all_cols.robot[k] == c && !robot_free[k]);
    if (!fixed) f.active.push_back(c);
  }
  Eigen::MatrixXd ja(f.j.rows(), static_cast<Eigen::Index>(f.active.size()));
  std::vector<std::string> names;
  std::vector<bool> fixable;
  for (std::size_t c = 0; c < f.active.size(); ++c) {
    ja.col(static_cast<Eigen::Index>(c)) = f.j.col(f.active[c]);
    names.push_back(all_cols.names[static_cast<std::size_t>(f.active[c])]);
    fixable.push_back(all_cols.fixable[static_cast<std::size_t>(f.active[c])]);
  }
  ObservabilityReport final_obs = AnalyzeObservability(ja, names, fixable, o.observability);
  if (!final_obs.directions.empty()) {
    result.warnings.push_back("observability at the solution differs from the seed: " +
                              final_obs.Summary());
  }
  // Report all columns, with the seed's fixing decisions.
  result.observability = seed_obs;
  result.observability.singular_values = final_obs.singular_values;
  result.observability.condition_number = final_obs.condition_number;
  const Eigen::Index m = f.j.rows();
  const double rss = f.r.squaredNorm();
  const double dof = static_cast<double>(m - static_cast<Eigen::Index>(f.active.size()));
  result.variance_factor = dof > 0 ? rss / dof : 0;
  result.covariance = CovarianceFromJacobian(f.j, f.active, result.variance_factor);
  for (int c : f.active)
    result.covariance_names.push_back(all_cols.names[static_cast<std::size_t>(c)]);
  return f;
}

// Results: the identified model, sigmas of the parameters, spheres and hand-eye.
void FillParameters(const DhChain& robot, const State& st, const JointIdentificationOptions& o,
                    const Columns& all_cols, const std::vector<bool>& robot_free,
                    const std::vector<int>& active, int spheres,
                    JointIdentificationResult& result) {
  const auto index_of = [&](int col) {
    for (std::size_t a = 0; a < active.size(); ++a) {
      if (active[a] == col) return static_cast<Eigen::Index>(a);
    }
    return Eigen::Index(-1);
  };
  const auto sigma_of = [&](int col) {
    const Eigen::Index a = index_of(col);
    return a >= 0 ? std::sqrt(result.covariance(a, a)) : 0.0;
  };
  const std::vector<double> input = DhParameterVector(robot);
  std::vector<double> identified(st.chain.parameters.begin(), st.chain.parameters.end());
  result.robot = WithDhParameters(robot, identified);
  result.flange_from_sensor = st.flange_from_sensor;
  for (int k = 0; k < kRobotParams; ++k) {
    result.parameter_names.push_back(DhParameterName(k, kJoints));
    result.parameter_corrections.push_back(identified[static_cast<std::size_t>(k)] -
                                           input[static_cast<std::size_t>(k)]);
    result.parameter_estimated.push_back(robot_free[k]);
    result.parameter_sigmas.push_back(
        all_cols.robot[k] >= 0 && robot_free[k] ? sigma_of(all_cols.robot[k]) : 0.0);
  }
  if (o.estimate_hand_eye) {
    Matrix6d cov;
    for (int a = 0; a < 6; ++a) {
      for (int c = 0; c < 6; ++c) {
        cov(a, c) =
            result.covariance(index_of(all_cols.hand_eye + a), index_of(all_cols.hand_eye + c));
      }
    }
    result.flange_from_sensor_covariance = cov;
  }
  result.sphere_centres_in_base = st.centres;
  for (int s = 0; s < spheres; ++s) {
    result.sphere_centre_sigmas.emplace_back(sigma_of(all_cols.centres + 3 * s),
                                             sigma_of(all_cols.centres + 3 * s + 1),
                                             sigma_of(all_cols.centres + 3 * s + 2));
  }
  result.radius_mm = st.radius;
  result.radius_sigma_mm = all_cols.radius >= 0 ? sigma_of(all_cols.radius) : 0.0;
}

// Residuals in mm, per sweep.
void FillResiduals(const std::vector<SphereSweep>& sweeps, const FinalJacobian& f,
                   const JointIdentificationOptions& o, JointIdentificationResult& result) {
  double sum2 = 0;
  result.sweeps.resize(sweeps.size());
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    result.sweeps[w].name = sweeps[w].name;
    result.sweeps[w].sphere = sweeps[w].sphere;
  }
  std::vector<double> sweep_sum2(sweeps.size(), 0), sweep_sum(sweeps.size(), 0);
  for (Eigen::Index i = 0; i < f.j.rows(); ++i) {
    const int w = f.row_sweep[static_cast<std::size_t>(i)];
    if (w < 0) continue;
    const double mm = f.r[i] * o.point_sigma_mm;
    result.residuals_mm.push_back(mm);
    sum2 += mm * mm;
    SweepResidual& sr = result.sweeps[static_cast<std::size_t>(w)];
    ++sr.points;
    sweep_sum2[static_cast<std::size_t>(w)] += mm * mm;
    sweep_sum[static_cast<std::size_t>(w)] += mm;
    sr.max_abs_mm = std::max(sr.max_abs_mm, std::abs(mm));
  }
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    SweepResidual& sr = result.sweeps[w];
    if (sr.points == 0) continue;
    sr.rms_mm = std::sqrt(sweep_sum2[w] / static_cast<double>(sr.points));
    sr.mean_mm = sweep_sum[w] / static_cast<double>(sr.points);
  }
  result.points_used = result.residuals_mm.size();
  result.rms_mm =
      std::sqrt(sum2 / static_cast<double>(std::max<std::size_t>(1, result.points_used)));
}

}  // namespace

JointIdentificationResult IdentifyRobot(const DhChain& robot,
                                        const Eigen::Isometry3d& flange_from_sensor,
                                        const std::vector<SphereSweep>& sweeps,
                                        const JointIdentificationOptions& o) {
  o.Check();
  const int spheres = CheckSweeps(robot, flange_from_sensor, sweeps, o);
  std::vector<bool> robot_estimated(kRobotParams, false);
  for (int k = 0; k < kRobotParams; ++k) {
    robot_estimated[k] = (k < kJoints) ? o.estimate_joint_offsets : o.estimate_dh_deltas;
  }
  // Counting: a sweep of a sphere fixes about 3 pose quantities (its centre seen from the pose)
  // plus the radius; the unknowns are the model parameters and 3 per free sphere centre.
  const Columns all_cols = MakeColumns(o, robot_estimated, spheres);
  const int constraints =
      3 * static_cast<int>(sweeps.size()) + (o.known_centres_in_base.empty() ? 0 : 3 * spheres) + 1;
  if (constraints <= all_cols.count) {
    throw InputError("sphere sweeps: " + std::to_string(sweeps.size()) + " poses give about " +
                     std::to_string(constraints) + " constraints, not more than the " +
                     std::to_string(all_cols.count) +
                     " parameters to estimate (robot, hand-eye, sphere centres, radius); "
                     "record more poses");
  }
  if (o.estimate_hand_eye) CheckMotion(robot, sweeps);

  State st;
  st.chain = KinematicChainReference::From(robot);
  st.flange_from_sensor = flange_from_sensor;
  std::vector<FlatSweep> flat(sweeps.size());
  SeedSpheres(SeedCandidates(st, sweeps, o, flat), sweeps, o, spheres, st, flat);

  JointIdentificationResult result;
  std::vector<bool> robot_free = robot_estimated;
  const ObservabilityReport seed_obs = FixUnobservable(st, sweeps, flat, o, all_cols, robot_free);
  Solve(st, sweeps, o, robot_free, flat, result);
  const FinalJacobian f = Uncertainty(st, sweeps, flat, o, all_cols, robot_free, seed_obs, result);
  FillParameters(robot, st, o, all_cols, robot_free, f.active, spheres, result);
  FillResiduals(sweeps, f, o, result);
  result.positioning = PositioningAtSweeps(result, sweeps);
  result.sweep_bias_ratio = SweepBiasRatio(result.sweeps);
  if (result.sweep_bias_ratio > kSweepBiasWarningRatio) {
    result.warnings.push_back(
        "the sweeps' mean residuals are " + FormatFixed(std::sqrt(result.sweep_bias_ratio), 1) +
        "x what their own scatter explains (F = " + FormatFixed(result.sweep_bias_ratio, 1) +
        "): the model misses something -- " +
        (o.estimate_dh_deltas ? std::string("the sphere radius or centres, or the hand-eye")
                              : std::string("link lengths off the nominal? estimate DH deltas")));
  }
  if (!result.converged) result.warnings.push_back("Ceres did not converge: " + result.termination);
  return result;
}

}  // namespace lasercell::calib
