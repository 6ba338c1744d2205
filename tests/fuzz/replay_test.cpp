// The fuzz targets (tests/fuzz/targets) in every build, without libFuzzer: each target's seeds,
// the crashers kept under tests/fuzz/regressions/<target>/, and a fixed set of mutants of the
// seeds go through it. A crash, a sanitizer report, an exception other than InputError, or a
// failed round-trip check (which aborts) fails this test. scripts/fuzz runs the same targets
// under libFuzzer (LASERCELL_FUZZ builds).

#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/io/file_util.hpp"
#include "tests/fuzz/harness/fuzz_target.hpp"

namespace lasercell::fuzz {
namespace {

const std::filesystem::path kRegressions =
    std::filesystem::path(LASERCELL_SOURCE_DIR) / "tests/fuzz/regressions";

void Feed(const Target& target, const std::string& bytes) {
  target.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

// One to four edits of the kinds that break parsers: a flipped bit, a byte set to a delimiter
// or an extreme, a cut, a deleted or repeated stretch, inserted bytes.
std::string Mutate(std::string s, std::mt19937_64& rng) {
  static const char kSpecial[] = {'\0', '\n', ' ', '-', '9', '[', ']', '{', ':', '\xff', '\x7f'};
  const auto pick = [&](std::size_t n) { return n == 0 ? 0 : rng() % n; };
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    const std::size_t at = pick(s.size() + 1);
    switch (rng() % 6) {
      case 0:
        if (at < s.size()) s[at] = static_cast<char>(s[at] ^ (1 << (rng() % 8)));
        break;
      case 1:
        if (at < s.size()) s[at] = kSpecial[pick(sizeof(kSpecial))];
        break;
      case 2:
        s.resize(at);
        break;
      case 3:
        s.erase(at, 1 + pick(16));
        break;
      case 4:
        s.insert(at, s.substr(at, 1 + pick(64)));
        break;
      default:
        for (std::size_t k = 0, n = 1 + pick(8); k < n; ++k) {
          s.insert(s.begin() + static_cast<std::ptrdiff_t>(at), static_cast<char>(rng()));
        }
    }
  }
  return s;
}

TEST(FuzzTargets, EveryInputLasercellParsesHasATarget) {
  const std::set<std::string> expected = {"cad",
                                          "cameramodel",
                                          "cell_yaml",
                                          "corners",
                                          "job",
                                          "lcp",
                                          "line_scan",
                                          "localize_options",
                                          "obj",
                                          "part",
                                          "pcd",
                                          "ply",
                                          "ppfm",
                                          "robot_poses",
                                          "robot_protocol",
                                          "stl",
                                          "touches",
                                          "udp_datagram",
                                          "udp_stream"};
  std::set<std::string> registered;
  for (const auto& [name, target] : Targets()) registered.insert(name);
  EXPECT_EQ(registered, expected);
}

TEST(FuzzTargets, EverySeedIsAcceptedByItsTarget) {
  for (const auto& [name, target] : Targets()) {
    SCOPED_TRACE(name);
    const std::vector<std::string> seeds = target.seeds();
    EXPECT_FALSE(seeds.empty()) << "a target without seeds starts libFuzzer from nothing";
    for (std::size_t k = 0; k < seeds.size(); ++k) {
      const std::size_t refused_before = RefusalCount();
      Feed(target, seeds[k]);
      EXPECT_EQ(RefusalCount(), refused_before)
          << "seed " << k << " is refused (LASERCELL_FUZZ_VERBOSE=1 says why): a seed must be a "
          << "valid input, or the fuzzer starts outside the format";
    }
  }
}

TEST(FuzzTargets, KeptCrashersStayFixed) {
  ASSERT_TRUE(std::filesystem::is_directory(kRegressions)) << kRegressions;
  std::size_t inputs = 0;
  for (const auto& dir : std::filesystem::directory_iterator(kRegressions)) {
    if (!dir.is_directory()) continue;
    const std::string name = dir.path().filename().string();
    ASSERT_TRUE(Targets().count(name)) << "tests/fuzz/regressions/" << name << " names no target";
    for (const auto& file : std::filesystem::directory_iterator(dir.path())) {
      SCOPED_TRACE(file.path().string());
      Feed(Targets().at(name), io::ReadFileBytes(file.path().string()));
      ++inputs;
    }
  }
  RecordProperty("regression_inputs", std::to_string(inputs));
}

TEST(FuzzTargets, MutatedSeedsAreReadOrRefusedNeverCrash) {
  for (const auto& [name, target] : Targets()) {
    SCOPED_TRACE(name);
    // A CAD read is an OpenCASCADE translation in a child process (~0.1 s): fewer of those.
    const int mutants = name == "cad" ? 30 : 300;
    const std::vector<std::string> seeds = target.seeds();
    ASSERT_FALSE(seeds.empty());
    std::mt19937_64 rng(std::hash<std::string>{}(name));
    for (int k = 0; k < mutants; ++k) {
      Feed(target, Mutate(seeds[static_cast<std::size_t>(k) % seeds.size()], rng));
    }
  }
}

}  // namespace
}  // namespace lasercell::fuzz
