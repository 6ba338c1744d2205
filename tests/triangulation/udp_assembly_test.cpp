// Profile datagrams and sweep reassembly without sockets: time is driven by the test.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>
#include <string>

#include "core/error.hpp"
#include "triangulation/udp_assembler.hpp"
#include "triangulation/udp_packet.hpp"
#include "triangulation/udp_stream.hpp"

namespace lasercell::triangulation {
namespace {

constexpr std::int64_t kMs = 1000000;

ProfileSet MakeSweep(std::uint32_t columns, std::uint32_t joints, int profiles,
                     std::uint64_t first_sequence = 500) {
  ProfileSet set;
  set.header.image_width = 1280;
  set.header.image_height = 1024;
  set.header.first_column = 1280 - columns;
  set.header.columns = columns;
  set.header.joint_count = joints;
  set.header.robot = joints > 0 ? "vision_robot" : "";
  set.header.metadata = "format: lasercell.capture\ncapture: udp test\n";
  for (int i = 0; i < profiles; ++i) {
    Profile p = Profile::Empty(columns, joints);
    p.sequence = first_sequence + static_cast<std::uint64_t>(i);
    p.timestamp_ns = 1'000'000'000LL + 256'410LL * i;  // 3900 profiles/s
    for (std::uint32_t j = 0; j < joints; ++j) p.joints_rad[j] = 0.01 * i - 0.3 * j;
    for (std::uint32_t c = 0; c < columns; ++c) {
      if ((c * 7 + static_cast<std::uint32_t>(i)) % 11 == 0) continue;  // no peak here
      p.row_px[c] = 300.0f + 0.25f * c + 0.001f * i;
      p.intensity[c] = 0.5f + 0.0004f * c;
      p.width_px[c] = 3.0f;
    }
    set.profiles.push_back(std::move(p));
  }
  return set;
}

std::string Record(const ProfileHeader& header, const Profile& p) {
  std::string out;
  AppendProfileRecord(header, p, &out);
  return out;
}

// Every delivered profile is byte-identical to the sent one with its sequence number.
void ExpectDeliveredIdentical(const ProfileSet& sent, const ProfileSet& got) {
  std::map<std::uint64_t, const Profile*> by_sequence;
  for (const Profile& p : sent.profiles) by_sequence[p.sequence] = &p;
  for (const Profile& p : got.profiles) {
    ASSERT_EQ(by_sequence.count(p.sequence), 1u) << p.sequence;
    EXPECT_EQ(Record(got.header, p), Record(sent.header, *by_sequence[p.sequence]))
        << "profile " << p.sequence;
  }
  for (std::size_t i = 1; i < got.profiles.size(); ++i) {
    EXPECT_LT(got.profiles[i - 1].sequence, got.profiles[i].sequence);
  }
}

TEST(ProfileDatagrams, ASweepSplitIntoFragmentsComesBackIdentical) {
  const ProfileSet sent = MakeSweep(1024, 6, 40);
  DatagramOptions options;
  options.sensor_id = 7;
  options.sweep_id = 3;
  const SweepDatagrams d = EncodeSweepDatagrams(sent, options);
  // (1472 - 64 - 6 * 8) / 12 = 113 columns per fragment: 10 fragments per profile.
  ASSERT_EQ(d.datagrams.size(), 40u * 10 + 2);
  for (const std::string& g : d.datagrams) EXPECT_LE(g.size(), 1472u);
  SweepAssembler assembler;
  for (const std::string& g : d.datagrams) assembler.Feed(g, 0);
  auto sweep = assembler.TakeFinished(0);
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.ended_by, SweepEnd::kComplete);
  EXPECT_EQ(sweep->account.sensor_id, 7u);
  EXPECT_EQ(sweep->account.sweep_id, 3u);
  EXPECT_EQ(sweep->account.delivered, 40u);
  EXPECT_EQ(sweep->account.sent_profiles, 40);
  EXPECT_TRUE(sweep->account.missing.empty());
  EXPECT_TRUE(sweep->account.incomplete.empty());
  EXPECT_EQ(sweep->set.header.robot, "vision_robot");
  EXPECT_EQ(sweep->set.header.metadata, sent.header.metadata);
  EXPECT_EQ(EncodeProfiles(sweep->set), EncodeProfiles(sent));
  EXPECT_FALSE(assembler.TakeFinished(0).has_value());
}

TEST(ProfileDatagrams, EveryMalformedDatagramIsRefusedForItsReasonAndCounted) {
  const ProfileSet sent = MakeSweep(64, 2, 3);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  const std::string fragment = d.datagrams[1];
  const auto with = [&](std::size_t offset, const void* bytes, std::size_t n) {
    std::string g = fragment;
    std::memcpy(g.data() + offset, bytes, n);
    return g;
  };
  const std::uint16_t two = 2, huge_joints = 1000;
  const std::uint32_t absurd_columns = 1u << 30, past_end = 60;
  const std::uint8_t version = 9, type = 7;
  const std::vector<std::pair<std::string, DatagramStatus>> cases = {
      {fragment.substr(0, 20), DatagramStatus::kTooShort},
      {fragment.substr(0, 50), DatagramStatus::kTooShort},
      {with(0, "XXXX", 4), DatagramStatus::kBadMagic},
      {with(4, &version, 1), DatagramStatus::kBadVersion},
      {with(5, &type, 1), DatagramStatus::kBadType},
      {fragment.substr(0, fragment.size() - 1), DatagramStatus::kBadLength},
      {fragment + "x", DatagramStatus::kBadLength},
      {with(32, &two, 2), DatagramStatus::kBadFragment},  // index 2 of count 1
      {with(36, &absurd_columns, 4), DatagramStatus::kBadColumns},
      {with(40, &past_end, 4), DatagramStatus::kBadColumns},  // offset + count > columns
      {with(48, &huge_joints, 2), DatagramStatus::kBadJoints},
      {d.datagrams.front().substr(0, 60), DatagramStatus::kBadHeader},
  };
  SweepAssembler assembler;
  Datagram out;
  for (const auto& [bytes, status] : cases) {
    EXPECT_EQ(DecodeDatagram(bytes, DatagramLimits{}, &out), status) << DatagramStatusName(status);
    assembler.Feed(bytes, 0);
  }
  EXPECT_EQ(assembler.counters().Refused(), cases.size());
  EXPECT_EQ(assembler.counters().refused[static_cast<int>(DatagramStatus::kTooShort)], 2u);
  EXPECT_EQ(assembler.counters().refused[static_cast<int>(DatagramStatus::kBadLength)], 2u);
  EXPECT_EQ(assembler.open_sweeps(), 0u);
  // The receiver keeps working: the real sweep after the garbage is delivered whole.
  for (const std::string& g : d.datagrams) assembler.Feed(g, 1);
  auto sweep = assembler.TakeFinished(1);
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.delivered, 3u);
}

TEST(ProfileDatagrams, RandomBytesNeverCrashAndAreRefused) {
  std::mt19937_64 rng(77);
  SweepAssembler random_bytes, random_after_magic;
  for (int i = 0; i < 20000; ++i) {
    std::string g(rng() % 200, '\0');
    for (char& c : g) c = static_cast<char>(rng());
    random_bytes.Feed(g, i);
    if (g.size() >= 8) std::memcpy(g.data(), i % 2 ? "LCUD\x01\x02\0\0" : "LCUD\x01\x03\0\0", 8);
    random_after_magic.Feed(g, i);
  }
  EXPECT_EQ(random_bytes.counters().Refused(), 20000u);
  EXPECT_EQ(random_bytes.counters().refused[static_cast<int>(DatagramStatus::kBadMagic)] +
                random_bytes.counters().refused[static_cast<int>(DatagramStatus::kTooShort)],
            20000u);
  // Behind a valid magic, whatever random fields pass the checks may open sweeps, but no more
  // than the bound, and everything is accounted for.
  EXPECT_EQ(random_after_magic.counters().datagrams, 20000u);
  EXPECT_LE(random_after_magic.open_sweeps(), SweepAssemblyOptions{}.max_open_sweeps);
  EXPECT_GT(random_after_magic.counters().Refused(), 0u);
  random_after_magic.Flush();
}

TEST(ProfileDatagrams, TheSenderRefusesWhatCannotBeSent) {
  ProfileSet set = MakeSweep(32, 0, 2);
  DatagramOptions tiny;
  tiny.max_datagram_bytes = 100;
  EXPECT_THROW(EncodeSweepDatagrams(set, tiny), OptionError);
  set.header.metadata.assign(3000, 'm');
  EXPECT_THROW(EncodeSweepDatagrams(set, {}), InputError);  // header over one datagram
  set = MakeSweep(32, 0, 2);
  set.profiles[1].sequence = set.profiles[0].sequence;
  EXPECT_THROW(EncodeSweepDatagrams(set, {}), InputError);
}

// What the impairing sender dropped is exactly what the receiver reports missing/incomplete;
// what it duplicated is what the receiver reports as duplicates.
TEST(SweepAssembly, TheLossAccountMatchesWhatTheSenderDroppedExactly) {
  const ProfileSet sent = MakeSweep(1024, 6, 300);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  int with_end = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    Impairments imp;
    imp.loss = imp.reorder = imp.duplicate = 0.01;
    imp.seed = seed;
    const ImpairedOrder order = ImpairDatagrams(d.datagrams.size(), imp);
    const SentAccount sent_account = AccountSent(sent, d, order);
    ASSERT_GT(order.dropped.size(), 0u);
    ASSERT_GT(order.reordered, 0u);
    SweepAssembler assembler;
    std::int64_t t = 0;
    for (std::size_t i : order.order) assembler.Feed(d.datagrams[i], t += 1000);
    auto sweep = assembler.TakeFinished(t + 600 * kMs);
    ASSERT_TRUE(sweep.has_value());
    const SweepAccount& acc = sweep->account;
    // Missing = lost profiles, except a lost tail that only END could announce.
    std::vector<std::uint64_t> missing;
    for (const SequenceRange& r : acc.missing) {
      for (std::uint64_t s = r.first; s <= r.last; ++s) missing.push_back(s);
    }
    std::vector<std::uint64_t> expected_missing = sent_account.lost_profiles;
    if (sent_account.end_dropped) {
      EXPECT_EQ(acc.ended_by, SweepEnd::kTimeout);
      std::erase_if(expected_missing, [&](std::uint64_t s) { return s > acc.last_sequence; });
    } else {
      ++with_end;
      EXPECT_EQ(acc.ended_by,
                sent_account.lost_profiles.empty() && sent_account.partial_profiles.empty()
                    ? SweepEnd::kComplete
                    : SweepEnd::kEndGrace);
      EXPECT_EQ(acc.sent_profiles, 300);
    }
    EXPECT_EQ(missing, expected_missing) << "seed " << seed;
    EXPECT_EQ(acc.incomplete, sent_account.partial_profiles) << "seed " << seed;
    EXPECT_EQ(acc.begin_received, !sent_account.begin_dropped);
    std::size_t fragment_duplicates = 0;
    std::set<std::size_t> seen;
    for (std::size_t i : order.order) {
      if (!seen.insert(i).second && d.profile_of[i] >= 0) ++fragment_duplicates;
    }
    EXPECT_EQ(acc.duplicate_fragments, fragment_duplicates) << "seed " << seed;
    EXPECT_EQ(acc.delivered,
              300 - sent_account.lost_profiles.size() - sent_account.partial_profiles.size());
    ExpectDeliveredIdentical(sent, sweep->set);
  }
  EXPECT_GE(with_end, 10);  // END is dropped with probability 1 %
}

TEST(SweepAssembly, ALostProfileIsAGapNeverAProfileWithAnotherTimestamp) {
  const ProfileSet sent = MakeSweep(200, 6, 5);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  SweepAssembler assembler;
  for (std::size_t i = 0; i < d.datagrams.size(); ++i) {
    if (d.profile_of[i] == 2) continue;  // profile 502 lost entirely
    assembler.Feed(d.datagrams[i], 0);
  }
  EXPECT_FALSE(assembler.TakeFinished(19 * kMs).has_value());  // within the END grace
  auto sweep = assembler.TakeFinished(21 * kMs);
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.ended_by, SweepEnd::kEndGrace);
  ASSERT_EQ(sweep->account.missing.size(), 1u);
  EXPECT_EQ(sweep->account.missing[0], (SequenceRange{502, 502}));
  ASSERT_EQ(sweep->set.profiles.size(), 4u);
  EXPECT_EQ(sweep->set.profiles[2].sequence, 503u);
  EXPECT_EQ(sweep->set.profiles[2].timestamp_ns, sent.profiles[3].timestamp_ns);
  EXPECT_EQ(sweep->set.profiles[2].joints_rad, sent.profiles[3].joints_rad);
  EXPECT_NE(sweep->account.Summary().find("1 missing (502)"), std::string::npos)
      << sweep->account.Summary();
}

TEST(SweepAssembly, ASenderThatStopsMidSweepEndsItByTimeout) {
  const ProfileSet sent = MakeSweep(200, 0, 10);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  SweepAssembler assembler;
  for (std::size_t i = 0; i < d.datagrams.size() / 2; ++i) assembler.Feed(d.datagrams[i], 0);
  EXPECT_EQ(assembler.NextDeadlineNs(), 500 * kMs);
  EXPECT_FALSE(assembler.TakeFinished(499 * kMs).has_value());
  auto sweep = assembler.TakeFinished(500 * kMs);
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.ended_by, SweepEnd::kTimeout);
  EXPECT_FALSE(sweep->account.end_received);
  EXPECT_EQ(sweep->account.sent_profiles, -1);
  EXPECT_EQ(sweep->account.delivered + sweep->account.incomplete.size(), 5u);
  ExpectDeliveredIdentical(sent, sweep->set);
  // What still arrives of the ended sweep is stale, not a new sweep...
  assembler.Feed(d.datagrams.back(), 501 * kMs);
  EXPECT_EQ(assembler.counters().stale, 1u);
  EXPECT_EQ(assembler.open_sweeps(), 0u);
  // ... until twice the timeout after its last datagram: then the number starts a new sweep
  // (a sender restarted at the same sweep number).
  assembler.Feed(d.datagrams.front(), 999 * kMs);
  EXPECT_EQ(assembler.counters().stale, 2u);
  assembler.Feed(d.datagrams.front(), 1000 * kMs);
  EXPECT_EQ(assembler.open_sweeps(), 1u);
}

TEST(SweepAssembly, MemoryStaysWithinTheReorderWindowUnderFloods) {
  const ProfileSet sent = MakeSweep(1024, 0, 100);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  SweepAssemblyOptions options;
  options.reorder_window = 8;
  SweepAssembler assembler(options);
  // Only the first fragment of every profile: none completes, at most 8 are held.
  std::size_t last_first_fragment = 0;
  for (std::size_t i = 1; i < d.datagrams.size(); ++i) {
    if (d.profile_of[i] >= 0 && d.profile_of[i] != d.profile_of[i - 1]) {
      assembler.Feed(d.datagrams[i], 0);
      last_first_fragment = i;
    }
  }
  // A duplicate flood of one fragment.
  for (int k = 0; k < 10000; ++k) assembler.Feed(d.datagrams[last_first_fragment], 0);
  EXPECT_EQ(assembler.counters().peak_reassembly, 8u);
  auto sweep = assembler.Flush();
  ASSERT_EQ(sweep.size(), 1u);
  EXPECT_EQ(sweep[0].account.incomplete.size(), 100u);
  EXPECT_EQ(sweep[0].account.delivered, 0u);
  EXPECT_EQ(sweep[0].account.duplicate_fragments, 10000u);
  EXPECT_EQ(sweep[0].account.late_fragments, 0u);
}

TEST(SweepAssembly, OnlyTheChosenSensorIsHeardAndSweepsAreBounded) {
  SweepAssemblyOptions options;
  options.sensor_id = 2;
  options.max_open_sweeps = 2;
  SweepAssembler assembler(options);
  DatagramOptions other;
  other.sensor_id = 1;
  const ProfileSet sent = MakeSweep(100, 0, 3);
  for (const std::string& g : EncodeSweepDatagrams(sent, other).datagrams) assembler.Feed(g, 0);
  EXPECT_EQ(assembler.counters().other_sensor, 5u);
  // Three sweeps of sensor 2 begin; the least recently active one is closed to make room.
  DatagramOptions mine;
  mine.sensor_id = 2;
  for (std::uint32_t s = 0; s < 3; ++s) {
    mine.sweep_id = s;
    assembler.Feed(EncodeSweepDatagrams(sent, mine).datagrams[1], s);
  }
  EXPECT_EQ(assembler.open_sweeps(), 2u);
  auto first = assembler.TakeFinished(3);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->account.sweep_id, 0u);
  EXPECT_EQ(first->account.ended_by, SweepEnd::kSuperseded);
}

TEST(SweepAssembly, FragmentsThatDisagreeWithTheirProfileAreDropped) {
  const ProfileSet sent = MakeSweep(300, 2, 1);
  const SweepDatagrams d = EncodeSweepDatagrams(sent, {});
  ASSERT_EQ(d.datagrams.size(), 3u + 2);  // 3 fragments
  SweepAssembler assembler;
  assembler.Feed(d.datagrams[1], 0);
  std::string moved = d.datagrams[2];
  const std::int64_t other_time = 42;
  std::memcpy(moved.data() + 24, &other_time, 8);  // another timestamp, same sequence
  assembler.Feed(moved, 0);
  EXPECT_EQ(assembler.counters().inconsistent, 1u);
  for (const std::string& g : d.datagrams) assembler.Feed(g, 0);
  auto sweep = assembler.TakeFinished(0);
  ASSERT_TRUE(sweep.has_value());
  EXPECT_EQ(sweep->account.delivered, 1u);
  EXPECT_EQ(sweep->account.inconsistent_fragments, 1u);
  EXPECT_EQ(sweep->account.duplicate_fragments, 1u);
  ExpectDeliveredIdentical(sent, sweep->set);
}

TEST(SweepAssembly, OptionsAreChecked) {
  SweepAssemblyOptions options;
  options.reorder_window = 0;
  EXPECT_THROW(SweepAssembler{options}, OptionError);
  options = {};
  options.sweep_timeout_ms = 0;
  EXPECT_THROW(SweepAssembler{options}, OptionError);
  Impairments imp;
  imp.loss = 1.0;
  EXPECT_THROW(imp.Check(), OptionError);
}

}  // namespace
}  // namespace lasercell::triangulation
