#include "tests/fuzz/harness/fuzz_target.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/io/file_util.hpp"

namespace lasercell::fuzz {
namespace {

std::map<std::string, Target>& Registry() {
  static std::map<std::string, Target> registry;
  return registry;
}

}  // namespace

bool RegisterTarget(const char* name, TargetFunction run, SeedFunction seeds) {
  Registry()[name] = Target{run, seeds};
  return true;
}

const std::map<std::string, Target>& Targets() { return Registry(); }

namespace {
thread_local std::string_view current_input;
thread_local std::size_t refusals = 0;
}  // namespace

void SetCurrentInput(std::string_view bytes) { current_input = bytes; }

std::size_t RefusalCount() { return refusals; }

void NoteRefusal(const char* target, const InputError& refused) {
  ++refusals;
  static const bool verbose = [] {
    const char* env = std::getenv("LASERCELL_FUZZ_VERBOSE");
    return env != nullptr && std::string(env) == "1";
  }();
  if (verbose) std::fprintf(stderr, "%s refused: %s\n", target, refused.what());
}

void Fail(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "lasercell fuzz finding at %s:%d: %s\n", file, line, what.c_str());
  std::string escaped;
  for (const char c : current_input.substr(0, 4096)) {
    if (c == '\\') {
      escaped += "\\\\";
    } else if (c == '\n' || (c >= ' ' && c <= '~')) {
      escaped += c;
    } else {
      char hex[5];
      std::snprintf(hex, sizeof(hex), "\\x%02x", static_cast<unsigned char>(c));
      escaped += hex;
    }
  }
  std::fprintf(stderr, "input (%zu bytes):\n%s\n", current_input.size(), escaped.c_str());
  std::fflush(stderr);
  std::abort();
}

void MustAccept(const char* file, int line, const std::function<void()>& parse_again) {
  try {
    parse_again();
  } catch (const InputError& e) {
    Fail(file, line, std::string("lasercell refused what it wrote itself: ") + e.what());
  }
}

std::string RepositoryFile(const std::string& relative_path) {
#ifdef LASERCELL_SOURCE_DIR
  return io::ReadFileBytes(std::string(LASERCELL_SOURCE_DIR) + "/" + relative_path);
#else
  throw InternalError("fuzz seeds: built without LASERCELL_SOURCE_DIR, cannot read " +
                      relative_path);
#endif
}

std::string WithSelector(char selector, const std::string& rest) {
  std::string out(1, selector);
  out += rest;
  return out;
}

const std::string& ScratchDir() {
  // Removed when the process exits normally (libFuzzer's -runs/-max_total_time end with exit()).
  struct Scratch {
    std::filesystem::path path;
    ~Scratch() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Scratch scratch{[] {
    std::filesystem::path base =
        std::filesystem::temp_directory_path() / ("lasercell-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(base);
    return base;
  }()};
  static const std::string dir = scratch.path.string();
  return dir;
}

}  // namespace lasercell::fuzz
