#include "localize/part.hpp"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"
#include "registration/localize_options_io.hpp"

namespace lasercell::localize {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

bool IsSnakeCase(const std::string& s) {
  if (s.empty() || !(s[0] >= 'a' && s[0] <= 'z')) return false;
  for (char c : s) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

std::string Where(const PartDefinition& part) {
  return part.file.empty() ? "part '" + part.name + "'" : part.file;
}

void ReadSymmetry(yaml::Fields& r, PartSymmetry* out) {
  if (!r.Has("symmetry")) {
    r.Known("symmetry");
    return;
  }
  yaml::Fields s = r.Sub("symmetry");
  std::string kind;
  s.ReadRequired("kind", &kind);
  if (kind == "none") {
    out->kind = PartSymmetry::Kind::kNone;
  } else if (kind == "axial") {
    out->kind = PartSymmetry::Kind::kAxial;
    s.ReadRequired("axis_in_part", &out->axis_in_part);
  } else if (kind == "discrete") {
    out->kind = PartSymmetry::Kind::kDiscrete;
    s.ReadRequired("axis_in_part", &out->axis_in_part);
    s.ReadRequired("order", &out->order);
  } else {
    s.Fail("kind", "is '" + kind + "'; expected none, axial or discrete");
  }
  s.Done();
}

void ReadCad(yaml::Fields& r, CadImportOptions* cad) {
  yaml::Fields c = r.Sub("cad");
  c.Read("sampling_step_mm", &cad->sampling_step_mm);
  c.Read("linear_deflection_mm", &cad->linear_deflection_mm);
  c.Read("angular_deflection_rad", &cad->angular_deflection_rad);
  c.Done();
}

void ReadFormDeviation(yaml::Fields& r, FormDeviation* out) {
  if (!r.Has("form_deviation")) {
    r.Known("form_deviation");
    return;
  }
  yaml::Fields f = r.Sub("form_deviation");
  f.ReadRequired("rms_mm", &out->rms_mm);
  f.Read("correlation_mm", &out->correlation_mm);
  if (!(out->rms_mm >= 0.0 && out->rms_mm <= 100.0)) {
    f.Fail("rms_mm", "must be in [0, 100] mm (the RMS of the part's surface against its model)");
  }
  if (!(out->correlation_mm > 0.0 && out->correlation_mm <= 1e4)) {
    f.Fail("correlation_mm", "must be in (0, 10000] mm");
  }
  f.Done();
}

PartDefinition FromFields(yaml::Fields r, const std::string& path) {
  PartDefinition part;
  part.file = path;
  r.RequireFormat(kPartFormat, kPartFormatVersion, "is this a lasercell part file?");
  r.Known({"name", "model", "units", "grasps", "stable_poses", "symmetry", "cad", "model_options",
           "form_deviation"});
  r.Done();  // a misspelt key is reported before the problems it causes
  r.ReadRequired("name", &part.name);
  if (!IsSnakeCase(part.name)) {
    r.Fail("name", "is '" + part.name + "'; use lower snake case ([a-z][a-z0-9_]*)");
  }
  r.ReadRequired("model", &part.model);
  const std::filesystem::path model(part.model);
  part.model_path = model.is_absolute() || path.empty()
                        ? part.model
                        : (std::filesystem::path(path).parent_path() / model).string();
  r.Read("units", &part.units);
  if (IsCadFile(part.model) && !part.units.empty()) {
    r.Fail("units",
           "is given for a CAD model; STEP and IGES files carry their own unit: "
           "remove the field");
  }
  if (!IsCadFile(part.model)) {
    if (part.units.empty()) {
      r.Fail("units", "is required for a mesh model (" + part.model +
                          " carries no unit): give mm, cm, m or inch");
    }
    UnitToMm(part.units, path + ": field 'units'");
  }
  yaml::Fields grasps = r.Sub("grasps");
  for (const std::string& name : grasps.Keys()) {
    yaml::Fields g = grasps.Sub(name.c_str());
    GraspFrame grasp;
    grasp.name = name;
    g.ReadRequiredPose("part_from_grasp", &grasp.part_from_grasp);
    g.Read("description", &grasp.description);
    g.Read("refine_radius_mm", &grasp.refine_radius_mm);
    g.Done();
    if (!IsSnakeCase(name)) {
      grasps.Fail(name, ": grasp names are lower snake case ([a-z][a-z0-9_]*)");
    }
    part.grasps.push_back(grasp);
  }
  grasps.Done();
  if (r.Has("stable_poses")) {
    yaml::Fields s = r.Sub("stable_poses");
    s.ReadRequired("up_in_part", &part.stable_up_in_part);
    double tilt_deg = part.max_tilt_rad / kDeg;
    s.Read("max_tilt_deg", &tilt_deg);
    part.max_tilt_rad = tilt_deg * kDeg;
    for (std::size_t i = 0; i < part.stable_up_in_part.size(); ++i) {
      if (std::abs(part.stable_up_in_part[i].norm() - 1.0) > 1e-6) {
        s.Fail("up_in_part", "[" + std::to_string(i) + "] is not a unit vector");
      }
    }
    if (!(tilt_deg >= 0.0 && tilt_deg <= 90.0)) s.Fail("max_tilt_deg", "must be in [0, 90]");
    s.Done();
  }
  ReadSymmetry(r, &part.symmetry);
  ReadCad(r, &part.cad);
  ReadFormDeviation(r, &part.form_deviation);
  yaml::Fields m = r.Sub("model_options");
  registration::ReadPpfModelOptionFields(m, &part.model_options);
  part.Check();
  return part;
}

std::string PoseYaml(const QuaternionPose& pose) {
  const Eigen::Vector3d& t = pose.translation_mm;
  const Eigen::Quaterniond& q = pose.rotation;
  return "{translation_mm: [" + FormatDouble(t.x()) + ", " + FormatDouble(t.y()) + ", " +
         FormatDouble(t.z()) + "], rotation_wxyz: [" + FormatDouble(q.w()) + ", " +
         FormatDouble(q.x()) + ", " + FormatDouble(q.y()) + ", " + FormatDouble(q.z()) + "]}";
}

std::string VectorYaml(const Eigen::Vector3d& v) {
  // Appends (not "[" + std::string): GCC 12 -O2 reports a false -Wrestrict on the latter.
  std::string s = "[";
  s += FormatDouble(v.x());
  s += ", ";
  s += FormatDouble(v.y());
  s += ", ";
  s += FormatDouble(v.z());
  s += "]";
  return s;
}

}  // namespace

double UnitToMm(const std::string& unit, const std::string& field) {
  if (unit == "mm") return 1.0;
  if (unit == "cm") return 10.0;
  if (unit == "m") return 1000.0;
  if (unit == "inch" || unit == "in") return 25.4;
  throw OptionError(field + " is '" + unit + "'; expected mm, cm, m or inch");
}

bool IsCadFile(const std::string& path) {
  const std::string ext = io::LowerExtension(path);
  return ext == ".step" || ext == ".stp" || ext == ".iges" || ext == ".igs";
}

const GraspFrame& PartDefinition::Grasp(const std::string& grasp_name) const {
  std::string known;
  for (const GraspFrame& g : grasps) {
    if (g.name == grasp_name) return g;
    known += (known.empty() ? "" : ", ") + g.name;
  }
  throw InputError(Where(*this) + ": part '" + name + "' has no grasp '" + grasp_name +
                   "' (it has: " + (known.empty() ? "none" : known) + ")");
}

void PartDefinition::Check() const {
  const std::string where = Where(*this);
  if (!IsSnakeCase(name)) throw InputError(where + ": name '" + name + "' is not lower snake case");
  if (model.empty())
    throw InputError(where + ": field 'model' is empty: name the CAD or mesh file");
  if (IsCadFile(model) != units.empty()) {
    throw InputError(where + ": field 'units' " +
                     (units.empty() ? "is required for a mesh model"
                                    : "must not be given for a CAD model (it has its own unit)"));
  }
  if (!units.empty()) UnitToMm(units, where + ": field 'units'");
  std::set<std::string> seen;
  for (const GraspFrame& g : grasps) {
    if (!IsSnakeCase(g.name))
      throw InputError(where + ": grasp '" + g.name + "' is not snake case");
    if (!seen.insert(g.name).second) {
      throw InputError(where + ": grasp '" + g.name + "' is defined twice");
    }
    CheckQuaternionPose(g.part_from_grasp, where + ": grasps." + g.name + ".part_from_grasp");
    if (!(g.refine_radius_mm >= 0.0 && g.refine_radius_mm <= 1e4)) {
      throw InputError(where + ": grasps." + g.name +
                       ".refine_radius_mm must be in [0, 10000] mm (0: no local refinement)");
    }
  }
  for (const Eigen::Vector3d& up : stable_up_in_part) {
    if (!up.allFinite() || std::abs(up.norm() - 1.0) > 1e-6) {
      throw InputError(where + ": stable_poses.up_in_part holds a vector that is not unit");
    }
  }
  if (!(max_tilt_rad >= 0.0 && max_tilt_rad <= std::numbers::pi / 2)) {
    throw InputError(where + ": stable_poses.max_tilt_deg must be in [0, 90]");
  }
  if (symmetry.kind != PartSymmetry::Kind::kNone &&
      (!symmetry.axis_in_part.allFinite() || std::abs(symmetry.axis_in_part.norm() - 1.0) > 1e-6)) {
    throw InputError(where + ": symmetry.axis_in_part must be a unit vector");
  }
  if (symmetry.kind == PartSymmetry::Kind::kDiscrete && symmetry.order < 2) {
    throw InputError(where + ": symmetry.order must be >= 2 for a discrete symmetry");
  }
  if (!(form_deviation.rms_mm >= 0.0 && form_deviation.rms_mm <= 100.0)) {
    throw InputError(where + ": form_deviation.rms_mm must be in [0, 100] mm");
  }
  if (!(form_deviation.correlation_mm > 0.0 && form_deviation.correlation_mm <= 1e4)) {
    throw InputError(where + ": form_deviation.correlation_mm must be in (0, 10000] mm");
  }
  try {
    cad.Check();
    model_options.Check();
  } catch (const OptionError& e) {
    throw OptionError(where + ": " + e.what());
  }
}

PartDefinition ParsePartFile(const std::string& text, const std::string& path) {
  return FromFields(yaml::Fields::Parse(text, path), path);
}

PartDefinition ReadPartFile(const std::string& path) {
  return FromFields(yaml::Fields::Load(path), path);
}

std::string PartFileYaml(const PartDefinition& part) {
  std::string out = std::string("format: ") + kPartFormat +
                    "\nversion: " + std::to_string(kPartFormatVersion) + "\nname: " + part.name +
                    "\nmodel: " + yaml::Quoted(part.model) + "\n";
  if (!part.units.empty()) out += "units: " + part.units + "\n";
  if (!part.grasps.empty()) {
    out += "grasps:\n";
    for (const GraspFrame& g : part.grasps) {
      out += "  " + g.name + ":\n    part_from_grasp: " + PoseYaml(g.part_from_grasp) + "\n";
      if (!g.description.empty()) out += "    description: " + yaml::Quoted(g.description) + "\n";
      if (g.refine_radius_mm > 0) {
        out += "    refine_radius_mm: " + FormatDouble(g.refine_radius_mm) + "\n";
      }
    }
  }
  if (!part.stable_up_in_part.empty()) {
    out += "stable_poses:\n  up_in_part: [";
    for (std::size_t i = 0; i < part.stable_up_in_part.size(); ++i) {
      out += (i ? ", " : "") + VectorYaml(part.stable_up_in_part[i]);
    }
    out += "]\n  max_tilt_deg: " + FormatDouble(part.max_tilt_rad / kDeg) + "\n";
  }
  switch (part.symmetry.kind) {
    case PartSymmetry::Kind::kNone:
      out += "symmetry: {kind: none}\n";
      break;
    case PartSymmetry::Kind::kAxial:
      out +=
          "symmetry: {kind: axial, axis_in_part: " + VectorYaml(part.symmetry.axis_in_part) + "}\n";
      break;
    case PartSymmetry::Kind::kDiscrete:
      out += "symmetry: {kind: discrete, axis_in_part: " + VectorYaml(part.symmetry.axis_in_part) +
             ", order: " + std::to_string(part.symmetry.order) + "}\n";
      break;
  }
  if (part.form_deviation.rms_mm > 0.0) {
    out += "form_deviation: {rms_mm: " + FormatDouble(part.form_deviation.rms_mm) +
           ", correlation_mm: " + FormatDouble(part.form_deviation.correlation_mm) + "}\n";
  }
  out += "cad:\n  sampling_step_mm: " + FormatDouble(part.cad.sampling_step_mm) +
         "\n  linear_deflection_mm: " + FormatDouble(part.cad.linear_deflection_mm) +
         "\n  angular_deflection_rad: " + FormatDouble(part.cad.angular_deflection_rad) + "\n";
  out += "model_options:\n" + registration::PpfModelOptionsYaml(part.model_options, "  ");
  return out;
}

void WritePartFile(const std::string& path, const PartDefinition& part) {
  part.Check();
  io::WriteFileAtomically(path, PartFileYaml(part));
}

}  // namespace lasercell::localize
