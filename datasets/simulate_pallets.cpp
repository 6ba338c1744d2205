#include "datasets/simulate_pallets.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"
#include "core/io/point_cloud_io.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/rng.hpp"
#include "datasets/simulate_records.hpp"
#include "localize/cad_export.hpp"
#include "localize/part.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {

namespace {

using sim_text::Num;
using sim_text::Pose;
using sim_text::Vec;

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Rendering noise of pallet scene i: StreamSeed(seed, kPalletRenderStream + i) (the placements
// draw from pallet_scene.cpp's own stream).
constexpr std::uint64_t kPalletRenderStream = 0x3000000;
const char* const kTool = "lasercell simulator " LASERCELL_VERSION;

// The output folder and the files written into it (relative paths).
class PalletOutput {
 public:
  explicit PalletOutput(const std::string& dir) : dir_(dir) {
    std::error_code ec;
    for (const char* sub : {"", "profiles", "truth", "models", "records"}) {
      std::filesystem::create_directories(std::filesystem::path(dir) / sub, ec);
      if (ec) throw FileError(dir, "cannot create the output folder: " + ec.message());
    }
  }
  void Write(const std::string& relative, std::string_view bytes) {
    io::WriteFileAtomically(Path(relative), bytes);
    files_.push_back(relative);
  }
  void WriteMesh(const std::string& name, const TriangleMesh& mesh) {
    io::WritePlyMesh(Path("models/" + name + ".ply"), mesh);
    files_.push_back("models/" + name + ".ply");
    io::WriteStlMesh(Path("models/" + name + ".stl"), mesh);
    files_.push_back("models/" + name + ".stl");
  }
  // A file some other writer put there.
  void Record(const std::string& relative) { files_.push_back(relative); }
  // models/<name>.part.yaml.
  void WritePart(const localize::PartDefinition& part) {
    const std::string relative = "models/" + part.name + ".part.yaml";
    localize::WritePartFile(Path(relative), part);
    files_.push_back(relative);
  }
  std::string Path(const std::string& relative) const {
    return (std::filesystem::path(dir_) / relative).string();
  }
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::string dir_;
  std::vector<std::string> files_;
};

// The CAD part: its STEP file and part file in models/, the STEP read back finely as the
// rendered geometry.
PalletPart CadPart(const CadChairPart& cad, double albedo, double deflection_mm,
                   PalletOutput& out) {
  const std::string step = "models/" + cad.name + ".step";
  localize::WriteCadSolid(out.Path(step), cad.solid, "mm");
  out.Record(step);
  out.WritePart(CadPartDefinition(cad));
  return MakePalletPart(cad.name, ReadCadRenderMesh(out.Path(step), deflection_mm), albedo,
                        cad.grasps, cad.rest_orientations);
}

std::string PartsTruthYaml(const std::vector<PalletPart>& parts,
                           const std::vector<PalletPlacement>& placements,
                           const Eigen::Isometry3d& hb_from_cell) {
  std::ostringstream o;
  o << "    parts:\n";
  for (const PalletPlacement& p : placements) {
    const PalletPart* part = nullptr;
    for (const PalletPart& q : parts) part = q.name == p.part ? &q : part;
    LASERCELL_CHECK(part != nullptr, "placement of an unknown part");
    const Eigen::Isometry3d hb_from_part = hb_from_cell * p.cell_from_part;
    o << "      - part: " << p.part << "\n        part_frame: " << p.frame
      << "\n        stable_pose: " << p.stable_pose
      << "\n        yaw_deg: " << Num(p.yaw_rad * kRadToDeg) << "\n        shift_xy_mm: ["
      << Num(p.shift_xy_mm.x()) << ", " << Num(p.shift_xy_mm.y())
      << "]\n        cell_from_part: " << Pose(p.cell_from_part)
      << "\n        handling_base_from_part: " << Pose(hb_from_part) << "\n        grasps:\n";
    for (const PartGrasp& g : part->grasps) {
      o << "          - name: " << g.name
        << "\n            cell_from_grasp: " << Pose(p.cell_from_part * g.part_from_grasp)
        << "\n            handling_base_from_grasp: " << Pose(hb_from_part * g.part_from_grasp)
        << "\n";
    }
  }
  return o.str();
}

// The closing `parts:` section of truth/captures.yaml: per part its grasps and stable poses.
std::string PartDefinitionsYaml(const std::vector<PalletPart>& parts) {
  std::ostringstream o;
  o << "parts:\n";
  for (const PalletPart& part : parts) {
    o << "  " << part.name << ":\n    grasps:\n";
    for (const PartGrasp& g : part.grasps) {
      o << "      - name: " << g.name << "\n        part_from_grasp: " << Pose(g.part_from_grasp)
        << "\n        hole_diameter_mm: " << Num(g.hole_diameter_mm)
        << "\n        hole_depth_mm: " << Num(g.hole_depth_mm) << "\n";
    }
    o << "    stable_poses:\n";
    for (const RestingPose& r : part.stable_poses) {
      o << "      - plane_from_part: " << Pose(r.plane_from_part)
        << "\n        up_in_part: " << Vec(r.plane_from_part.linear().row(2).transpose())
        << "\n        stability_margin_mm: " << Num(r.stability_margin_mm)
        << "\n        contacts_in_part: [";
      for (std::size_t k = 0; k < r.contacts_in_part.size(); ++k) {
        o << (k ? ", " : "") << Vec(r.contacts_in_part[k]);
      }
      o << "]\n";
    }
  }
  return o.str();
}

StaticEdge PartEdge(const std::string& frame, const Eigen::Isometry3d& hb_from_part) {
  StaticEdge e;
  e.parent = "handling_base";
  e.child = frame;
  e.SetParentFromChild(hb_from_part);
  e.provenance.tool = kTool;
  e.provenance.residual_summary = "simulated ground truth (part pose)";
  return e;
}

CaptureReport WritePalletSweep(const std::string& name, const SweepResult& result,
                               const SimConfig& config, PalletOutput& out) {
  if (result.valid_peaks == 0) {
    throw OptionError("capture '" + name +
                      "' (pallet): the sensor sees nothing in any of its profiles; check "
                      "SimConfig.sweep.* and SimConfig.render.min_intensity");
  }
  triangulation::ProfileSet set = result.profiles;
  set.header.metadata = "format: lasercell.capture\ncapture: " + name +
                        "\nkind: pallet\nsimulator: \"" + kTool +
                        "\"\nseed: " + std::to_string(config.seed) + "\n";
  CaptureReport r;
  r.name = name;
  r.kind = "pallet";
  r.profiles_file = "profiles/" + name + ".lcp";
  r.profiles = set.profiles.size();
  r.valid_peaks = result.valid_peaks;
  out.Write(r.profiles_file, triangulation::EncodeProfiles(set));
  return r;
}

}  // namespace

void PalletSimOptions::Check(const std::string& what) const {
  back.Check(what + ".back");
  armrest.Check(what + ".armrest");
  placement.Check(what + ".placement");
  if (!(sweep_length_mm >= 0) || !std::isfinite(sweep_length_mm) || sweep_length_mm > 5000) {
    throw OptionError(what + ".sweep_length_mm must be in [0, 5000] mm (0: the config's), got " +
                      std::to_string(sweep_length_mm));
  }
  if (!(render_deflection_mm > 0) || render_deflection_mm > 1) {
    throw OptionError(what + ".render_deflection_mm must be in (0, 1] mm, got " +
                      std::to_string(render_deflection_mm));
  }
}

SimulationReport SimulatePallets(const SimConfig& config_in, int scenes, const std::string& out_dir,
                                 const PalletSimOptions& options, const ProgressCallback& progress,
                                 int threads) {
  const auto start = std::chrono::steady_clock::now();
  if (scenes < 1 || scenes > 100000) {
    throw OptionError("scenes must be in [1, 100000] (got " + std::to_string(scenes) + ")");
  }
  options.Check();
  SimConfig config = config_in;
  if (options.sweep_length_mm > 0) config.sweep_length_mm = options.sweep_length_mm;
  const CellTruth truth = MakeCellTruth(config);
  PalletOutput out(out_dir);
  const double albedo = config.albedo.seat;  // all three parts: the seed's dark plastic
  std::vector<PalletPart> parts;
  parts.push_back(MakePalletPart("seat", truth.seat.part, albedo, {SeatHoleGrasp(truth.seat)},
                                 {Eigen::Matrix3d::Identity()}));
  parts.push_back(CadPart(MakeSeatBack(options.back), albedo, options.render_deflection_mm, out));
  parts.push_back(CadPart(MakeArmrest(options.armrest), albedo, options.render_deflection_mm, out));
  ReportProgress(progress, "pallet parts", 1.0);

  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const LinearSweep sweep = MakeLinearSweep(config, truth.sensor);
  std::string captures_yaml = CapturesPreambleYaml(config, truth);
  FrameGraph graph = truth.Graph();
  SimulationReport report;
  for (int i = 0; i < scenes; ++i) {
    const std::vector<PalletPlacement> placements =
        DrawPalletPlacements(options.placement, parts, config.seed, i);
    const Scene scene = MakePalletScene(truth.layout, parts, placements);
    const LaserRenderer renderer(scene, truth.sensor, config.render);
    const SweepResult result = RenderSweep(
        renderer,
        [&](double t) {
          return SensorState{sweep.At(t), {}};
        },
        config.timing, StreamSeed(config.seed, kPalletRenderStream + static_cast<std::uint64_t>(i)),
        0, "", threads);
    char name[32];
    std::snprintf(name, sizeof(name), "pallet_%03d", i);
    const CaptureReport r = WritePalletSweep(name, result, config, out);
    report.captures.push_back(r);
    captures_yaml += CaptureHeaderYaml(r) + LinearSweepTruthYaml(sweep, hb_from_cell, config) +
                     ExposureTimesTruthYaml(result, config) +
                     PartsTruthYaml(parts, placements, hb_from_cell);
    for (const PalletPlacement& p : placements) {
      graph.SetStaticEdge(PartEdge(p.frame, hb_from_cell * p.cell_from_part));
    }
    ReportProgress(progress, "pallet scenes", static_cast<double>(i + 1) / scenes);
  }
  out.Write("records/linear_sweep.yaml",
            triangulation::LinearSweepRecordYaml(LinearSweepRecordOf(sweep, config)));
  out.Write("truth/captures.yaml", captures_yaml + PartDefinitionsYaml(parts));
  out.Write("truth/cell.yaml", FrameGraphToYaml(graph));
  out.Write("truth/camera.cameramodel", MrcalCameraModelText(config.sensor.camera));
  out.Write("truth/sensor.yaml", SensorTruthYaml(truth, config));
  out.Write("truth/robots.yaml", RobotsTruthYaml(truth));
  out.Write("truth/sim_config.yaml", SimConfigToYaml(config));
  // The seat's models/ mesh is its CAD (truth.seat_cad); the others' are their STEP's render.
  for (const PalletPart& part : parts) {
    out.WriteMesh(part.name, part.name == "seat" ? truth.seat_cad.part.mesh : part.geometry.mesh);
  }
  out.WritePart(SeatPartDefinition(truth.seat_cad, &truth.seat));
  out.WriteMesh("pallet", MakePallet().mesh);
  report.files = out.files();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace lasercell::datasets
