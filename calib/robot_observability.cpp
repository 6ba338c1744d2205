#include "calib/robot_observability.hpp"

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.hpp"

namespace lasercell::calib {

namespace {

/// Scaled singular values and right singular vectors of the given columns.
struct ScaledSvd {
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;  // columns = right singular vectors (in scaled coordinates)
};

ScaledSvd SvdOfColumns(const Eigen::MatrixXd& jacobian, const std::vector<int>& columns) {
  Eigen::MatrixXd j(jacobian.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const double norm = jacobian.col(columns[c]).norm();
    j.col(static_cast<Eigen::Index>(c)) = norm > 0
                                              ? Eigen::VectorXd(jacobian.col(columns[c]) / norm)
                                              : Eigen::VectorXd::Zero(jacobian.rows());
  }
  // QR first: the SVD of the small triangular factor has the same singular values.
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(j);
  const Eigen::Index n = j.cols();
  const Eigen::MatrixXd r = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(r, Eigen::ComputeFullV);
  return {svd.singularValues(), svd.matrixV()};
}

}  // namespace

void ObservabilityOptions::Check() const {
  if (!(relative_tolerance > 0 && relative_tolerance < 1)) {
    throw OptionError("ObservabilityOptions.relative_tolerance must be in (0, 1)");
  }
  if (!(component_threshold > 0 && component_threshold < 1)) {
    throw OptionError("ObservabilityOptions.component_threshold must be in (0, 1)");
  }
}

std::vector<std::string> ObservabilityReport::Fixed() const {
  std::vector<std::string> fixed;
  for (const UnidentifiableDirection& d : directions) {
    if (!d.fixed_parameter.empty()) fixed.push_back(d.fixed_parameter);
  }
  return fixed;
}

std::string ObservabilityReport::Summary() const {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "condition number %.3g over %d parameters", condition_number,
                static_cast<int>(singular_values.size()));
  std::string s = buf;
  for (const UnidentifiableDirection& d : directions) {
    s += "; not identifiable: ";
    for (std::size_t i = 0; i < d.parameters.size(); ++i) s += (i ? " ~ " : "") + d.parameters[i];
    s += d.fixed_parameter.empty() ? " (nothing fixable)" : " (fixed " + d.fixed_parameter + ")";
  }
  return s;
}

ObservabilityReport AnalyzeObservability(const Eigen::MatrixXd& jacobian,
                                         const std::vector<std::string>& names,
                                         const std::vector<bool>& fixable,
                                         const ObservabilityOptions& options) {
  options.Check();
  const Eigen::Index n = jacobian.cols();
  if (static_cast<Eigen::Index>(names.size()) != n ||
      static_cast<Eigen::Index>(fixable.size()) != n) {
    throw InputError("AnalyzeObservability: " + std::to_string(n) + " Jacobian columns but " +
                     std::to_string(names.size()) + " names and " + std::to_string(fixable.size()) +
                     " fixable flags");
  }
  if (jacobian.rows() < n) {
    throw InputError("AnalyzeObservability: " + std::to_string(jacobian.rows()) +
                     " residuals for " + std::to_string(n) +
                     " parameters; the data cannot determine more parameters than residuals");
  }
  ObservabilityReport report;
  report.parameters = names;
  report.identifiable.assign(static_cast<std::size_t>(n), true);
  std::vector<int> active;
  for (int k = 0; k < n; ++k) active.push_back(k);
  while (!active.empty()) {
    const ScaledSvd svd = SvdOfColumns(jacobian, active);
    const double smax = svd.values[0];
    const Eigen::Index last = svd.values.size() - 1;
    const double ratio = smax > 0 ? svd.values[last] / smax : 0;
    if (ratio >= options.relative_tolerance) {
      report.singular_values = svd.values;
      report.condition_number = 1 / ratio;
      break;
    }
    const Eigen::VectorXd v = svd.vectors.col(last);
    UnidentifiableDirection dir;
    dir.relative_singular_value = ratio;
    int best = -1;
    double best_abs = 0;
    std::vector<std::pair<double, int>> members;
    for (std::size_t c = 0; c < active.size(); ++c) {
      const double a = std::abs(v[static_cast<Eigen::Index>(c)]);
      if (a >= options.component_threshold) members.emplace_back(a, static_cast<int>(c));
      if (fixable[active[c]] && a > best_abs) {
        best_abs = a;
        best = static_cast<int>(c);
      }
    }
    std::sort(members.begin(), members.end(), [](auto& x, auto& y) { return x.first > y.first; });
    for (const auto& [a, c] : members) {
      dir.parameters.push_back(names[active[c]]);
      dir.components.push_back(v[c]);
    }
    if (best < 0 || best_abs < options.component_threshold) {
      report.directions.push_back(dir);
      report.degenerate = true;
      report.singular_values = svd.values;
      report.condition_number = ratio > 0 ? 1 / ratio : INFINITY;
      return report;
    }
    dir.fixed_parameter = names[active[best]];
    report.identifiable[active[best]] = false;
    report.directions.push_back(dir);
    active.erase(active.begin() + best);
  }
  return report;
}

Eigen::MatrixXd CovarianceFromJacobian(const Eigen::MatrixXd& jacobian,
                                       const std::vector<int>& columns, double variance_factor) {
  const Eigen::Index n = static_cast<Eigen::Index>(columns.size());
  Eigen::MatrixXd j(jacobian.rows(), n);
  Eigen::VectorXd scale(n);
  for (Eigen::Index c = 0; c < n; ++c) {
    scale[c] = jacobian.col(columns[c]).norm();
    if (!(scale[c] > 0)) throw InternalError("CovarianceFromJacobian: a zero Jacobian column");
    j.col(c) = jacobian.col(columns[c]) / scale[c];
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(j);
  if (qr.rank() < n) throw InternalError("CovarianceFromJacobian: rank-deficient Jacobian");
  // (Js^T Js)^-1 = P R^-1 R^-T P^T; unscale: Cov = D^-1 (Js^T Js)^-1 D^-1.
  const Eigen::MatrixXd r = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inv =
      r.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(n, n));
  const Eigen::MatrixXd inner = r_inv * r_inv.transpose();
  const Eigen::MatrixXd p = qr.colsPermutation();
  Eigen::MatrixXd cov = p * inner * p.transpose();
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) cov(a, b) *= variance_factor / (scale[a] * scale[b]);
  }
  return cov;
}

}  // namespace lasercell::calib
