#include "datasets/pallet_scene.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "datasets/simulate_pallets.hpp"
#include "datasets/simulate_records.hpp"
#include "localize/part.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {
namespace {

// Simulation profile: ideal (SimConfig{} noise; fewer profiles and fan rays than the default).
SimConfig PalletConfig() {
  SimConfig c;
  c.seed = 11;
  c.timing.profiles = 160;  // 7.5 mm apart over the 1200 mm sweep: few, but every part is hit
  c.render.fan_rays = 512;
  return c;
}

// A point of a sweep in the cell frame (true camera ray of its row, true laser plane, sensor
// pose at the profile's timestamp) and the camera centre that saw it.
struct SweepPoint {
  Eigen::Vector3d point, camera;
};

std::vector<SweepPoint> SweepPoints(const std::string& file, const SimConfig& config,
                                    const PalletSimOptions& options) {
  SimConfig used = config;
  used.sweep_length_mm = options.sweep_length_mm;
  const CellTruth truth = MakeCellTruth(used);
  const LinearSweep sweep = MakeLinearSweep(used, truth.sensor);
  const Eigen::Vector4d plane = truth.sensor.laser.Coefficients();
  const triangulation::ProfileSet set = triangulation::ReadProfiles(file);
  std::vector<SweepPoint> points;
  for (const triangulation::Profile& p : set.profiles) {
    const Eigen::Isometry3d cell_from_sensor =
        sweep.At((p.timestamp_ns - config.timing.start_ns) * 1e-9);
    for (std::uint32_t c = 0; c < set.header.columns; ++c) {
      if (std::isnan(p.row_px[c])) continue;
      const Eigen::Vector3d ray = truth.sensor.camera.Unproject({c, p.row_px[c]});
      points.push_back({cell_from_sensor * (-plane[3] / plane.head<3>().dot(ray) * ray),
                        cell_from_sensor.translation()});
    }
  }
  return points;
}

// Sweep points on the part's rendered surface placed at cell_from_part: the camera's ray to the
// point meets that surface within 1 mm of the point (a bound on the distance to the surface).
int PointsOnSurface(const std::vector<SweepPoint>& points, const PalletPart& part,
                    const Eigen::Isometry3d& cell_from_part) {
  Scene scene;
  MeshPart posed = part.geometry;
  posed.Transform(cell_from_part);
  scene.Add({part.name, std::move(posed), {}});
  scene.Commit();
  int on = 0;
  for (const SweepPoint& p : points) {
    const Eigen::Vector3d d = p.point - p.camera;
    const auto hit = scene.Intersect(p.camera, d);
    on += hit && std::abs(hit->t_mm - d.norm()) <= 1.0 ? 1 : 0;
  }
  return on;
}

// The parts exactly as SimulatePallets builds them (from the STEP files it wrote).
std::vector<PalletPart> PartsOf(const std::string& dir, const SimConfig& config) {
  const CellTruth truth = MakeCellTruth(config);
  std::vector<PalletPart> parts;
  parts.push_back(MakePalletPart("seat", truth.seat.part, 0.08, {SeatHoleGrasp(truth.seat)},
                                 {Eigen::Matrix3d::Identity()}));
  const CadChairPart back = MakeSeatBack(), arm = MakeArmrest();
  parts.push_back(MakePalletPart("back", ReadCadRenderMesh(dir + "/models/back.step"), 0.08,
                                 back.grasps, back.rest_orientations));
  parts.push_back(MakePalletPart("armrest", ReadCadRenderMesh(dir + "/models/armrest.step"), 0.08,
                                 arm.grasps, arm.rest_orientations));
  return parts;
}

TEST(PalletScene, AllThreePartsLieApartOnTheDeckAndTheSweepSeesEach) {
  const test::TestDir scratch("pallet_scene");
  const std::string dir = scratch.path().string();
  const SimConfig config = PalletConfig();
  const PalletSimOptions options;
  const SimulationReport report = SimulatePallets(config, 2, dir, options, {}, 2);
  ASSERT_EQ(report.captures.size(), 2u);
  const std::vector<PalletPart> parts = PartsOf(dir, config);
  for (int scene = 0; scene < 2; ++scene) {
    SCOPED_TRACE("scene " + std::to_string(scene));
    const std::vector<PalletPlacement> placements =
        DrawPalletPlacements(options.placement, parts, config.seed, scene);
    ASSERT_EQ(placements.size(), 3u);
    const std::vector<SweepPoint> points =
        SweepPoints(dir + "/" + report.captures[scene].profiles_file, config, options);
    std::vector<std::vector<Eigen::Vector2d>> hulls;
    for (std::size_t k = 0; k < 3; ++k) {
      const PalletPart& part = parts[k];
      const PalletPlacement& p = placements[k];
      ASSERT_EQ(p.part, part.name);
      // Resting on the deck: the lowest vertex at its height, the others above it.
      double z_min = 1e9;
      std::vector<Eigen::Vector2d> xy;
      for (const Eigen::Vector3d& v : part.geometry.mesh.vertices.positions) {
        const Eigen::Vector3d q = p.cell_from_part * v;
        z_min = std::min(z_min, q.z());
        xy.push_back(q.head<2>());
      }
      EXPECT_NEAR(z_min, kPalletHeightMm, 1e-9) << part.name;
      EXPECT_GT(part.stable_poses[p.stable_pose].stability_margin_mm, 5.0) << part.name;
      hulls.push_back(ConvexHull2d(xy));
      // Seen: points of the sweep on the part's posed rendered mesh.
      const int on = PointsOnSurface(points, part, p.cell_from_part);
      EXPECT_GT(on, 3000) << part.name;
      RecordProperty("scene" + std::to_string(scene) + "_" + part.name + "_points",
                     std::to_string(on));
    }
    // Apart: no two footprints (convex hulls seen from above, so the solids too) overlap.
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t b = a + 1; b < 3; ++b) {
        EXPECT_FALSE(ConvexPolygonsCloserThan(hulls[a], hulls[b], 0.0)) << a << " " << b;
      }
    }
  }
}

TEST(PalletScene, TruthFilesAgreeWithTheFrameGraphAndTheDraws) {
  const test::TestDir scratch("pallet_truth");
  const std::string dir = scratch.path().string();
  SimConfig config = PalletConfig();
  config.timing.profiles = 20;
  const PalletSimOptions options;
  const SimulationReport report = SimulatePallets(config, 2, dir, options, {}, 2);
  const std::vector<PalletPart> parts = PartsOf(dir, config);
  const FrameGraph graph = LoadFrameGraph(dir + "/truth/cell.yaml");
  const std::string captures = io::ReadFileBytes(dir + "/truth/captures.yaml");
  const Eigen::Isometry3d hb_from_cell =
      MakeCellTruth(config).layout.cell_from_handling_base.inverse();
  EXPECT_LT((graph.Transform("handling_base", "cell").matrix() - hb_from_cell.matrix()).norm(),
            1e-9);
  for (int scene = 0; scene < 2; ++scene) {
    for (const PalletPlacement& p :
         DrawPalletPlacements(options.placement, parts, config.seed, scene)) {
      SCOPED_TRACE(p.frame);
      // The file's pose (quaternion and translation text) equals the draw to round-off; the
      // captures are written from the draw itself.
      const Eigen::Isometry3d hb_from_part = hb_from_cell * p.cell_from_part;
      EXPECT_LT((graph.Transform("handling_base", p.frame).matrix() - hb_from_part.matrix()).norm(),
                1e-9);
      EXPECT_NE(captures.find("part_frame: " + p.frame), std::string::npos);
      EXPECT_NE(captures.find("handling_base_from_part: " + sim_text::Pose(hb_from_part)),
                std::string::npos);
      for (const PalletPart& part : parts) {
        if (part.name != p.part) continue;
        for (const PartGrasp& g : part.grasps) {
          EXPECT_NE(captures.find("handling_base_from_grasp: " +
                                  sim_text::Pose(hb_from_part * g.part_from_grasp)),
                    std::string::npos);
        }
      }
    }
  }
  for (const char* f : {"models/back.step", "models/armrest.step", "models/seat.stl",
                        "models/back.stl", "models/pallet.ply", "records/linear_sweep.yaml",
                        "truth/sensor.yaml", "truth/sim_config.yaml", "profiles/pallet_001.lcp"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  }
  for (const std::string& f : report.files) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  }
  // The part files name their models beside them and carry the grasps the truth uses.
  for (const PalletPart& part : parts) {
    SCOPED_TRACE(part.name);
    const localize::PartDefinition def =
        localize::ReadPartFile(dir + "/models/" + part.name + ".part.yaml");
    EXPECT_EQ(def.name, part.name);
    EXPECT_TRUE(std::filesystem::exists(def.model_path)) << def.model_path;
    EXPECT_EQ(def.units, part.name == "seat" ? "mm" : "");
    ASSERT_EQ(def.grasps.size(), part.grasps.size());
    const Eigen::Isometry3d file_grasp = def.grasps[0].part_from_grasp.ToIsometry();
    EXPECT_EQ(def.grasps[0].name, part.grasps[0].name);
    EXPECT_LT((file_grasp.matrix() - part.grasps[0].part_from_grasp.matrix()).norm(), 1e-12);
    if (part.name != "seat") {
      // The stable pose it lies in: its up axis within the file's tilt of a listed one.
      ASSERT_EQ(def.stable_up_in_part.size(), 1u);
      const Eigen::Vector3d up = part.stable_poses[0].plane_from_part.linear().row(2);
      EXPECT_LT(std::acos(std::min(1.0, up.dot(def.stable_up_in_part[0]))), def.max_tilt_rad);
    }
  }
  // The effective config (the pallet sweep's length) reads back.
  EXPECT_EQ(LoadSimConfig(dir + "/truth/sim_config.yaml").sweep_length_mm, options.sweep_length_mm);
}

TEST(PalletScene, SameSeedGivesIdenticalFilesForAnyThreadCount) {
  const test::TestDir scratch("pallet_same");
  SimConfig config = PalletConfig();
  config.timing.profiles = 24;
  const SimulationReport a = SimulatePallets(config, 1, scratch.File("a"), {}, {}, 1);
  const SimulationReport b = SimulatePallets(config, 1, scratch.File("b"), {}, {}, 2);
  ASSERT_EQ(a.files, b.files);
  for (const std::string& f : a.files) {
    EXPECT_EQ(io::ReadFileBytes(scratch.File("a/" + f)), io::ReadFileBytes(scratch.File("b/" + f)))
        << f;
  }
  config.seed = 12;
  const SimulationReport c = SimulatePallets(config, 1, scratch.File("c"), {}, {}, 2);
  EXPECT_NE(io::ReadFileBytes(scratch.File("a/profiles/pallet_000.lcp")),
            io::ReadFileBytes(scratch.File("c/profiles/pallet_000.lcp")));
}

TEST(PalletScene, PartsThatCannotFitAreAnOptionErrorNamingTheRegion) {
  const test::TestDir scratch("pallet_fit");
  PalletSimOptions options;
  options.placement.region_half_size_mm = {300, 250};
  options.placement.max_attempts = 2000;
  SimConfig config = PalletConfig();
  config.timing.profiles = 4;
  try {
    SimulatePallets(config, 1, scratch.File("x"), options);
    ADD_FAILURE() << "no error";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("region_half_size_mm"), std::string::npos) << e.what();
  }
  options = {};
  options.placement.min_gap_mm = -1;
  EXPECT_THROW(SimulatePallets(config, 1, scratch.File("y"), options), OptionError);
  EXPECT_THROW(SimulatePallets(config, 0, scratch.File("y")), OptionError);
}

}  // namespace
}  // namespace lasercell::datasets
