#include "triangulation/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "core/error.hpp"

namespace lasercell::triangulation {

void SweepOptions::Check(const std::string& what) const {
  if (!velocity_mm_s.allFinite()) {
    throw OptionError(what + ".velocity_mm_s must be finite");
  }
  if (motion == SweepMotion::kRobot && target_frame.empty()) {
    throw OptionError(what + ".target_frame must name a frame of the cell for robot sweeps");
  }
}

std::string SweepResult::Summary() const {
  char b[160];
  std::snprintf(b, sizeof b, "%zu profiles (%zu lost by sequence gaps) in frame '%s': ", profiles,
                sequence_gaps, frame.c_str());
  return b + counts.Summary();
}

SweepResult AssembleSweep(const ProfileSet& set, const Triangulator& triangulator,
                          const SweepOptions& options, const FrameGraph* graph) {
  options.Check();
  const ProfileHeader& header = set.header;
  header.Check("profiles");
  const calib::CameraModel& camera = triangulator.camera();
  if (static_cast<int>(header.image_width) != camera.width_px() ||
      static_cast<int>(header.image_height) != camera.height_px()) {
    throw InputError("profiles come from a " + std::to_string(header.image_width) + " x " +
                     std::to_string(header.image_height) + " sensor but the camera model is " +
                     std::to_string(camera.width_px()) + " x " +
                     std::to_string(camera.height_px()) + "; use the camera of that sensor");
  }
  const std::size_t count = set.profiles.size();
  const std::string robot = options.robot.empty() ? header.robot : options.robot;
  if (options.motion == SweepMotion::kRobot) {
    if (graph == nullptr) {
      throw InputError("a robot sweep needs the cell's frame graph (cell.yaml)");
    }
    if (header.joint_count == 0 || robot.empty()) {
      throw InputError(
          "the profiles record no robot joints (joint_count 0): a robot sweep needs "
          "them; use a linear sweep (velocity) instead");
    }
    if (!graph->HasFrame("sensor") || !graph->HasFrame(options.target_frame) ||
        !graph->Connected("sensor", options.target_frame)) {
      throw InputError("the cell has no path from frame 'sensor' to '" + options.target_frame +
                       "'; calibrate the hand-eye (vision_flange_from_sensor) first or choose "
                       "another --frame");
    }
  }
  const std::int64_t t0_ns =
      options.t0_ns ? *options.t0_ns : (count > 0 ? set.profiles.front().timestamp_ns : 0);

  // Per profile: points in the sweep frame (NaN where rejected), counts.
  std::vector<std::vector<Eigen::Vector3d>> points(count);
  std::vector<TriangulationCounts> counts(count);
  const auto work = [&](std::size_t i) {
    const Profile& p = set.profiles[i];
    points[i].resize(p.row_px.size());
    counts[i] = triangulator.Triangulate(p.row_px, header.first_column, points[i], options.path);
    Eigen::Isometry3d sweep_from_sensor = Eigen::Isometry3d::Identity();
    if (options.motion == SweepMotion::kLinear) {
      const double t = static_cast<double>(p.timestamp_ns - t0_ns) * 1e-9;
      sweep_from_sensor.translation() = options.velocity_mm_s * t;
    } else if (options.motion == SweepMotion::kRobot) {
      sweep_from_sensor = graph->Transform(options.target_frame, "sensor", {{robot, p.joints_rad}});
    }
    if (options.motion != SweepMotion::kNone) {
      for (Eigen::Vector3d& q : points[i]) q = sweep_from_sensor * q;  // NaN stays NaN
    }
  };
  const int threads = options.threads > 0
                          ? options.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (threads <= 1 || count < 2) {
    for (std::size_t i = 0; i < count; ++i) work(i);
  } else {
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
    for (int w = 0; w < threads; ++w) {
      pool.emplace_back([&, w] {
        try {
          for (std::size_t i = static_cast<std::size_t>(w); i < count;
               i += static_cast<std::size_t>(threads)) {
            work(i);
          }
        } catch (...) {
          errors[static_cast<std::size_t>(w)] = std::current_exception();
        }
      });
    }
    for (std::thread& t : pool) t.join();
    for (const std::exception_ptr& e : errors) {
      if (e) std::rethrow_exception(e);
    }
  }

  SweepResult result;
  result.profiles = count;
  result.frame = options.motion == SweepMotion::kRobot    ? options.target_frame
                 : options.motion == SweepMotion::kLinear ? "sensor_t0"
                                                          : "sensor";
  for (std::size_t i = 0; i < count; ++i) {
    result.counts += counts[i];
    if (i > 0 && set.profiles[i].sequence > set.profiles[i - 1].sequence + 1) {
      result.sequence_gaps += set.profiles[i].sequence - set.profiles[i - 1].sequence - 1;
    }
  }
  PointCloud& cloud = result.cloud;
  cloud.positions.reserve(result.counts.points);
  cloud.intensity.reserve(result.counts.points);
  cloud.profile.reserve(result.counts.points);
  cloud.column.reserve(result.counts.points);
  cloud.timestamp_s.reserve(result.counts.points);
  cloud.grid_rows = static_cast<std::int32_t>(count);
  cloud.grid_cols = static_cast<std::int32_t>(header.columns);
  for (std::size_t i = 0; i < count; ++i) {
    const Profile& p = set.profiles[i];
    const double t = options.motion == SweepMotion::kLinear
                         ? static_cast<double>(p.timestamp_ns - t0_ns) * 1e-9
                         : static_cast<double>(p.timestamp_ns) * 1e-9;
    for (std::size_t j = 0; j < points[i].size(); ++j) {
      if (std::isnan(points[i][j].x())) continue;
      cloud.positions.push_back(points[i][j]);
      cloud.intensity.push_back(p.intensity[j]);
      cloud.profile.push_back(static_cast<std::int32_t>(i));
      cloud.column.push_back(static_cast<std::int32_t>(j));
      cloud.timestamp_s.push_back(t);
    }
  }
  return result;
}

}  // namespace lasercell::triangulation
