#include "calib/laser_plane_heights_record.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::calib {

std::string PlaneHeightsYaml(const PlaneHeightsRecord& record) {
  std::string o =
      "format: lasercell.plane_heights\nversion: 1\n"
      "# profiles/plane_<i>.lcp sweeps the white plate at heights_mm[i] (along the plate\n"
      "# normal, relative to an arbitrary zero).\n"
      "heights_mm: [";
  for (std::size_t i = 0; i < record.heights_mm.size(); ++i) {
    o += (i ? ", " : "") + FormatDouble(record.heights_mm[i]);
  }
  const Eigen::Vector3d& m = record.plate_normal_in_sensor;
  o += "]\nplate_normal_in_sensor: [" + FormatDouble(m.x()) + ", " + FormatDouble(m.y()) + ", " +
       FormatDouble(m.z()) + "]\n";
  return o;
}

PlaneHeightsRecord ParsePlaneHeightsYaml(const std::string& text, const std::string& name) {
  yaml::Fields fields = yaml::Fields::Parse(text, name);
  fields.RequireFormat("lasercell.plane_heights", 1);
  PlaneHeightsRecord record;
  fields.ReadRequired("heights_mm", &record.heights_mm);
  fields.ReadRequired("plate_normal_in_sensor", &record.plate_normal_in_sensor);
  fields.Done();
  if (record.heights_mm.empty()) {
    throw InputError(name + ": heights_mm is empty; give one plate height (mm) per plane_<i>.lcp");
  }
  for (const double h : record.heights_mm) {
    if (!std::isfinite(h)) throw InputError(name + ": heights_mm holds a non-finite height");
  }
  if (!record.plate_normal_in_sensor.allFinite() || record.plate_normal_in_sensor.norm() < 1e-9) {
    throw InputError(name +
                     ": plate_normal_in_sensor must be a finite non-zero vector (the plate "
                     "normal in the sensor frame, pointing towards the sensor)");
  }
  return record;
}

PlaneHeightsRecord ReadPlaneHeightsYaml(const std::string& path) {
  return ParsePlaneHeightsYaml(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::calib
