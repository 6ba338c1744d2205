// IntrinsicsResult's summaries and the lens-inversion assessment of a solved calibration.
#include <Eigen/Geometry>
#include <cstdio>
#include <string>

#include "calib/camera_model.hpp"
#include "calib/intrinsics.hpp"
#include "core/format.hpp"

namespace lasercell::calib {
std::string IntrinsicsResult::Summary() const {
  std::string s = (camera ? camera->lensmodel() : std::string("no model")) + ": rms " +
                  FormatFixed(rms_px, 3) + " px over " + std::to_string(num_corners) + " corners";
  int used = 0;
  for (const ViewResult& v : views) used += v.used ? 1 : 0;
  s += " in " + std::to_string(used) + "/" + std::to_string(views.size()) + " views, " +
       std::to_string(num_outliers) + " outliers";
  if (camera) {
    s += ", fx " + FormatFixed(camera->intrinsics()[0], 3);
    if (!intrinsics_sigma.empty()) s += " +- " + FormatFixed(intrinsics_sigma[0], 3);
  }
  s += ", " + std::to_string(iterations) + " iterations";
  if (!converged) s += ", NOT CONVERGED";
  if (!focal_observable) s += ", FOCAL UNOBSERVABLE";
  if (!invertible) s += ", NOT INVERTIBLE WHERE OBSERVED";
  if (imager_fraction_without_ray > 0) {
    s += ", no ray at " + FormatFixed(100 * imager_fraction_without_ray, 1) + " % of the imager";
  } else if (imager_folds) {
    s += ", folds over beyond the observed corners";
  }
  if (!warnings.empty()) s += ", " + std::to_string(warnings.size()) + " warning(s)";
  return s;
}

std::string IntrinsicsResult::RejectionReason() const {
  if (!camera) return "no lens model was solved";
  // Every reason, not the first: a solve that does not converge on views that leave the focal
  // length unobservable must say why it could not converge.
  std::string reasons;
  const auto add = [&reasons](const std::string& reason) {
    reasons += (reasons.empty() ? "" : "; ") + reason;
  };
  if (!converged) add("the solver did not converge: " + termination);
  if (!focal_observable) {
    add(focal_problem.empty() ? "the focal length is unobservable" : focal_problem);
  }
  if (!invertible) {
    add(inversion_problem.empty() ? "the lens model is not invertible" : inversion_problem);
  }
  return reasons;
}

void AssessLensInversion(IntrinsicsResult* result) {
  if (!result->camera) return;
  std::vector<Eigen::Vector2d> observed;
  for (const CornerResidual& c : result->corners) {
    if (!c.outlier) observed.push_back(c.observed_px);
  }
  // Among the corners (their convex hull), not their bounding box: the box's corners can lie
  // far from every board, where the model is as much extrapolation as outside it.
  const LensInversionCheck inside = CheckLensInversionWithin(*result->camera, observed);
  const LensInversionCheck imager = CheckLensInversion(*result->camera);
  result->imager_fraction_without_ray = imager.FractionWithoutRay();
  result->imager_folds = !imager.ok();
  if (!observed.empty() && !inside.ok()) {
    result->invertible = false;
    result->inversion_problem = inside.Describe() +
                                ", among the observed corners, where the boards pinned it "
                                "down; use a lower-order model (OPENCV5)";
    result->warnings.push_back(result->inversion_problem);
  } else if (imager.without_ray == 0 && imager.reversed_cells == 0 && !imager.ok()) {
    result->warnings.push_back(imager.Describe() +
                               "; rays near that ring are wrong wherever it lies: use a "
                               "lower-order model (OPENCV5)");
  } else if (!imager.ok()) {
    result->warnings.push_back(
        imager.Describe() +
        ", outside the observed corners; rays there are extrapolation: add views that reach "
        "the image corners, or use a lower-order model (OPENCV5)");
  }
}

}  // namespace lasercell::calib
