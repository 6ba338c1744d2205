// `lasercell stream send` and `lasercell scan record --udp` as processes on loopback: what the
// recorder writes is what the sender sent minus what its impairments dropped, and bad input
// exits 2 with one line. Every wait is bounded (the recorder's --timeout-s, a polling limit).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/cli_util.hpp"
#include "tests/net_util.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {
namespace {

namespace fs = std::filesystem;

class StreamCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::MakeTestDir("stream");
    ProfileSet set;
    set.header.columns = 640;
    set.header.image_width = 640;
    set.header.image_height = 480;
    set.header.metadata = "capture: stream cli\n";
    for (int i = 0; i < 200; ++i) {
      Profile p = Profile::Empty(640);
      p.sequence = 10 + static_cast<std::uint64_t>(i);
      p.timestamp_ns = 1000LL * i;
      for (std::uint32_t c = 0; c < 640; c += 3) {
        p.row_px[c] = 200.0f + 0.5f * i;
        p.intensity[c] = 0.9f;
        p.width_px[c] = 2.0f;
      }
      set.profiles.push_back(std::move(p));
    }
    WriteProfiles(P("in.lcp"), set);
    sent_ = set;
  }
  void TearDown() override { test::RemoveTestDir(dir_); }
  std::string P(const std::string& f) const { return (dir_ / f).string(); }

  fs::path dir_;
  ProfileSet sent_;
};

TEST_F(StreamCli, TheRecorderWritesWhatArrivedAndAccountsForWhatDidNot) {
  const std::string port = std::to_string(test::FreeLoopbackPort(SOCK_DGRAM));
  const std::string cli = LASERCELL_CLI;
  // The recorder in the background; the sender starts once it listens (at most 5 s of polling).
  const std::string script =
      cli + " scan record --udp " + port + " --bind 127.0.0.1 --out '" + P("got.lcp") +
      "' --timeout-s 5 --account-json '" + P("received.json") + "' > '" + P("rec.log") +
      "' 2>&1 & rec=$!; for i in $(seq 100); do grep -q listening '" + P("rec.log") +
      "' && break; sleep 0.05; done; " + cli + " stream send '" + P("in.lcp") +
      "' --to 127.0.0.1:" + port +
      " --rate 20000 --datagram-bytes 1472 --loss 0.05 --duplicate 0.05 --reorder 0.05 --seed 4 "
      "--account-json '" +
      P("sent.json") + "'; wait $rec; echo recorder exit $?";
  const test::CommandResult run = test::RunCommand(script + " 2>&1");
  EXPECT_NE(run.out.find("recorder exit 0"), std::string::npos)
      << run.out << test::Slurp(P("rec.log"));
  const auto sent = nlohmann::json::parse(test::Slurp(P("sent.json")));
  const auto received = nlohmann::json::parse(test::Slurp(P("received.json")));
  const auto& s = sent["sweeps"][0];
  const auto& r = received["sweep"];
  ASSERT_FALSE(s["end_dropped"].get<bool>()) << "seed 4 keeps END";
  ASSERT_GT(s["lost_profiles"].size() + s["partial_profiles"].size(), 0u);
  std::vector<std::uint64_t> missing;
  for (const auto& range : r["missing"]) {
    for (auto q = range[0].get<std::uint64_t>(); q <= range[1].get<std::uint64_t>(); ++q) {
      missing.push_back(q);
    }
  }
  EXPECT_EQ(missing, s["lost_profiles"].get<std::vector<std::uint64_t>>());
  EXPECT_EQ(r["incomplete"], s["partial_profiles"]);
  EXPECT_EQ(received["format"], "lasercell.stream_received");
  const ProfileSet got = ReadProfiles(P("got.lcp"));
  EXPECT_EQ(got.profiles.size(), 200 - s["lost_profiles"].size() - s["partial_profiles"].size());
  EXPECT_EQ(got.header.metadata, sent_.header.metadata);
  for (const Profile& p : got.profiles) {
    std::string a, b;
    AppendProfileRecord(got.header, p, &a);
    AppendProfileRecord(sent_.header, sent_.profiles[p.sequence - 10], &b);
    EXPECT_EQ(a, b) << p.sequence;
  }
  EXPECT_NE(test::Slurp(P("rec.log")).find("missing"), std::string::npos);
}

TEST_F(StreamCli, BadInputExitsTwoWithOneLine) {
  const std::string in = "'" + P("in.lcp") + "'";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"stream send '" + P("none.lcp") + "' --to 127.0.0.1:5000", "none.lcp"},
      {"stream send " + in + " --to localhost", "HOST:PORT"},
      {"stream send " + in + " --to 127.0.0.1:99999", "port"},
      {"stream send " + in + " --to 127.0.0.1:5000 --loss 1.5", "loss"},
      {"stream send " + in + " --to 127.0.0.1:5000 --datagram-bytes 100", "max_datagram_bytes"},
      {"scan record --udp " + std::to_string(test::FreeLoopbackPort(SOCK_DGRAM)) +
           " --bind 127.0.0.1 --timeout-s 0.2 --out '" + P("never.lcp") + "'",
       "no sweep arrived"},
      {"scan record --udp 5000 --bind 300.1.1.1 --out '" + P("never.lcp") + "'", "IPv4"},
  };
  for (const auto& [args, expected] : cases) {
    const test::CommandResult r = test::RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(P("never.lcp")));
}

}  // namespace
}  // namespace lasercell::triangulation
