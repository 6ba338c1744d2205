// Profiles over UDP on loopback (127.0.0.1 only): the sender, its impairments and the
// receiving source. Every wait is bounded by the source's idle timeout.
#include "triangulation/udp_stream.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/error.hpp"
#include "core/net_address.hpp"

namespace lasercell::triangulation {
namespace {

ProfileSet MakeSweep(int profiles, std::uint64_t first_sequence) {
  ProfileSet set;
  set.header.image_width = 1024;
  set.header.image_height = 1024;
  set.header.columns = 1024;
  set.header.joint_count = 6;
  set.header.robot = "vision_robot";
  set.header.metadata = "capture: loopback\n";
  for (int i = 0; i < profiles; ++i) {
    Profile p = Profile::Empty(1024, 6);
    p.sequence = first_sequence + static_cast<std::uint64_t>(i);
    p.timestamp_ns = 5'000'000LL * i;
    for (int j = 0; j < 6; ++j) p.joints_rad[j] = 0.001 * i + j;
    for (std::uint32_t c = 0; c < 1024; c += 2) {
      p.row_px[c] = 400.0f + 0.01f * c + 0.1f * i;
      p.intensity[c] = 0.8f;
      p.width_px[c] = 2.0f;
    }
    set.profiles.push_back(std::move(p));
  }
  return set;
}

UdpSourceOptions Loopback() {
  UdpSourceOptions options;
  options.bind_address = "127.0.0.1";
  options.idle_timeout_ms = 3000;  // a test never waits longer for a datagram
  return options;
}

TEST(UdpProfileStream, TwoSweepsArriveWholeAndInOrder) {
  UdpProfileSource source(Loopback());
  ASSERT_GT(source.port(), 0);
  const ProfileSet a = MakeSweep(120, 0), b = MakeSweep(80, 120);
  std::thread sender([&] {
    UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    SendOptions options;
    options.rate_hz = 20000;
    options.datagram.sweep_id = 10;
    SendSweep(udp, a, options);
    options.datagram.sweep_id = 11;
    SendSweep(udp, b, options);
  });
  auto first = source.NextAssembledSweep();
  auto second = source.NextAssembledSweep();
  sender.join();
  ASSERT_TRUE(first.has_value());
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(first->account.sweep_id, 10u);
  EXPECT_EQ(first->account.ended_by, SweepEnd::kComplete);
  EXPECT_EQ(EncodeProfiles(first->set), EncodeProfiles(a));
  EXPECT_EQ(second->account.sweep_id, 11u);
  EXPECT_EQ(EncodeProfiles(second->set), EncodeProfiles(b));
  EXPECT_EQ(source.counters().kernel_dropped, 0u);
  EXPECT_EQ(source.counters().Refused(), 0u);
  EXPECT_EQ(source.last_account()->sweep_id, 11u);
  EXPECT_EQ(source.Describe(), "udp 127.0.0.1:" + std::to_string(source.port()));
}

TEST(UdpProfileStream, ImpairedSendingIsAccountedExactlyOnTheWire) {
  UdpProfileSource source(Loopback());
  const ProfileSet sent = MakeSweep(400, 1000);
  SendOptions options;
  options.impairments.loss = options.impairments.reorder = options.impairments.duplicate = 0.01;
  options.impairments.seed = 5;
  SentAccount sent_account;
  std::thread sender([&] {
    UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    sent_account = SendSweep(udp, sent, options);
  });
  auto sweep = source.NextAssembledSweep();
  sender.join();
  ASSERT_TRUE(sweep.has_value());
  ASSERT_FALSE(sent_account.end_dropped) << "seed 5 keeps END; choose a seed that does";
  ASSERT_GT(sent_account.datagrams_dropped, 0u);
  std::vector<std::uint64_t> missing;
  for (const SequenceRange& r : sweep->account.missing) {
    for (std::uint64_t s = r.first; s <= r.last; ++s) missing.push_back(s);
  }
  EXPECT_EQ(missing, sent_account.lost_profiles);
  EXPECT_EQ(sweep->account.incomplete, sent_account.partial_profiles);
  EXPECT_EQ(sweep->account.delivered,
            400 - sent_account.lost_profiles.size() - sent_account.partial_profiles.size());
  for (const Profile& p : sweep->set.profiles) {
    std::string got, want;
    AppendProfileRecord(sweep->set.header, p, &got);
    AppendProfileRecord(sent.header, sent.profiles[p.sequence - 1000], &want);
    EXPECT_EQ(got, want) << p.sequence;
  }
  EXPECT_EQ(source.counters().kernel_dropped, 0u);
}

// A receiver that does not read while a burst arrives: the OS drops what its small buffer cannot
// hold, the counters say how many, and the account shows the lost profiles.
TEST(UdpProfileStream, DatagramsTheOsDroppedAreCounted) {
  UdpSourceOptions options = Loopback();
  options.receive_buffer_bytes = 65536;
  UdpProfileSource source(options);
  const ProfileSet burst = MakeSweep(200, 0);
  std::size_t sent = 0;
  {
    UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    sent = SendSweep(udp, burst, {}).datagrams_sent;  // as fast as possible, nobody reading
  }
  // A second sweep after the burst, read as it comes: its datagrams carry the drop count.
  std::size_t sent_late = 0;
  std::thread late([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    SendOptions paced;
    paced.rate_hz = 2000;
    paced.datagram.sweep_id = 1;
    sent_late = SendSweep(udp, MakeSweep(5, 1000), paced).datagrams_sent;
  });
  std::vector<AssembledSweep> got;
  while (got.size() < 2) {
    auto sweep = source.NextAssembledSweep();  // ends after 3 s of silence at the latest
    if (!sweep) break;
    got.push_back(std::move(*sweep));
  }
  late.join();
  const StreamCounters& c = source.counters();
  EXPECT_GT(c.kernel_dropped, 0u);
  EXPECT_LE(c.datagrams + c.kernel_dropped, sent + sent_late);
  ASSERT_EQ(got.size(), 2u);
  const SweepAccount& burst_account =
      got[0].account.sweep_id == 0 ? got[0].account : got[1].account;
  EXPECT_EQ(burst_account.sweep_id, 0u);
  EXPECT_LT(burst_account.delivered, 200u);
}

TEST(UdpProfileStream, SilenceEndsTheWaitAndStopInterruptsIt) {
  UdpSourceOptions options = Loopback();
  options.idle_timeout_ms = 100;
  UdpProfileSource source(options);
  EXPECT_FALSE(source.NextSweep().has_value());
  options.idle_timeout_ms = 0;  // for ever, until Stop()
  UdpProfileSource waiting(options);
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    waiting.Stop();
  });
  EXPECT_FALSE(waiting.NextSweep().has_value());
  stopper.join();
}

TEST(UdpProfileStream, GarbageOnThePortIsCountedAndTheStreamGoesOn) {
  UdpProfileSource source(Loopback());
  const ProfileSet sent = MakeSweep(20, 0);
  std::thread sender([&] {
    UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    const std::string junk[] = {"", "hello", std::string(3000, '\xff'), "LCUD\x01\x02"};
    std::vector<const std::string*> all;
    for (const std::string& j : junk) all.push_back(&j);
    udp.Send(all);
    SendSweep(udp, sent, {});
  });
  auto sweep = source.NextAssembledSweep();
  sender.join();
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.delivered, 20u);
  EXPECT_EQ(source.counters().Refused(), 4u);
}

TEST(UdpProfileStream, AddressesAreCheckedWithClearErrors) {
  EXPECT_THROW(net::ParseHostPort("localhost", "--to"), InputError);
  EXPECT_THROW(net::ParseHostPort("127.0.0.1:0", "--to"), InputError);
  EXPECT_THROW(net::ParseHostPort("127.0.0.1:70000", "--to"), InputError);
  EXPECT_THROW(net::ParseHostPort("127.0.0.1:5x", "--to"), InputError);
  EXPECT_EQ(net::ParseHostPort("127.0.0.1:5000", "--to").second, 5000);
  UdpSourceOptions bad = Loopback();
  bad.bind_address = "not an address";
  EXPECT_THROW(UdpProfileSource{bad}, InputError);
  UdpProfileSource holder(Loopback());
  UdpSourceOptions same = Loopback();
  same.port = holder.port();
  try {
    UdpProfileSource second(same);
    FAIL() << "a second listener on the same port was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(holder.port())), std::string::npos);
  }
}

}  // namespace
}  // namespace lasercell::triangulation
