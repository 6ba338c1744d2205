// fuzz_seeds OUT_DIR: writes every fuzz target's seeds to OUT_DIR/<target>/seed_<k> (the start
// of scripts/fuzz's corpora); `fuzz_seeds --list` prints the target names.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "core/io/file_util.hpp"
#include "tests/fuzz/harness/fuzz_target.hpp"

int main(int argc, char** argv) {
  using lasercell::fuzz::Targets;
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR | --list\n");
    return 2;
  }
  const std::string arg = argv[1];
  try {
    for (const auto& [name, target] : Targets()) {
      if (arg == "--list") {
        std::printf("%s\n", name.c_str());
        continue;
      }
      const std::filesystem::path dir = std::filesystem::path(arg) / name;
      std::filesystem::create_directories(dir);
      const auto seeds = target.seeds();
      for (std::size_t k = 0; k < seeds.size(); ++k) {
        lasercell::io::WriteFileAtomically((dir / ("seed_" + std::to_string(k))).string(),
                                           seeds[k]);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
