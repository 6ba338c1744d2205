// The product's main job on the reference part, end to end through the command line:
// `simulate seat` -> `scan triangulate` (the simulator's true camera and laser plane) ->
// `localize` with the seat's CAD mesh as the model. The gripper needs the 27 mm hole within
// +-10 mm (Skotheim et al. 2012); the SINTEF cell reached 1.8 mm mean after ICP.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/se3.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/linear_sweep.hpp"

namespace lasercell::test {
namespace {

Eigen::Vector3d Vec3(const YAML::Node& node) {
  return Eigen::Vector3d(node[0].as<double>(), node[1].as<double>(), node[2].as<double>());
}

Eigen::Isometry3d Pose(const YAML::Node& node) {
  const YAML::Node q = node["rotation_wxyz"];
  return PoseFromQuaternion(
      Eigen::Quaterniond(q[0].as<double>(), q[1].as<double>(), q[2].as<double>(), q[3].as<double>())
          .normalized(),
      Vec3(node["translation_mm"]));
}

// Placements of seed 11 (not the seeds the mesh-normal fix was tried on: 1, 3, 5). Measured:
// the hole centre 0.18 and 0.47 mm from the truth (seed 5: 0.06-0.58 mm over 6 seats). The error is
// the mesh's facets, not noise: the model's points are the CAD mesh's vertices (192 x 40 around
// the shell), the sweep samples the true curved surface, and ICP fits one to the other. 1.5 mm
// keeps the test well under SINTEF's 1.8 mm mean and a seventh of the gripper's 10 mm.
// Simulation profile: ideal (`simulate seat` without --profile); the realistic chain is tested
// in tests/datasets/table1_bench_test.cpp.
TEST(LocalizeSeat, TheSimulatedSeatsHoleIsFoundWithinAMillimetreAndAHalf) {
  const TestDir dir("localize_seat");
  const std::string sim = (dir.path() / "sim").string();
  CommandResult r = RunCli("simulate seat --placements 2 --seed 11 --quiet --out " + sim);
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const YAML::Node truth = YAML::LoadFile(sim + "/truth/captures.yaml");
  const Eigen::Vector3d v = triangulation::ReadLinearSweepRecord(sim + "/records/linear_sweep.yaml")
                                .velocity_mm_s_in_sensor;
  char velocity[128];
  std::snprintf(velocity, sizeof velocity, "%.17g,%.17g,%.17g", v[0], v[1], v[2]);
  const Eigen::Vector3d hole_in_part = Vec3(truth["hole_center_in_part"]);

  int seats = 0;
  for (const YAML::Node& capture : truth["captures"]) {
    if (capture["kind"].as<std::string>() != "seat") continue;
    const std::string name = capture["name"].as<std::string>();
    const std::string cloud = (dir.path() / (name + ".ply")).string();
    const std::string result = (dir.path() / (name + ".json")).string();
    r = RunCli("scan triangulate --quiet --sensor-truth " + sim + "/truth/sensor.yaml --camera " +
               sim + "/truth/camera.cameramodel --profiles " + sim + "/profiles/" + name +
               ".lcp --velocity-mm-s=" + velocity + " --out " + cloud);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // The sweep's sensor frame at t0 looks along its +z.
    r = RunCli("localize --model " + sim + "/models/seat.ply --scene " + cloud +
               " --view-direction 0,0,1 --out " + result);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("scene_from_model: {translation_mm: ["), std::string::npos) << r.out;

    const nlohmann::json j = nlohmann::json::parse(Slurp(result));
    ASSERT_TRUE(j["found"].get<bool>()) << name << ": " << j["message"];
    // The pose in the file notation {translation_mm, rotation_wxyz}, as cell.yaml holds it.
    const nlohmann::json& pose = j["candidates"][0]["scene_from_model"];
    const std::vector<double> q = pose["rotation_wxyz"].get<std::vector<double>>();
    const std::vector<double> t = pose["translation_mm"].get<std::vector<double>>();
    ASSERT_EQ(q.size(), 4u);
    ASSERT_EQ(t.size(), 3u);
    const Eigen::Isometry3d sensor_from_seat = PoseFromQuaternion(
        Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Eigen::Vector3d(t[0], t[1], t[2]));
    const Eigen::Isometry3d base_from_sensor =
        Pose(capture["sweep"]["handling_base_from_sensor_at_t0"]);
    const Eigen::Vector3d hole_true = Vec3(capture["hole_center_in_handling_base"]);
    const Eigen::Vector3d hole_found = base_from_sensor * sensor_from_seat * hole_in_part;
    const double error_mm = (hole_found - hole_true).norm();
    EXPECT_LT(error_mm, 1.5) << name;
    std::printf("%s: hole centre %.3f mm from the truth\n", name.c_str(), error_mm);
    ++seats;
  }
  EXPECT_EQ(seats, 2);
}

}  // namespace
}  // namespace lasercell::test
