#include "datasets/sensor.hpp"

extern "C" {
#include <mrcal/mrcal.h>
}

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numbers>

#include "core/error.hpp"
#include "core/se3.hpp"

namespace lasercell::datasets {

namespace {

std::string Number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

}  // namespace

std::array<double, 12> CameraIntrinsics::MrcalVector() const {
  std::array<double, 12> v{};
  v[0] = fx_px;
  v[1] = fy_px;
  v[2] = cx_px;
  v[3] = cy_px;
  for (int i = 0; i < 8; ++i) v[4 + i] = distortion[i];
  return v;
}

void CameraIntrinsics::Check(const std::string& what) const {
  if (width_px <= 0 || height_px <= 0 || width_px > 65536 || height_px > 65536) {
    throw OptionError(what + ".width_px/height_px must be in [1, 65536] (got " +
                      std::to_string(width_px) + " x " + std::to_string(height_px) + ")");
  }
  const auto positive = [&](double v, const char* field) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw OptionError(what + "." + field + " must be a positive number (got " +
                        std::to_string(v) + ")");
    }
  };
  positive(fx_px, "fx_px");
  positive(fy_px, "fy_px");
  if (!std::isfinite(cx_px) || cx_px < 0 || cx_px > width_px - 1) {
    throw OptionError(what + ".cx_px must lie inside the image, in [0, width_px - 1] (got " +
                      std::to_string(cx_px) + ")");
  }
  if (!std::isfinite(cy_px) || cy_px < 0 || cy_px > height_px - 1) {
    throw OptionError(what + ".cy_px must lie inside the image, in [0, height_px - 1] (got " +
                      std::to_string(cy_px) + ")");
  }
  for (std::size_t i = 0; i < distortion.size(); ++i) {
    if (!std::isfinite(distortion[i]) || std::abs(distortion[i]) > 10) {
      throw OptionError(what + ".distortion[" + std::to_string(i) +
                        "] must be finite with magnitude <= 10 (got " +
                        std::to_string(distortion[i]) + ")");
    }
  }
}

calib::CameraModel MakeCameraModel(const CameraIntrinsics& intrinsics) {
  const std::array<double, 12> v = intrinsics.MrcalVector();
  return calib::CameraModel("LENSMODEL_OPENCV8", std::vector<double>(v.begin(), v.end()),
                            intrinsics.width_px, intrinsics.height_px);
}

std::optional<Eigen::Vector2d> ProjectInView(const calib::CameraModel& camera,
                                             const Eigen::Vector3d& p) {
  if (!(p.z() > 1e-9)) return std::nullopt;
  // Outside ~70 deg off-axis the rational model folds back; treat as not imaged.
  if (p.head<2>().norm() > 3.0 * p.z()) return std::nullopt;
  Eigen::Vector2d pixel;
  try {
    pixel = camera.Project(p);
  } catch (const InternalError&) {  // mrcal_project failed
    return std::nullopt;
  }
  if (!pixel.allFinite()) return std::nullopt;
  return pixel;
}

Eigen::Vector3d LaserPlane::RayDirection(double alpha_rad) const {
  return std::cos(alpha_rad) * center_in_sensor + std::sin(alpha_rad) * Lateral();
}

Eigen::Vector4d LaserPlane::Coefficients() const {
  return Eigen::Vector4d(normal_in_sensor.x(), normal_in_sensor.y(), normal_in_sensor.z(),
                         -normal_in_sensor.dot(origin_in_sensor));
}

void SensorOptions::Check(const std::string& what) const {
  camera.Check(what + ".camera");
  if (!(baseline_mm > 0) || !std::isfinite(baseline_mm)) {
    throw OptionError(what + ".baseline_mm must be positive (got " + std::to_string(baseline_mm) +
                      ")");
  }
  if (!(standoff_mm > 0) || !std::isfinite(standoff_mm)) {
    throw OptionError(what + ".standoff_mm must be positive (got " + std::to_string(standoff_mm) +
                      ")");
  }
  if (!(fan_angle_deg > 0 && fan_angle_deg < 170)) {
    throw OptionError(what + ".fan_angle_deg must be in (0, 170) (got " +
                      std::to_string(fan_angle_deg) + ")");
  }
}

SensorModel MakeSensor(const SensorOptions& options) {
  options.Check();
  SensorModel s{MakeCameraModel(options.camera), LaserPlane{}, {0, 0}};
  const double b = options.baseline_mm;
  const double d = options.standoff_mm;
  const double len = std::hypot(b, d);
  s.laser.origin_in_sensor = Eigen::Vector3d(0, -b, 0);
  s.laser.center_in_sensor = Eigen::Vector3d(0, b / len, d / len);
  // n = c x (+x) so that Lateral() = n x c = +x: positive fan angles move to higher columns.
  s.laser.normal_in_sensor = Eigen::Vector3d(0, d / len, -b / len);
  s.laser.fan_angle_rad = options.fan_angle_deg * std::numbers::pi / 180.0;
  // Measuring range at the principal column: rows 0 and height-1 intersected with the plane.
  const auto range_at_row = [&](double row) {
    const Eigen::Vector3d ray = s.camera.Unproject({options.camera.cx_px, row});
    const double denom = s.laser.normal_in_sensor.dot(ray);
    const double t = denom != 0 ? s.laser.normal_in_sensor.dot(s.laser.origin_in_sensor) / denom
                                : std::numeric_limits<double>::infinity();
    if (!(t > 0) || !std::isfinite(t)) return std::numeric_limits<double>::infinity();
    return (t * ray - s.laser.origin_in_sensor).dot(s.laser.center_in_sensor);
  };
  const double r0 = range_at_row(0.0);
  const double r1 = range_at_row(options.camera.height_px - 1.0);
  s.central_range_mm = {std::min(r0, r1), std::max(r0, r1)};
  return s;
}

Eigen::Matrix3d SensorLookingDown(const LaserPlane& laser, const Eigen::Vector3d& sweep_direction) {
  Eigen::Vector3d s(sweep_direction.x(), sweep_direction.y(), 0.0);
  LASERCELL_CHECK(s.norm() > 1e-9, "sweep direction must not be vertical");
  s.normalize();
  const Eigen::Vector3d down(0, 0, -1);
  Eigen::Matrix3d source, target;
  source << laser.normal_in_sensor, laser.center_in_sensor, laser.Lateral();
  target << s, down, s.cross(down);
  return target * source.transpose();
}

std::string MrcalCameraModelText(const CameraIntrinsics& intrinsics,
                                 const Eigen::Isometry3d& camera_from_ref) {
  const Vector6d rt = RotationVectorTranslation(camera_from_ref);
  std::string out;
  out += "# lasercell simulator: true camera (mrcal LENSMODEL_OPENCV8), units mm and px\n";
  out += "{\n  'lensmodel':  'LENSMODEL_OPENCV8',\n  'intrinsics': [ ";
  for (double v : intrinsics.MrcalVector()) out += Number(v) + ", ";
  out += "],\n  'imagersize': [ " + std::to_string(intrinsics.width_px) + ", " +
         std::to_string(intrinsics.height_px) + " ],\n  'extrinsics': [ ";
  for (int i = 0; i < 6; ++i) out += Number(rt[i]) + ", ";
  out += "]\n}\n";
  return out;
}

CameraIntrinsics CameraIntrinsicsFromMrcalText(const std::string& text, const std::string& name) {
  mrcal_cameramodel_t* model =
      mrcal_read_cameramodel_string(text.data(), static_cast<int>(text.size()));
  if (model == nullptr) throw FileError(name, "mrcal could not parse this .cameramodel");
  std::unique_ptr<mrcal_cameramodel_t, void (*)(mrcal_cameramodel_t*)> guard(
      model, [](mrcal_cameramodel_t* m) { mrcal_free_cameramodel(&m); });
  if (model->lensmodel.type != MRCAL_LENSMODEL_OPENCV8) {
    throw FileError(name, std::string("lens model ") +
                              mrcal_lensmodel_name_unconfigured(&model->lensmodel) +
                              " is not LENSMODEL_OPENCV8");
  }
  CameraIntrinsics c;
  c.width_px = static_cast<int>(model->imagersize[0]);
  c.height_px = static_cast<int>(model->imagersize[1]);
  c.fx_px = model->intrinsics[0];
  c.fy_px = model->intrinsics[1];
  c.cx_px = model->intrinsics[2];
  c.cy_px = model->intrinsics[3];
  for (int i = 0; i < 8; ++i) c.distortion[i] = model->intrinsics[4 + i];
  return c;
}

}  // namespace lasercell::datasets
