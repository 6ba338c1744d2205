#include "triangulation/sensor_error_field.hpp"

#include <Eigen/LU>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "core/error.hpp"

namespace lasercell::triangulation {

SensorErrorField::SensorErrorField(const calib::CameraModel& camera, const LaserPlaneEntry& plane)
    : camera_(camera), normal_(plane.normal), modes_(plane.error_modes) {
  if (modes_.empty()) {
    throw InputError(
        "the laser plane has no error_modes: calibrate it with lasercell (calibrate laser) so "
        "that the cell holds them");
  }
  if (!(std::abs(plane.OffsetMm()) >= 1.0)) {
    throw InputError("the laser plane passes within 1 mm of the sensor origin: no triangulation");
  }
  const auto n = static_cast<Eigen::Index>(camera.NumIntrinsics());
  intrinsics_steps_ = Eigen::MatrixXd::Zero(n, Modes());
  for (Eigen::Index k = 0; k < Modes(); ++k) {
    const std::vector<double>& step = modes_[static_cast<std::size_t>(k)].intrinsics_step;
    if (step.empty()) continue;
    if (static_cast<Eigen::Index>(step.size()) != n) {
      throw InputError("laser plane error_modes[" + std::to_string(k) + "] steps " +
                       std::to_string(step.size()) + " intrinsics but the camera (" +
                       camera.lensmodel() + ") has " + std::to_string(n) +
                       ": the plane was calibrated through another camera model");
    }
    intrinsics_steps_.col(k) = Eigen::Map<const Eigen::VectorXd>(step.data(), n);
  }
}

Eigen::Matrix<double, 3, Eigen::Dynamic> SensorErrorField::Displacements(
    const Eigen::Vector3d& p_in_sensor) const {
  Eigen::Matrix<double, 3, Eigen::Dynamic> out =
      Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, Modes());
  Eigen::Matrix<double, 2, 3> dq_dp;
  Eigen::Matrix<double, 2, Eigen::Dynamic> dq_dtheta;
  camera_.Project(p_in_sensor, &dq_dp, &dq_dtheta);
  Eigen::Matrix3d a;
  a.topRows<2>() = dq_dp;
  a.row(2) = normal_.transpose();
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
  if (!lu.isInvertible()) return out;
  const Eigen::Matrix<double, 2, Eigen::Dynamic> pixel_shift = dq_dtheta * intrinsics_steps_;
  for (Eigen::Index k = 0; k < Modes(); ++k) {
    const Eigen::Vector4d& plane_step = modes_[static_cast<std::size_t>(k)].plane_step;
    Eigen::Vector3d rhs;
    rhs.head<2>() = -pixel_shift.col(k);
    rhs(2) = -(plane_step.head<3>().dot(p_in_sensor) + plane_step(3));
    out.col(k) = lu.solve(rhs);
  }
  return out;
}

std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(std::size_t)> CloudPointDisplacements(
    const SensorErrorField& field, const PointCloud& cloud,
    const std::vector<Eigen::Isometry3d>& frame_from_sensor) {
  if (!cloud.HasProfile()) {
    throw InputError(
        "the cloud has no profile attribute: which sensor pose saw each point is "
        "unknown (triangulate the sweep with lasercell)");
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.profile[i] < 0 ||
        static_cast<std::size_t>(cloud.profile[i]) >= frame_from_sensor.size()) {
      throw InputError("cloud point " + std::to_string(i) + " belongs to profile " +
                       std::to_string(cloud.profile[i]) + " but " +
                       std::to_string(frame_from_sensor.size()) + " sensor poses are given");
    }
  }
  struct Data {
    SensorErrorField field;
    std::vector<Eigen::Vector3d> positions;
    std::vector<std::int32_t> profile;
    std::vector<Eigen::Isometry3d> frame_from_sensor;
  };
  auto data =
      std::make_shared<const Data>(Data{field, cloud.positions, cloud.profile, frame_from_sensor});
  return [data](std::size_t i) {
    const Eigen::Isometry3d& frame_from_sensor =
        data->frame_from_sensor[static_cast<std::size_t>(data->profile[i])];
    const Eigen::Vector3d p_sensor = frame_from_sensor.inverse() * data->positions[i];
    return Eigen::Matrix<double, 3, Eigen::Dynamic>(frame_from_sensor.linear() *
                                                    data->field.Displacements(p_sensor));
  };
}

}  // namespace lasercell::triangulation
