#include "triangulation/linear_sweep.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace lasercell::triangulation {
namespace {

TEST(LinearSweepRecord, WriterAndReaderRoundTripExactly) {
  LinearSweepRecord r;
  r.t0_ns = 1000000000;
  r.velocity_mm_s_in_sensor = Eigen::Vector3d(-0.1, 123.456789012345678, 1e-17);
  r.speed_mm_s = r.velocity_mm_s_in_sensor.norm();
  const std::string text = LinearSweepRecordYaml(r);
  EXPECT_EQ(text.rfind("format: lasercell.linear_sweep\nversion: 1\n", 0), 0u) << text;
  const LinearSweepRecord back = ParseLinearSweepRecord(text, "linear_sweep.yaml");
  EXPECT_EQ(back.t0_ns, r.t0_ns);
  EXPECT_EQ(back.velocity_mm_s_in_sensor, r.velocity_mm_s_in_sensor);
  EXPECT_EQ(back.speed_mm_s, r.speed_mm_s);
  EXPECT_EQ(LinearSweepRecordYaml(back), text);
  const SweepOptions o = back.Options();
  EXPECT_EQ(o.motion, SweepMotion::kLinear);
  EXPECT_EQ(o.velocity_mm_s, r.velocity_mm_s_in_sensor);
  ASSERT_TRUE(o.t0_ns.has_value());
  EXPECT_EQ(*o.t0_ns, r.t0_ns);
}

TEST(LinearSweepRecord, BadFilesNameTheField) {
  const auto message = [](const std::string& text) {
    try {
      ParseLinearSweepRecord(text, "ls.yaml");
    } catch (const OptionError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = "format: lasercell.linear_sweep\nversion: 1\n";
  EXPECT_NE(message(head + "velocity_mm_s_in_sensor: [1, 2, 3]\n").find("'t0_ns' is required"),
            std::string::npos);
  EXPECT_NE(
      message(head + "t0_ns: 0\nvelocity_mm_s_in_sensor: [1, 2]\n").find("velocity_mm_s_in_sensor"),
      std::string::npos);
  EXPECT_NE(message(head + "t0_ns: 0\nvelocity_mm_s_in_sensor: [1, 2, 3]\nspeed: 4\n")
                .find("unknown field 'speed'"),
            std::string::npos);
  EXPECT_NE(message("format: lasercell.sim_sensor\nversion: 1\n").find("format"),
            std::string::npos);
  EXPECT_NE(message("t0_ns: 0\nvelocity_mm_s_in_sensor: [1, 2, 3]\n").find("format"),
            std::string::npos);
  // A non-finite velocity is refused, naming the field (yaml::Fields or the record's own check).
  const std::string nan = message(head + "t0_ns: 0\nvelocity_mm_s_in_sensor: [.nan, 2, 3]\n");
  EXPECT_NE(nan.find("velocity_mm_s_in_sensor"), std::string::npos) << nan;
}

}  // namespace
}  // namespace lasercell::triangulation
