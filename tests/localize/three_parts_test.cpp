// RunJob on the simulator's pallet scene (Skotheim et al., Fig. 4): seat, seat back and armrest
// in one sweep, each part file one instance. The back and the armrest are STEP models the job
// samples at its own 1 mm step, while the sweep was rendered from a 0.02 mm tessellation of the
// same files. The cell knows the sensor's true placement (this checks the job pipeline, not the
// calibration chain).
// Simulation profile: ideal (SimConfig{}, seed 31).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "datasets/simulate_pallets.hpp"
#include "datasets/simulate_records.hpp"
#include "localize/job_run.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell::localize {
namespace {

class ThreeParts : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TestDir("three_parts");
    const std::string sim = dir_->File("sim");
    datasets::SimConfig config;
    config.seed = 31;
    const datasets::PalletSimOptions options;
    datasets::SimulatePallets(config, kScenes, sim, options, {}, 0);
    truth_ = new FrameGraph(LoadFrameGraph(sim + "/truth/cell.yaml"));
    // The cell: handling_base <- sensor at the sweep's t0 and the true laser plane.
    config.sweep_length_mm = options.sweep_length_mm;
    const datasets::CellTruth cell_truth = datasets::MakeCellTruth(config);
    const datasets::LinearSweep sweep = datasets::MakeLinearSweep(config, cell_truth.sensor);
    FrameGraph cell = *truth_;
    cell.RemoveEdge("vision_flange", "sensor");
    StaticEdge edge;
    edge.parent = "handling_base";
    edge.child = "sensor";
    edge.SetParentFromChild(cell_truth.layout.cell_from_handling_base.inverse() * sweep.At(0.0));
    cell.SetStaticEdge(edge);
    const datasets::SimSensorTruth sensor = datasets::ReadSensorTruth(sim + "/truth/sensor.yaml");
    LaserPlaneEntry plane;
    plane.normal = sensor.laser_normal_in_sensor;
    plane.point_mm = -sensor.laser_d_mm * sensor.laser_normal_in_sensor;
    cell.SetLaserPlane("laser", plane);
    SaveFrameGraph(dir_->File("cell.yaml"), cell);
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete dir_;
  }
  static std::string WriteJob(int scene) {
    char name[32];
    std::snprintf(name, sizeof(name), "pallet_%03d", scene);
    const std::string path = dir_->File(std::string(name) + ".job.yaml");
    io::WriteFileAtomically(path,
                            "format: lasercell.job\nversion: 1\ncell: cell.yaml\n"
                            "camera: sim/truth/camera.cameramodel\n"
                            "source: {file: sim/profiles/" +
                                std::string(name) +
                                ".lcp}\n"
                                "trajectory: {linear: sim/records/linear_sweep.yaml}\n"
                                "parts:\n"
                                "  - {part: sim/models/seat.part.yaml, instances: 1}\n"
                                "  - {part: sim/models/back.part.yaml, instances: 1}\n"
                                "  - {part: sim/models/armrest.part.yaml, instances: 1}\n"
                                // The back's panel and wings are extruded along its y:
                                // only the ridge, the bosses and the end faces hold a fit
                                // in y. Thinned to the default 1500 ICP source points,
                                // too few of them stay and the fit slides (8.1 mm in
                                // pallet_001); at 6000 it is held (0.02 mm).
                                "localize: {max_icp_source_points: 6000}\n");
    return path;
  }
  // Sanitizer time: one pallet scene (the same three parts and job) instead of two.
  static constexpr int kScenes = test::kSanitizerBuild ? 1 : 2;
  static test::TestDir* dir_;
  static FrameGraph* truth_;
};
test::TestDir* ThreeParts::dir_ = nullptr;
FrameGraph* ThreeParts::truth_ = nullptr;

// Every part is reported exactly once with its grasps within 1 mm and graspable (Skotheim et
// al., Fig. 4, and the three-part target). The armrest is the hard one: the smallest part
// (~4.5k sweep points), its upright walls barely lit by the vertical laser plane, a thin shell
// whose two faces share the model's voxels.
TEST_F(ThreeParts, EachPartIsFoundOnceWithItsGraspWithinAMillimetre) {
  for (int scene = 0; scene < kScenes; ++scene) {
    SCOPED_TRACE("pallet_" + std::to_string(scene));
    const Job job = ReadJobFile(WriteJob(scene));
    JobRunOptions options;
    options.threads = 2;
    const JobResult result = RunJob(job, options);
    std::map<std::string, int> found;
    for (const PartInstance& inst : result.parts.instances) ++found[inst.part];
    for (const char* part : {"seat", "back", "armrest"}) {
      EXPECT_EQ(found[part], 1) << part << ": " << result.Summary();
    }
    // Each search reports the work behind its time.
    for (const PartSearch& s : result.parts.searches) {
      SCOPED_TRACE(s.part);
      EXPECT_GT(s.sampled_points, s.reference_points);
      EXPECT_GT(s.reference_points, 0U);
      EXPECT_GT(s.scene_pairs, s.reference_points);
      EXPECT_GT(s.votes_cast, s.scene_pairs);  // every search here has flooded keys
      EXPECT_GE(s.judgement_ms, 0.0);
    }
    for (const PartInstance& inst : result.parts.instances) {
      SCOPED_TRACE(inst.frame);
      char frame[32];
      std::snprintf(frame, sizeof(frame), "%s_%03d", inst.part.c_str(), scene);
      const Eigen::Isometry3d truth = truth_->Transform("handling_base", frame);
      const JobPart* part = nullptr;
      for (const JobPart& p : job.parts) part = p.part.name == inst.part ? &p : part;
      ASSERT_NE(part, nullptr);
      ASSERT_EQ(inst.grasps.size(), part->part.grasps.size());
      for (const GraspPose& g : inst.grasps) {
        const Eigen::Isometry3d grasp_truth =
            truth * part->part.Grasp(g.name).part_from_grasp.ToIsometry();
        const double error_mm =
            (g.target_from_grasp.translation() - grasp_truth.translation()).norm();
        const double axis_deg =
            std::acos(std::clamp(
                g.target_from_grasp.linear().col(2).dot(grasp_truth.linear().col(2)), -1.0, 1.0)) *
            180.0 / M_PI;
        EXPECT_LT(error_mm, 1.0) << g.name;
        EXPECT_LT(axis_deg, 1.0) << g.name;
        EXPECT_TRUE(inst.graspable) << inst.not_graspable_reason;
        RecordProperty("scene" + std::to_string(scene) + "_" + inst.part + "_grasp_error_mm",
                       std::to_string(error_mm));
      }
      EXPECT_FALSE(inst.ambiguous) << inst.ambiguity_reason;
    }
  }
}

}  // namespace
}  // namespace lasercell::localize
