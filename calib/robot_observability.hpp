#pragma once
// Observability of a least-squares identification problem (robot calibration): which
// parameters the data determine, from the singular values of the column-scaled Jacobian.
//
// Column scaling (each column divided by its norm) makes the singular values independent of the
// parameters' units (mm vs rad), so the condition number compares like with like (Hollerbach &
// Wampler 1996, "The calibration index and taxonomy for robot kinematic calibration methods",
// sec. 4). A direction v with sigma_i / sigma_max below `relative_tolerance` is a combination
// of parameters the data cannot see (e.g. a joint-1 offset and a rotation of every sphere centre
// about the base z axis); the parameters with large |v_k| are "not separable" from each other.
// AnalyzeObservability resolves each such direction by fixing (holding at its prior value) the
// fixable parameter with the largest component, and repeats until the rest is identifiable.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace lasercell::calib {

/// Options of AnalyzeObservability.
struct ObservabilityOptions {
  /// A scaled singular value below relative_tolerance * sigma_max is treated as zero
  /// (unidentifiable direction). Dimensionless; default 1e-7.
  double relative_tolerance = 1e-7;
  /// A parameter belongs to an unidentifiable direction when |v_k| >= this (unit vector v).
  double component_threshold = 0.1;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// One unidentifiable direction found (and how it was resolved).
struct UnidentifiableDirection {
  double relative_singular_value = 0;   ///< sigma / sigma_max when found.
  std::vector<std::string> parameters;  ///< Parameters with |v_k| >= component_threshold.
  std::vector<double> components;       ///< Their components of the unit null vector.
  std::string fixed_parameter;          ///< The parameter held fixed ("" when none was fixable).
};

/// What the Jacobian says about the parameters.
struct ObservabilityReport {
  std::vector<std::string> parameters;  ///< All columns, in order.
  std::vector<bool> identifiable;       ///< Per column: false when fixed by the analysis.
  Eigen::VectorXd singular_values;      ///< Scaled, descending, over identifiable columns.
  double condition_number = 0;          ///< sigma_max / sigma_min over identifiable columns.
  std::vector<UnidentifiableDirection> directions;  ///< In the order found.
  /// True when a direction involved no fixable parameter (the data are degenerate for the
  /// quantities that must be estimated); `directions.back()` names it.
  bool degenerate = false;
  /// Names of the parameters fixed by the analysis.
  std::vector<std::string> Fixed() const;
  /// One line: condition number, unidentifiable parameters.
  std::string Summary() const;
};

/// Analyses a dense Jacobian (rows = residuals, one column per parameter named in `names`).
/// Only columns with `fixable[k]` may be fixed. Zero columns count as unidentifiable.
/// Throws InputError when the sizes disagree or there are fewer rows than columns.
ObservabilityReport AnalyzeObservability(const Eigen::MatrixXd& jacobian,
                                         const std::vector<std::string>& names,
                                         const std::vector<bool>& fixable,
                                         const ObservabilityOptions& options = {});

/// Covariance (JᵀJ)⁻¹ * variance_factor over the columns in `columns`, computed through a
/// column-scaled QR for accuracy. Throws InternalError when the block is rank deficient.
Eigen::MatrixXd CovarianceFromJacobian(const Eigen::MatrixXd& jacobian,
                                       const std::vector<int>& columns, double variance_factor);

}  // namespace lasercell::calib
