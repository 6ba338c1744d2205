// IntrinsicsResult's summaries and the lens-inversion assessment of a solved calibration.
#include <Eigen/Geometry>
#include <cstdio>
#include <string>

#include "calib/camera_model.hpp"
#include "calib/intrinsics.hpp"

namespace lasercell::calib {
namespace {

std::string Fixed(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

std::string IntrinsicsResult::Summary() const {
  std::string s = (camera ? camera->lensmodel() : std::string("no model")) + ": rms " +
                  Fixed(rms_px) + " px over " + std::to_string(num_corners) + " corners";
  int used = 0;
  for (const ViewResult& v : views) used += v.used ? 1 : 0;
  s += " in " + std::to_string(used) + "/" + std::to_string(views.size()) + " views, " +
       std::to_string(num_outliers) + " outliers";
  if (camera) {
    s += ", fx " + Fixed(camera->intrinsics()[0]);
    if (!intrinsics_sigma.empty()) s += " +- " + Fixed(intrinsics_sigma[0]);
  }
  s += ", " + std::to_string(iterations) + " iterations";
  if (!converged) s += ", NOT CONVERGED";
  if (!focal_observable) s += ", FOCAL UNOBSERVABLE";
  if (!invertible) s += ", NOT INVERTIBLE WHERE OBSERVED";
  if (imager_fraction_without_ray > 0)
    s += ", no ray at " + Fixed(100 * imager_fraction_without_ray, 1) + " % of the imager";
  if (!warnings.empty()) s += ", " + std::to_string(warnings.size()) + " warning(s)";
  return s;
}

std::string IntrinsicsResult::RejectionReason() const {
  if (!camera) return "no lens model was solved";
  if (!converged) return "the solver did not converge: " + termination;
  const auto warning_with = [this](const std::string& key, const std::string& fallback) {
    for (const std::string& w : warnings) {
      if (w.find(key) != std::string::npos) return w;
    }
    return fallback;
  };
  if (!focal_observable) return warning_with("focal length", "the focal length is unobservable");
  if (!invertible) return warning_with("where the board", "the lens model is not invertible");
  return "";
}

void AssessLensInversion(IntrinsicsResult* result) {
  if (!result->camera) return;
  Eigen::AlignedBox2d observed;
  for (const CornerResidual& c : result->corners) {
    if (!c.outlier) observed.extend(c.observed_px);
  }
  const LensInversionCheck inside = CheckLensInversion(*result->camera, observed);
  const LensInversionCheck imager = CheckLensInversion(*result->camera);
  result->imager_fraction_without_ray = imager.FractionWithoutRay();
  if (!observed.isEmpty() && !inside.ok()) {
    result->invertible = false;
    result->warnings.push_back(inside.Describe() +
                               ", inside the box of the observed corners, where the board "
                               "pinned it down; use a lower-order model (OPENCV5)");
  } else if (!imager.ok()) {
    result->warnings.push_back(
        imager.Describe() +
        ", outside the observed corners; rays there are extrapolation: add views that reach "
        "the image corners, or use a lower-order model (OPENCV5)");
  }
}

}  // namespace lasercell::calib
