#include "triangulation/linear_sweep.hpp"

#include <cmath>
#include <sstream>

#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::triangulation {
namespace {

// Shortest round-trip text; infinities in YAML spelling.
std::string Num(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return FormatDouble(v);
}

}  // namespace

SweepOptions LinearSweepRecord::Options() const {
  SweepOptions o;
  o.motion = SweepMotion::kLinear;
  o.velocity_mm_s = velocity_mm_s_in_sensor;
  o.t0_ns = t0_ns;
  return o;
}

std::string LinearSweepRecordYaml(const LinearSweepRecord& r) {
  const Eigen::Vector3d& v = r.velocity_mm_s_in_sensor;
  std::ostringstream o;
  o << "format: lasercell.linear_sweep\nversion: 1\n"
    << "# Every linear capture (profiles/plane_*, spheres, seat_*) uses this motion: the sensor\n"
    << "# frame at t0 moves with constant velocity; points of the profile stamped t_ns lie at\n"
    << "# p_in_sensor_t0 = p_in_sensor + velocity_mm_s_in_sensor * (t_ns - t0_ns) * 1e-9.\n"
    << "t0_ns: " << r.t0_ns << "\n"
    << "velocity_mm_s_in_sensor: [" << Num(v.x()) << ", " << Num(v.y()) << ", " << Num(v.z())
    << "]\n"
    << "speed_mm_s: " << Num(r.speed_mm_s) << "\n";
  return o.str();
}

LinearSweepRecord ParseLinearSweepRecord(const std::string& text, const std::string& name) {
  yaml::Fields f = yaml::Fields::Parse(text, name);
  f.RequireFormat("lasercell.linear_sweep", 1);
  LinearSweepRecord r;
  f.ReadRequired("t0_ns", &r.t0_ns);
  f.ReadRequired("velocity_mm_s_in_sensor", &r.velocity_mm_s_in_sensor);
  f.Read("speed_mm_s", &r.speed_mm_s);
  f.Done();
  if (!r.velocity_mm_s_in_sensor.allFinite()) {
    f.Fail("velocity_mm_s_in_sensor", "must hold finite numbers (mm/s)");
  }
  return r;
}

LinearSweepRecord ReadLinearSweepRecord(const std::string& path) {
  return ParseLinearSweepRecord(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::triangulation
