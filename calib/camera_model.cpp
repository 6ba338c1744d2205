#include "calib/camera_model.hpp"

extern "C" {
#include <mrcal/mrcal.h>  // C library without extern "C" guards
}

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <utility>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/number_list.hpp"

namespace lasercell::calib {
namespace {

mrcal_lensmodel_t ParseLensmodel(const std::string& name) {
  mrcal_lensmodel_t lens;
  if (!mrcal_lensmodel_from_name(&lens, name.c_str()) ||
      !mrcal_lensmodel_type_is_valid(lens.type)) {
    throw InputError("lens model '" + name +
                     "' is not a configured mrcal model name (e.g. LENSMODEL_OPENCV8 or "
                     "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100)");
  }
  return lens;
}

// mrcal's .cameramodel lexer trusts its buffer to hold a complete model: a quoted string or a
// bracket left open by a truncated file makes it read past the end of the buffer (SIGSEGV).
// This check, at lasercell's boundary, lets only complete texts through: no NUL byte, every
// string closed on its line, brackets balanced, and a top-level { ... } present.
void CheckCompleteModelText(const std::string& text, const std::string& name) {
  int line = 1;
  int depth = 0;
  bool opened = false;
  const auto fail = [&](const std::string& what) {
    throw FileError(name, "line " + std::to_string(line) + ": " + what +
                              " (truncated or not a mrcal .cameramodel?)");
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\0') fail("contains a NUL byte; a .cameramodel is text");
    if (c == '\n') {
      ++line;
    } else if (c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
    } else if (c == '\'' || c == '"') {
      const char stops[] = {c, '\n', '\0'};
      const std::size_t close = text.find_first_of(stops, i + 1);
      if (close == std::string::npos || text[close] != c) fail("a quoted string is not closed");
      i = close;
    } else if (c == '{' || c == '[' || c == '(') {
      ++depth;
      opened = true;
    } else if (c == '}' || c == ']' || c == ')') {
      if (--depth < 0) fail(std::string("a closing '") + c + "' closes nothing");
    }
  }
  if (!opened) fail("no '{' starts the model");
  if (depth != 0) fail("the model's brackets are not all closed");
}

using ModelPtr = std::unique_ptr<mrcal_cameramodel_t, void (*)(mrcal_cameramodel_t*)>;

ModelPtr Guard(mrcal_cameramodel_t* model) {
  return ModelPtr(model, [](mrcal_cameramodel_t* m) { mrcal_free_cameramodel(&m); });
}

CameraModel FromMrcal(const mrcal_cameramodel_t& m, const std::string& name) {
  char buffer[1024];
  if (!mrcal_lensmodel_name(buffer, sizeof(buffer), &m.lensmodel)) {
    throw FileError(name, "its lens model has no printable mrcal name");
  }
  const int n = mrcal_lensmodel_num_params(&m.lensmodel);
  try {
    return CameraModel(buffer, std::vector<double>(m.intrinsics, m.intrinsics + n),
                       static_cast<int>(m.imagersize[0]), static_cast<int>(m.imagersize[1]));
  } catch (const InputError& e) {
    throw FileError(name, e.what());
  }
}

constexpr char kCovarianceKey[] = "lasercell_intrinsics_covariance";

/// The text without its comments (a '#' outside quotes up to the end of the line).
std::string WithoutComments(const std::string& text) {
  std::string out;
  char quote = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quote == 0 && c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (c == '\'' || c == '"') quote = quote == 0 ? c : (quote == c ? 0 : quote);
    out += c;
  }
  return out;
}

/// The covariance stored under kCovarianceKey (empty when the key is absent). FileError when
/// its value is not a list of n * n numbers.
Eigen::MatrixXd ParseCovarianceKey(const std::string& text, const std::string& name, int n) {
  const std::string code = WithoutComments(text);
  std::size_t at = std::string::npos;
  const std::string key = kCovarianceKey;
  for (const std::string& quoted : {"'" + key + "'", "\"" + key + "\""}) {
    const std::size_t k = code.find(quoted);
    if (k != std::string::npos) at = k + quoted.size();
  }
  if (at == std::string::npos) return {};
  const std::size_t open = code.find('[', at);
  const std::size_t close = open == std::string::npos ? open : code.find(']', open);
  const std::string between = code.substr(at, open == std::string::npos ? 0 : open - at);
  if (close == std::string::npos || between.find_first_not_of(" \t\r\n:") != std::string::npos) {
    throw FileError(name, std::string("'") + kCovarianceKey +
                              "' must be followed by a list [ ... ] of numbers");
  }
  std::string list;
  for (const char c : code.substr(open + 1, close - open - 1)) {
    if (!std::isspace(static_cast<unsigned char>(c))) list += c;
  }
  if (!list.empty() && list.back() == ',') list.pop_back();
  std::vector<double> values;
  try {
    values = ParseNumberList(list, kCovarianceKey, static_cast<std::size_t>(n) * n);
  } catch (const OptionError&) {
    throw FileError(name, std::string("'") + kCovarianceKey + "' must hold " +
                              std::to_string(n * n) + " finite numbers (the " + std::to_string(n) +
                              " x " + std::to_string(n) +
                              " covariance of the intrinsics, row-major); remove the key if the "
                              "covariance is unknown");
  }
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), n, n);
}

}  // namespace

CameraModel::CameraModel(std::string lensmodel, std::vector<double> intrinsics, int width_px,
                         int height_px)
    : lensmodel_(std::move(lensmodel)),
      intrinsics_(std::move(intrinsics)),
      width_px_(width_px),
      height_px_(height_px) {
  lens_ = ParseLensmodel(lensmodel_);
  const int n = mrcal_lensmodel_num_params(&lens_);
  if (static_cast<int>(intrinsics_.size()) != n) {
    throw InputError("lens model " + lensmodel_ + " needs " + std::to_string(n) +
                     " intrinsics, got " + std::to_string(intrinsics_.size()));
  }
  for (std::size_t i = 0; i < intrinsics_.size(); ++i) {
    if (!std::isfinite(intrinsics_[i])) {
      throw InputError("intrinsic " + std::to_string(i) + " of the " + lensmodel_ +
                       " camera is not finite");
    }
  }
  if (width_px_ <= 0 || height_px_ <= 0) {
    throw InputError("camera imager size " + std::to_string(width_px_) + " x " +
                     std::to_string(height_px_) + " px must be positive");
  }
}

void CameraModel::SetIntrinsicsCovariance(const Eigen::MatrixXd& covariance) {
  if (covariance.size() == 0) {
    intrinsics_covariance_.resize(0, 0);
    return;
  }
  const int n = NumIntrinsics();
  if (covariance.rows() != n || covariance.cols() != n) {
    throw InputError("the intrinsics covariance of the " + lensmodel_ + " camera must be " +
                     std::to_string(n) + " x " + std::to_string(n) + ", got " +
                     std::to_string(covariance.rows()) + " x " + std::to_string(covariance.cols()));
  }
  if (!covariance.allFinite()) {
    throw InputError("the intrinsics covariance of the " + lensmodel_ + " camera is not finite");
  }
  const double scale = covariance.cwiseAbs().maxCoeff();
  if ((covariance - covariance.transpose()).cwiseAbs().maxCoeff() > 1e-6 * scale) {
    throw InputError("the intrinsics covariance of the " + lensmodel_ + " camera is not symmetric");
  }
  if ((covariance.diagonal().array() < 0).any()) {
    throw InputError("the intrinsics covariance of the " + lensmodel_ +
                     " camera has a negative variance on its diagonal");
  }
  intrinsics_covariance_ = 0.5 * (covariance + covariance.transpose());
}

bool CameraModel::HasGradients() const { return mrcal_lensmodel_metadata(&lens_).has_gradients; }

Eigen::Vector2d CameraModel::Project(const Eigen::Vector3d& p_in_camera) const {
  return ProjectWithIntrinsics(intrinsics_.data(), p_in_camera, nullptr, nullptr);
}

Eigen::Vector2d CameraModel::Project(
    const Eigen::Vector3d& p_in_camera, Eigen::Matrix<double, 2, 3>* dq_dp,
    Eigen::Matrix<double, 2, Eigen::Dynamic>* dq_dintrinsics) const {
  std::vector<double> dqdi;
  if (dq_dintrinsics != nullptr) dqdi.resize(2 * intrinsics_.size());
  const Eigen::Vector2d q = ProjectWithIntrinsics(
      intrinsics_.data(), p_in_camera, dq_dp, dq_dintrinsics != nullptr ? dqdi.data() : nullptr);
  if (dq_dintrinsics != nullptr) {
    const int n = NumIntrinsics();
    dq_dintrinsics->resize(2, n);
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < n; ++c) (*dq_dintrinsics)(r, c) = dqdi[r * n + c];
    }
  }
  return q;
}

Eigen::Vector2d CameraModel::ProjectWithIntrinsics(const double* intrinsics,
                                                   const Eigen::Vector3d& p_in_camera,
                                                   Eigen::Matrix<double, 2, 3>* dq_dp,
                                                   double* dq_dintrinsics_row_major) const {
  const mrcal_point3_t p = {{p_in_camera.x(), p_in_camera.y(), p_in_camera.z()}};
  mrcal_point2_t q;
  mrcal_point3_t dqdp[2];
  if (!mrcal_project(&q, dq_dp != nullptr ? dqdp : nullptr, dq_dintrinsics_row_major, &p, 1, &lens_,
                     intrinsics)) {
    throw InternalError("mrcal_project failed for lens model " + lensmodel_);
  }
  if (dq_dp != nullptr) {
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 3; ++c) (*dq_dp)(r, c) = dqdp[r].xyz[c];
    }
  }
  return {q.x, q.y};
}

Eigen::Vector3d CameraModel::Unproject(const Eigen::Vector2d& pixel) const {
  return UnprojectMany({pixel}).front();
}

std::vector<Eigen::Vector3d> CameraModel::UnprojectMany(
    const std::vector<Eigen::Vector2d>& pixels) const {
  std::vector<mrcal_point2_t> q(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) q[i] = {{pixels[i].x(), pixels[i].y()}};
  std::vector<mrcal_point3_t> v(pixels.size());
  if (!pixels.empty() && !mrcal_unproject(v.data(), q.data(), static_cast<int>(q.size()), &lens_,
                                          intrinsics_.data())) {
    throw InternalError("mrcal_unproject failed for lens model " + lensmodel_);
  }
  std::vector<Eigen::Vector3d> rays(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    rays[i] = Eigen::Vector3d(v[i].x, v[i].y, v[i].z).normalized();
  }
  return rays;
}

bool CameraModel::InImage(const Eigen::Vector2d& pixel) const {
  return pixel.x() >= 0.0 && pixel.y() >= 0.0 && pixel.x() <= width_px_ - 1.0 &&
         pixel.y() <= height_px_ - 1.0;
}

std::string LensInversionCheck::Describe() const {
  if (ok()) return "";
  if (without_ray == 0 && reversed_cells == 0) {
    return "the radial distortion turns back " + FormatFixed(radial_fold_px, 1) +
           " px from the principal point (its high-order terms cancel where the boards were and "
           "diverge there): the lens model folds over on that ring";
  }
  if (without_ray > 0) {
    return std::to_string(without_ray) + " of " + std::to_string(pixels) +
           " grid pixels have no ray that projects back (worst " + FormatDouble(worst_px) +
           " px, first at column " + FormatDouble(first_bad_px.x()) + ", row " +
           FormatDouble(first_bad_px.y()) + "): the lens model folds over there";
  }
  return std::to_string(reversed_cells) + " of " + std::to_string(cells) +
         " grid cells map to rays in reversed order: the lens model folds over there";
}

namespace {

// Distorted normalized radius at which an OPENCV model's radial map g(r) = r * N(r^2) / D(r^2)
// (N = 1 + k1 r^2 + k2 r^4 + k3 r^6, D = 1 + k4 r^2 + k5 r^4 + k6 r^6; Brown-Conrady with
// OpenCV's rational extension) stops increasing or D reaches zero, marching r outwards until g
// passes `needed`; +inf when it passes without turning back or the model is not OPENCV. The
// tangential terms (p1, p2, ~1e-4 here) are left out: they shift, not fold.
double RadialFoldRadius(const CameraModel& model, double needed) {
  const std::string& name = model.lensmodel();
  if (name.rfind("LENSMODEL_OPENCV", 0) != 0) return std::numeric_limits<double>::infinity();
  const std::vector<double>& in = model.intrinsics();
  const auto k = [&](std::size_t i) { return i < in.size() ? in[i] : 0.0; };
  const double k1 = k(4), k2 = k(5), k3 = k(8), k4 = k(9), k5 = k(10), k6 = k(11);
  const auto g = [&](double r, bool* bad) {
    const double s = r * r;
    const double den = 1 + s * (k4 + s * (k5 + s * k6));
    *bad = !(den > 0);
    return r * (1 + s * (k1 + s * (k2 + s * k3))) / den;
  };
  constexpr double kStep = 1e-4;  // normalized radius: ~0.1 px at fx ~ 1000
  double previous = 0;
  for (double r = kStep; r < 20.0; r += kStep) {
    bool bad = false;
    const double value = g(r, &bad);
    if (bad || !(value > previous)) return previous;
    if (value >= needed) return std::numeric_limits<double>::infinity();
    previous = value;
  }
  return std::numeric_limits<double>::infinity();
}

/// CheckLensInversion over `region` (empty: the whole imager); with `hull` (a convex polygon,
/// counter-clockwise or clockwise), only pixels inside it, and cells whose three grid pixels are
/// inside it, count.
LensInversionCheck CheckGrid(const CameraModel& model, const Eigen::AlignedBox2d& region,
                             const std::vector<cv::Point2f>* hull, int grid, double tolerance_px) {
  if (grid < 2) throw InputError("lens inversion check: grid " + std::to_string(grid) + " < 2");
  if (!(tolerance_px > 0)) {
    throw InputError("lens inversion check: tolerance_px " + FormatDouble(tolerance_px) +
                     " must be positive");
  }
  // The imager's full extent: pixel centres are integers, so its edges lie half a pixel beyond
  // the outer centres (the triangulator's lookup tables reach them too).
  const Eigen::AlignedBox2d imager(
      Eigen::Vector2d(-0.5, -0.5),
      Eigen::Vector2d(model.width_px() - 0.5, model.height_px() - 0.5));
  const Eigen::AlignedBox2d box = region.isEmpty() ? imager : region.intersection(imager);
  LensInversionCheck check;
  if (box.isEmpty()) return check;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(static_cast<std::size_t>(grid) * grid);
  for (int j = 0; j < grid; ++j) {
    for (int i = 0; i < grid; ++i) {
      pixels.push_back(box.min() + (box.max() - box.min())
                                       .cwiseProduct(Eigen::Vector2d(double(i) / (grid - 1),
                                                                     double(j) / (grid - 1))));
    }
  }
  std::vector<char> counts(pixels.size(), 1);
  if (hull != nullptr) {
    for (std::size_t k = 0; k < pixels.size(); ++k) {
      const cv::Point2f p(static_cast<float>(pixels[k].x()), static_cast<float>(pixels[k].y()));
      counts[k] = cv::pointPolygonTest(*hull, p, false) >= 0 ? 1 : 0;
    }
  }
  check.pixels = static_cast<int>(std::count(counts.begin(), counts.end(), 1));
  if (region.isEmpty()) {  // the whole imager: where the triangulator needs every ray
    const std::vector<double>& in = model.intrinsics();
    double needed = 0;  // largest normalized distorted radius in the region
    for (const Eigen::Vector2d& c :
         {box.min(), box.max(), Eigen::Vector2d(box.min().x(), box.max().y()),
          Eigen::Vector2d(box.max().x(), box.min().y())}) {
      needed = std::max(needed, std::hypot((c.x() - in[2]) / in[0], (c.y() - in[3]) / in[1]));
    }
    const double fold = RadialFoldRadius(model, needed);
    if (std::isfinite(fold)) check.radial_fold_px = std::max(fold * in[0], 1e-9);
  }
  std::vector<Eigen::Vector3d> rays;
  try {
    rays = model.UnprojectMany(pixels);
  } catch (const InternalError&) {
    check.without_ray = check.pixels;
    check.worst_px = std::numeric_limits<double>::infinity();
    check.first_bad_px = pixels.front();
    return check;
  }
  for (std::size_t k = 0; k < pixels.size(); ++k) {
    if (!counts[k]) continue;
    double error = std::numeric_limits<double>::infinity();
    // A ray that does not point forward (z <= 1e-6) is no ray for lasercell's forward-looking
    // sensors (the triangulator's tables need z > 0), even when it projects back onto its pixel:
    // it counts as a pixel without a ray.
    if (rays[k].allFinite() && rays[k].z() > 1e-6)
      error = (model.Project(rays[k]) - pixels[k]).norm();
    if (!(error <= tolerance_px)) {
      if (check.without_ray++ == 0) check.first_bad_px = pixels[k];
      check.worst_px = std::max(check.worst_px, error);
    }
  }
  // A fold keeps the round trip exact but flips the orientation of the pixel -> ray map: the
  // triple product of neighbouring rays' differences with the ray changes sign.
  for (int j = 0; j + 1 < grid; ++j) {
    for (int i = 0; i + 1 < grid; ++i) {
      const int at = j * grid + i;
      if (!counts[at] || !counts[at + 1] || !counts[at + grid]) continue;
      const Eigen::Vector3d& r = rays[j * grid + i];
      const Eigen::Vector3d du = rays[j * grid + i + 1] - r, dv = rays[(j + 1) * grid + i] - r;
      if (!r.allFinite() || !du.allFinite() || !dv.allFinite()) continue;  // counted above
      if (du.squaredNorm() == 0.0 || dv.squaredNorm() == 0.0) continue;    // a degenerate box
      ++check.cells;
      check.reversed_cells += du.cross(dv).dot(r) <= 0 ? 1 : 0;
    }
  }
  return check;
}

}  // namespace

LensInversionCheck CheckLensInversion(const CameraModel& model, const Eigen::AlignedBox2d& region,
                                      int grid, double tolerance_px) {
  return CheckGrid(model, region, nullptr, grid, tolerance_px);
}

LensInversionCheck CheckLensInversionWithin(const CameraModel& model,
                                            const std::vector<Eigen::Vector2d>& observed_px,
                                            int grid, double tolerance_px) {
  std::vector<cv::Point2f> points;
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector2d& p : observed_px) {
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
    box.extend(p);
  }
  if (points.size() < 3) return {};
  std::vector<cv::Point2f> hull;
  cv::convexHull(points, hull);
  return CheckGrid(model, box, &hull, grid, tolerance_px);
}

std::string LensInversionProblem(const CameraModel& model, int grid, double tolerance_px) {
  return CheckLensInversion(model, {}, grid, tolerance_px).Describe();
}

std::string CameraModelText(const CameraModel& model, const std::string& comment) {
  std::string out = "# lasercell-cameramodel v1 (mrcal .cameramodel; units mm and px)\n";
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out += "# " + line + "\n";
  out += "{\n  'lensmodel':  '" + model.lensmodel() + "',\n  'intrinsics': [ ";
  for (double v : model.intrinsics()) out += FormatDouble(v) + ", ";
  out += "],\n  'imagersize': [ " + std::to_string(model.width_px()) + ", " +
         std::to_string(model.height_px()) + " ],\n  'extrinsics': [ 0, 0, 0, 0, 0, 0 ]";
  const Eigen::MatrixXd& cov = model.intrinsics_covariance();
  if (cov.size() > 0) {
    out += ",\n  '";
    out += kCovarianceKey;
    out += "': [";
    for (int r = 0; r < cov.rows(); ++r) {
      out += "\n   ";
      for (int c = 0; c < cov.cols(); ++c) {
        out += ' ';
        out += FormatDouble(cov(r, c));
        if (r + 1 < cov.rows() || c + 1 < cov.cols()) out += ',';
      }
    }
    out += " ]";
  }
  out += "\n}\n";
  return out;
}

CameraModel ParseCameraModel(const std::string& text, const std::string& name) {
  CheckCompleteModelText(text, name);
  // A final comment without its newline would also run mrcal's lexer off the end.
  const std::string terminated = text + "\n";
  mrcal_cameramodel_t* raw =
      mrcal_read_cameramodel_string(terminated.data(), static_cast<int>(terminated.size()));
  if (raw == nullptr) {
    throw FileError(name,
                    "mrcal could not parse this .cameramodel (expected a mrcal camera "
                    "model text with lensmodel, intrinsics, imagersize, extrinsics)");
  }
  const ModelPtr model = Guard(raw);
  CameraModel camera = FromMrcal(*model, name);
  try {
    camera.SetIntrinsicsCovariance(ParseCovarianceKey(text, name, camera.NumIntrinsics()));
  } catch (const InputError& e) {
    throw FileError(name, e.what());
  }
  return camera;
}

CameraModel LoadCameraModel(const std::string& path) {
  const std::string text = io::ReadFileBytes(path);
  return ParseCameraModel(text, path);
}

void SaveCameraModel(const std::string& path, const CameraModel& model,
                     const std::string& comment) {
  const std::string text = CameraModelText(model, comment);
  // Never write a file that mrcal itself would not read back identically.
  const CameraModel check = ParseCameraModel(text, path);
  LASERCELL_CHECK(
      check.intrinsics() == model.intrinsics() && check.lensmodel() == model.lensmodel() &&
          check.intrinsics_covariance().rows() == model.intrinsics_covariance().rows() &&
          (model.intrinsics_covariance().size() == 0 ||
           check.intrinsics_covariance() == model.intrinsics_covariance()),
      "camera model text does not round-trip through mrcal's reader");
  io::WriteFileAtomically(path, text);
}

}  // namespace lasercell::calib
