// RunServeLoad: a few seconds of the hostile load against a handler with a fixed answer, and
// against one whose answer drifts, which the load must report as wrong answers.
#include "localize/serve_load.hpp"

#include <gtest/gtest.h>

#include <atomic>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "core/steady_time.hpp"

namespace lasercell::localize {
namespace {

// Two grasps per LOOK; from LOOK number `drift_from` on, the second one moves by 10 um (both
// encodings carry 1 um).
LookHandler TwoGrasps(std::atomic<int>* looks, int drift_from) {
  return [looks, drift_from](const RobotRequest&) {
    const int n = ++*looks;
    LookOutcome out;
    out.sweep_taken_ns = SteadyNowNs();
    for (int k = 1; k <= 2; ++k) {
      RobotReply r;
      r.status = ReplyStatus::kOk;
      r.part = "seat";
      r.part_index = 0;
      r.instance = k;
      r.target_from_grasp = PoseFromRotationVector({0.1, 0.2, 0.3 * k}, {100.0 * k, -20.0, 50.0});
      if (k == 2 && n >= drift_from) r.target_from_grasp.translation().x() += 0.01;
      r.position_sigma_mm = 0.05;
      out.grasps.push_back(r);
    }
    out.status = ReplyStatus::kOk;
    return out;
  };
}

ServeLoadOptions ShortLoad() {
  ServeLoadOptions o;
  o.clients = 4;
  o.seconds = 3.0;
  o.warmup_seconds = 0.5;
  o.server.frame_timeout_ms = 200.0;
  o.server.send_buffer_bytes = 8192;  // so unread replies reach the server's own bound
  return o;
}

TEST(ServeLoad, EveryValidRequestIsAnsweredRightAmongMisbehavingClients) {
  std::atomic<int> looks{0};
  const ServeLoadReport r = RunServeLoad(TwoGrasps(&looks, 1 << 30), ShortLoad());
  std::printf("%s", r.Markdown().c_str());
  for (const std::string& p : r.problems) std::printf("  %s\n", p.c_str());
  EXPECT_EQ(r.reference_replies, 4u);  // LOOK, NEXT, NEXT -> NO_MORE, PING
  EXPECT_GT(r.valid_cycles, 0u);
  EXPECT_EQ(r.valid_requests, 4 * r.valid_cycles);
  EXPECT_EQ(r.wrong_answers, 0u);
  EXPECT_EQ(r.failed_cycles, 0u);
  // Every kind of misbehaviour happened, and the server saw it as such.
  EXPECT_GT(r.garbage + r.half_frames + r.stalled_frames + r.slow_readers + r.bad_lines, 5u);
  EXPECT_GT(r.server.bad_requests, 0u);
  EXPECT_GT(r.server.disconnects, 0u);
  EXPECT_GT(r.server.frame_timeouts, 0u);
  EXPECT_GT(r.server.slow_readers, 0u);
  EXPECT_GT(r.rss_end_mb, 0.0);
}

TEST(ServeLoad, AnAnswerThatChangesIsReportedWrong) {
  std::atomic<int> looks{0};
  // The reference cycles are LOOKs 1 and 2; from the 4th on, the second grasp moves.
  const ServeLoadReport r = RunServeLoad(TwoGrasps(&looks, 4), ShortLoad());
  ASSERT_GT(r.valid_cycles, 1u);
  EXPECT_GT(r.wrong_answers, 0u);
  ASSERT_FALSE(r.problems.empty());
  EXPECT_NE(r.problems[0].find("expected"), std::string::npos) << r.problems[0];
}

TEST(ServeLoad, OptionsNameTheField) {
  ServeLoadOptions o;
  o.warmup_seconds = o.seconds;
  try {
    o.Check();
    FAIL() << "no error";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("warmup_seconds"), std::string::npos) << e.what();
  }
  o = ServeLoadOptions{};
  o.server.max_clients = 0;
  EXPECT_THROW(o.Check(), OptionError);
}

}  // namespace
}  // namespace lasercell::localize
