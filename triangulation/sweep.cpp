#include "triangulation/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"

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
  char b[256];
  const bool placed = motion == SweepMotion::kLinear && frame != "sensor";
  std::snprintf(b, sizeof b, "%zu profiles (%zu lost by sequence gaps) in frame '%s'%s: ", profiles,
                sequence_gaps, frame.c_str(),
                placed ? " (linear sweep placed through static edges)" : "");
  return b + counts.Summary();
}

namespace {

// Throws InputError unless the graph reaches `target` from "sensor" (and, for a linear sweep,
// through static edges only: the sensor at t0 is a fixed frame, a robot joint state is unknown).
void CheckTargetFrame(const FrameGraph& graph, const std::string& target, SweepMotion motion) {
  if (!graph.HasFrame("sensor") || !graph.HasFrame(target) || !graph.Connected("sensor", target)) {
    throw InputError("the cell has no path from frame 'sensor' to '" + target +
                     (motion == SweepMotion::kRobot
                          ? "'; calibrate the hand-eye (vision_flange_from_sensor) first or choose "
                            "another --frame"
                          : "'; calibrate the sensor's place (calibrate spheres writes "
                            "handling_base <- sensor) or choose another --frame"));
  }
  if (motion == SweepMotion::kLinear) {
    const std::vector<std::string> robots = graph.RobotsOnPath(target, "sensor");
    if (!robots.empty()) {
      throw InputError("the path from 'sensor' to '" + target + "' passes robot '" +
                       robots.front() +
                       "'; a linear sweep is placed through static edges only (calibrate "
                       "spheres writes one)");
    }
  }
}

}  // namespace

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
    CheckTargetFrame(*graph, options.target_frame, options.motion);
  }
  // A linear sweep placed in a cell frame: target <- sensor (at t0) through static edges.
  const bool placed = options.motion == SweepMotion::kLinear && !options.target_frame.empty();
  Eigen::Isometry3d target_from_sensor = Eigen::Isometry3d::Identity();
  if (placed) {
    if (graph == nullptr) {
      throw InputError("a linear sweep placed in frame '" + options.target_frame +
                       "' needs the cell's frame graph (cell.yaml)");
    }
    CheckTargetFrame(*graph, options.target_frame, options.motion);
    target_from_sensor = graph->Transform(options.target_frame, "sensor");
  }
  const std::int64_t t0_ns =
      options.t0_ns ? *options.t0_ns : (count > 0 ? set.profiles.front().timestamp_ns : 0);

  // Per profile: points in the sweep frame (NaN where rejected), counts.
  std::vector<std::vector<Eigen::Vector3d>> points(count);
  std::vector<TriangulationCounts> counts(count);
  std::vector<Eigen::Isometry3d> frame_from_sensor(count, Eigen::Isometry3d::Identity());
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
    // Two steps (not one composed pose) so a placed sweep is the unplaced one moved, bit for bit.
    if (placed) {
      for (Eigen::Vector3d& q : points[i]) q = target_from_sensor * q;
    }
    frame_from_sensor[i] = placed ? target_from_sensor * sweep_from_sensor : sweep_from_sensor;
  };
  // Per profile into its own slots: the result does not depend on the thread count.
  ParallelForChunks(options.threads, count, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) work(i);
  });

  SweepResult result;
  result.profiles = count;
  result.motion = options.motion;
  result.frame = options.motion == SweepMotion::kRobot || placed ? options.target_frame : "sensor";
  result.frame_from_sensor = std::move(frame_from_sensor);
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

ScanSetup ScanSetupFromCell(const FrameGraph* cell, const std::string& cell_name,
                            const LaserPlaneSource& source, const SweepOptions& options) {
  options.Check();
  ScanSetup setup;
  setup.options = options;
  if (source.plane) {
    setup.laser_plane = *source.plane;
    setup.laser_plane_source = source.plane_label;
  } else if (cell != nullptr) {
    const auto it = cell->laser_planes().find(source.laser);
    if (it == cell->laser_planes().end()) {
      throw FileError(
          cell_name,
          cell->laser_planes().empty()
              ? std::string("has no laser_planes section; run `lasercell calibrate "
                            "laser` or give --laser-plane nx,ny,nz,d")
              : "has no laser plane named '" + source.laser + "' in laser_planes.planes");
    }
    const LaserPlaneEntry& plane = it->second;
    if (plane.frame != "sensor") {
      throw FileError(cell_name, "laser plane '" + source.laser + "' is given in frame '" +
                                     plane.frame +
                                     "'; scan triangulate needs it in 'sensor' (the camera frame)");
    }
    setup.laser_plane = {plane.normal.x(), plane.normal.y(), plane.normal.z(), plane.OffsetMm()};
    setup.laser_plane_source = cell_name;
  } else {
    throw InputError(
        "no laser plane: give a cell file with a calibrated laser plane "
        "(laser_planes section) or the plane (n, d) in the sensor frame");
  }
  const bool needs_frame =
      options.motion == SweepMotion::kRobot ||
      (options.motion == SweepMotion::kLinear && !options.target_frame.empty());
  if (needs_frame) {
    if (cell == nullptr) {
      throw InputError("frame '" + options.target_frame +
                       "' needs the cell's frame graph (cell.yaml)");
    }
    // A robot sweep's path is checked with its profiles (AssembleSweep: joints first).
    if (options.motion == SweepMotion::kLinear) {
      CheckTargetFrame(*cell, options.target_frame, options.motion);
    }
  }
  return setup;
}

}  // namespace lasercell::triangulation
