// The robot protocol's frames and lines, and the pose server on loopback (127.0.0.1) with a
// scripted LOOK handler, against well-behaved and misbehaving clients. Every wait is bounded by
// the client's timeouts; the serving thread stops when the test ends.
#include "localize/pose_server.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"
#include "core/se3.hpp"
#include "core/steady_time.hpp"
#include "localize/robot_client.hpp"

namespace lasercell::localize {
namespace {

Eigen::Isometry3d Pose(double x, double y, double z, double rx, double ry, double rz) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = RotationFromFixedXyzDeg({rx, ry, rz});
  return p;
}

TEST(RobotProtocol, FramesAndLinesRoundTrip) {
  RobotRequest look;
  look.command = RobotCommand::kLook;
  look.request_id = 77;
  look.base_from_flange = Pose(812.25, -40.5, 600.0, 179.5, -2.25, 33.0);
  for (const bool ascii : {false, true}) {
    const std::string bytes = ascii ? EncodeAsciiRequest(look) : EncodeBinaryRequest(look);
    const RobotDecode d =
        ascii ? DecodeAsciiRequest(bytes.substr(0, bytes.size() - 1)) : DecodeBinaryRequest(bytes);
    ASSERT_TRUE(d.request.has_value()) << d.error;
    EXPECT_EQ(d.request->command, RobotCommand::kLook);
    if (!ascii) {
      EXPECT_EQ(d.request->request_id, 77);
    }
    ASSERT_TRUE(d.request->base_from_flange.has_value());
    EXPECT_LT(
        (d.request->base_from_flange->translation() - look.base_from_flange->translation()).norm(),
        1e-3);
  }
  EXPECT_EQ(EncodeBinaryRequest(look).size(), kRobotRequestBytes);
  RobotReply reply;
  reply.status = ReplyStatus::kOk;
  reply.request_id = 5;
  reply.part_index = 1;
  reply.part = "seat back";
  reply.instance = 2;
  reply.target_from_grasp = Pose(-1200.125, 300.5, 12.0, 10.0, 20.0, -170.0);
  reply.instances_left = 3;
  reply.position_sigma_mm = 0.042;
  reply.latency_ms = 18.5;
  const std::string frame = EncodeBinaryReply(reply);
  ASSERT_EQ(frame.size(), kRobotReplyBytes);
  // Big-endian: the magic reads "LCRS" as bytes.
  EXPECT_EQ(frame.substr(0, 4), "LCRS");
  EXPECT_EQ(io::GetBe<std::int32_t>(frame.data() + 6 * 4), -1200125);  // x in um
  for (const bool ascii : {false, true}) {
    const auto back = ascii ? DecodeAsciiReply(EncodeAsciiReply(reply)) : DecodeBinaryReply(frame);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->status, ReplyStatus::kOk);
    EXPECT_EQ(back->request_id, 5);
    EXPECT_EQ(back->instance, 2);
    EXPECT_EQ(back->instances_left, 3);
    EXPECT_LT(
        (back->target_from_grasp.translation() - reply.target_from_grasp.translation()).norm(),
        1e-3);
    EXPECT_LT(RotationDistance(back->target_from_grasp, reply.target_from_grasp), 1e-4);
    EXPECT_NEAR(back->position_sigma_mm, 0.042, 1e-3);
    EXPECT_EQ(back->part_index, 1);
    if (ascii) {
      EXPECT_EQ(back->part, "seat_back");
    }  // spaces cannot travel in a field
  }
}

// The robot side refuses a reply line it could not have been sent: a part name with control
// bytes, numbers beyond the encoder's range (it clamps to +-1e9), a negative sigma.
TEST(RobotProtocol, ReplyLinesOutsideWhatTheServerWritesAreRefused) {
  const std::string good = "ok 7 0 seat 1 812.250 -40.500 93.000 0.000 0.000 0.000 1 0.120 3.500";
  ASSERT_TRUE(DecodeAsciiReply(good).has_value());
  std::string nul = good;
  nul[8] = '\0';
  EXPECT_FALSE(DecodeAsciiReply(nul).has_value());
  EXPECT_FALSE(DecodeAsciiReply("ok 7 0 seat 1 1e12 -40.5 93 0 0 0 1 0.12 3.5").has_value());
  EXPECT_FALSE(DecodeAsciiReply("ok 7 0 seat 1 812 -40.5 93 0 0 0 1 -0.12 3.5").has_value());
  EXPECT_FALSE(
      DecodeAsciiReply("ok 7 0 " + std::string(49, 'p') + " 1 1 2 3 0 0 0 1 0.1 3").has_value());
  // Only an ok reply carries a pose: numbers in another reply's pose fields are not one.
  const auto no_part = DecodeAsciiReply("no_part 7 0 - 0 812 -40.5 93 10 0 0 0 0 3.5");
  ASSERT_TRUE(no_part.has_value());
  EXPECT_TRUE(no_part->target_from_grasp.isApprox(Eigen::Isometry3d::Identity()));
  // What the encoder writes for any part name decodes again.
  RobotReply reply;
  reply.part = std::string(
      "a\0b\x01"
      "c",
      5);
  const auto back = DecodeAsciiReply(EncodeAsciiReply(reply));
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->part, "a_b_c");
}

TEST(RobotProtocol, MalformedRequestsSayWhy) {
  RobotRequest ping;
  std::string frame = EncodeBinaryRequest(ping);
  EXPECT_FALSE(DecodeBinaryRequest(frame.substr(0, 47)).request);
  std::string wrong = frame;
  wrong[0] = 'X';
  EXPECT_EQ(DecodeBinaryRequest(wrong).error, "wrong magic");
  wrong = frame;
  wrong[7] = 9;  // version
  EXPECT_NE(DecodeBinaryRequest(wrong).error.find("version"), std::string::npos);
  wrong = frame;
  wrong[11] = 4;  // command
  EXPECT_NE(DecodeBinaryRequest(wrong).error.find("command"), std::string::npos);
  wrong = frame;
  wrong[43] = 2;  // pose flag
  EXPECT_NE(DecodeBinaryRequest(wrong).error.find("pose flag"), std::string::npos);
  for (const char* line :
       {"", "JUMP", "LOOK 1 2 3", "NEXT 1 2 3 4 5 6", "LOOK 1 2 3 4 5 nan", "LOOK 1 2 3 4 5 6 7"}) {
    EXPECT_FALSE(DecodeAsciiRequest(line).request) << line;
  }
  EXPECT_TRUE(DecodeAsciiRequest("LOOK 1 2 3 4 5 6\r").request);
  EXPECT_TRUE(DecodeAsciiRequest("  PING ").request);
  // A pose no robot reaches: the replies' encoder could not write it back (found by fuzzing).
  EXPECT_EQ(DecodeAsciiRequest("LOOK 1e12 2 3 4 5 6").error,
            "pose value beyond +-1e9 (mm or degrees)");
  EXPECT_TRUE(DecodeAsciiRequest("LOOK 1e9 2 3 4 5 -1e9").request);
}

// A server on a thread with a handler that finds two grasps per LOOK.
class PoseServerTest : public ::testing::Test {
 protected:
  void Start(PoseServerOptions options = {}) {
    options.bind_address = "127.0.0.1";
    options.frame_timeout_ms = 300;
    server_ = std::make_unique<PoseServer>(
        [this](const RobotRequest& request) {
          ++looks_;
          std::this_thread::sleep_for(std::chrono::milliseconds(look_delay_ms_.load()));
          LookOutcome out;
          out.sweep_taken_ns = SteadyNowNs();
          flange_seen_ = request.base_from_flange.has_value();
          if (empty_) {
            out.status = ReplyStatus::kNoPart;
            return out;
          }
          for (int k = 1; k <= 2; ++k) {
            RobotReply r;
            r.status = ReplyStatus::kOk;
            r.part = "seat";
            r.part_index = 0;
            r.instance = k;
            r.target_from_grasp = Pose(100.0 * k, 0, 50, 180, 0, 10.0 * k);
            r.position_sigma_mm = 0.05;
            out.grasps.push_back(r);
          }
          out.status = ReplyStatus::kOk;
          return out;
        },
        options);
    thread_ = std::thread([this] { server_->Serve(stop_); });
  }
  void TearDown() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::string Address() const { return "127.0.0.1:" + std::to_string(server_->port()); }
  static RobotRequest Request(RobotCommand command, std::int32_t id = 1) {
    RobotRequest r;
    r.command = command;
    r.request_id = id;
    return r;
  }
  // A robot that connects now gets its PING answered (`when` says when it came, for the failure).
  void ExpectANewRobotIsServed(const std::string& when) const {
    try {
      RobotClient late(Address(), false);
      EXPECT_EQ(late.Request(Request(RobotCommand::kPing), 3000).status, ReplyStatus::kAlive);
    } catch (const InputError& e) {
      ADD_FAILURE() << "the robot that " << when << " was not served: " << e.what();
    }
  }
  // Waits (at most 2 s) until `done` holds: the server thread updates what it checks.
  static bool Eventually(const std::function<bool()>& done) {
    for (int i = 0; i < 200 && !done(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return done();
  }

  std::unique_ptr<PoseServer> server_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> looks_{0};
  std::atomic<int> look_delay_ms_{0};  // the LOOK handler's time, ms
  std::atomic<bool> flange_seen_{false};
  bool empty_ = false;
};

TEST_F(PoseServerTest, APickCycleInBothEncodings) {
  Start();
  for (const bool ascii : {false, true}) {
    RobotClient robot(Address(), ascii);
    RobotRequest look = Request(RobotCommand::kLook, 41);
    look.base_from_flange = Pose(500, 0, 800, 180, 0, 0);
    RobotReply r = robot.Request(look);
    EXPECT_EQ(r.status, ReplyStatus::kOk);
    EXPECT_EQ(r.request_id, ascii ? 1 : 41);  // ASCII replies count the connection's requests
    EXPECT_EQ(r.instance, 1);
    EXPECT_EQ(r.instances_left, 1);
    EXPECT_NEAR(r.target_from_grasp.translation().x(), 100.0, 1e-3);
    EXPECT_GE(r.latency_ms, 0.0);
    EXPECT_TRUE(flange_seen_);
    r = robot.Request(Request(RobotCommand::kNext, 42));
    EXPECT_EQ(r.status, ReplyStatus::kOk);
    EXPECT_EQ(r.instance, 2);
    EXPECT_EQ(r.instances_left, 0);
    EXPECT_NEAR(r.target_from_grasp.translation().x(), 200.0, 1e-3);
    EXPECT_EQ(robot.Request(Request(RobotCommand::kNext, 43)).status, ReplyStatus::kNoMore);
    EXPECT_EQ(robot.Request(Request(RobotCommand::kPing, 44)).status, ReplyStatus::kAlive);
  }
  EXPECT_EQ(looks_, 2);
  empty_ = true;
  RobotClient robot(Address(), false);
  EXPECT_EQ(robot.Request(Request(RobotCommand::kLook)).status, ReplyStatus::kNoPart);
  EXPECT_EQ(robot.Request(Request(RobotCommand::kNext)).status, ReplyStatus::kNoMore);
}

TEST_F(PoseServerTest, GarbageIsAnsweredAndTheConnectionGoesOn) {
  Start();
  RobotClient binary(Address(), false);
  binary.SendRaw("LC" + std::string(46, '\x7f'));  // a binary frame with a broken magic
  EXPECT_EQ(binary.Request(Request(RobotCommand::kPing, 9)).status, ReplyStatus::kBadRequest);
  // The bad frame's reply came first; the PING's is next.
  EXPECT_EQ(binary.Request(Request(RobotCommand::kPing, 10)).status, ReplyStatus::kAlive);
  RobotClient text(Address(), true);
  text.SendRaw("HELLO\n" + std::string(500, 'x') + "\n");
  EXPECT_EQ(text.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kBadRequest);
  EXPECT_EQ(text.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kBadRequest);
  EXPECT_EQ(text.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  EXPECT_TRUE(Eventually([&] { return server_->counters().bad_requests == 3; }));
}

TEST_F(PoseServerTest, AClientStoppingMidFrameIsClosedAndStallsNobody) {
  Start();
  RobotClient stuck(Address(), false);
  stuck.SendRaw(EncodeBinaryRequest(Request(RobotCommand::kPing)).substr(0, 20));
  RobotClient other(Address(), false);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(other.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(250));
  EXPECT_TRUE(Eventually([&] { return server_->counters().frame_timeouts == 1; }));
  EXPECT_THROW(stuck.Request(Request(RobotCommand::kPing), 1000), InputError);
  {
    RobotClient leaving(Address(), true);
    leaving.SendRaw("LOO");
  }
  EXPECT_TRUE(Eventually([&] { return server_->counters().disconnects >= 1; }));
  EXPECT_TRUE(Eventually([&] { return server_->clients() == 1; }));
}

TEST_F(PoseServerTest, ClientsBeyondTheLimitAndSlowReadersAreClosed) {
  PoseServerOptions options;
  options.max_clients = 2;
  options.send_buffer_bytes = 4096;
  options.max_pending_reply_bytes = 4096;
  Start(options);
  RobotClient a(Address(), false), b(Address(), false);
  EXPECT_EQ(a.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  EXPECT_EQ(b.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  RobotClient c(Address(), false);
  EXPECT_THROW(c.Request(Request(RobotCommand::kPing), 2000), InputError);
  EXPECT_TRUE(Eventually([&] { return server_->counters().refused == 1; }));
  // `a` sends PINGs and never reads: its replies pile up until the server closes it.
  std::string flood;
  for (int i = 0; i < 20000; ++i) flood += EncodeBinaryRequest(Request(RobotCommand::kPing));
  try {
    a.SendRaw(flood);
  } catch (const InputError&) {
    // the server may close it while it is still sending
  }
  EXPECT_TRUE(Eventually([&] { return server_->counters().slow_readers == 1; }));
  EXPECT_EQ(b.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
}

// While a LOOK runs the server sees no connection; clients that connect, send and hang up in
// that time wait in the listen queue. When the server gets to them, those already gone must not
// take the place of a robot that is still there.
TEST_F(PoseServerTest, ClientsThatHungUpDuringALookDoNotCountAgainstTheLimit) {
  PoseServerOptions options;
  options.max_clients = 2;
  look_delay_ms_ = 500;
  Start(options);
  RobotClient robot(Address(), false);
  ASSERT_EQ(robot.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  RobotReply look_reply;
  std::thread look([&] { look_reply = robot.Request(Request(RobotCommand::kLook), 5000); });
  ASSERT_TRUE(Eventually([&] { return looks_ == 1; }));
  for (int i = 0; i < 3; ++i) {
    RobotClient gone(Address(), true);
    gone.SendRaw("HELLO\n");
  }
  ExpectANewRobotIsServed("came last");
  look.join();
  EXPECT_EQ(look_reply.status, ReplyStatus::kOk);
  EXPECT_EQ(server_->counters().refused, 0u);
  EXPECT_EQ(server_->counters().connections, 5u);
}

// A client whose half frame went overdue while a LOOK ran is as good as gone: the robot that
// connects next must get its place, not a refusal (the overdue one is closed first).
TEST_F(PoseServerTest, AClientWhoseFrameWentOverdueDuringALookDoesNotCountAgainstTheLimit) {
  PoseServerOptions options;
  options.max_clients = 2;  // Start() sets frame_timeout_ms = 300
  look_delay_ms_ = 900;
  Start(options);
  RobotClient robot(Address(), false);
  ASSERT_EQ(robot.Request(Request(RobotCommand::kPing)).status, ReplyStatus::kAlive);
  RobotClient stalled(Address(), false);
  stalled.SendRaw(EncodeBinaryRequest(Request(RobotCommand::kPing)).substr(0, 10));
  ASSERT_TRUE(Eventually([&] { return server_->clients() == 2; }));  // accepted before the LOOK
  RobotReply look_reply;
  std::thread look([&] { look_reply = robot.Request(Request(RobotCommand::kLook), 5000); });
  ASSERT_TRUE(Eventually([&] { return looks_ == 1; }));
  ExpectANewRobotIsServed("came during the LOOK");
  look.join();
  EXPECT_EQ(look_reply.status, ReplyStatus::kOk);
  EXPECT_EQ(server_->counters().refused, 0u);
  EXPECT_EQ(server_->counters().frame_timeouts, 1u);
}

TEST(PoseServerOptionsTest, BadOptionsAndAddressesAreClearErrors) {
  PoseServerOptions options;
  options.max_clients = 0;
  EXPECT_THROW(options.Check(), OptionError);
  options = {};
  options.bind_address = "localhost";
  EXPECT_THROW(PoseServer([](const RobotRequest&) { return LookOutcome{}; }, options), InputError);
  EXPECT_THROW(RobotClient("127.0.0.1", false), InputError);
}

}  // namespace
}  // namespace lasercell::localize
