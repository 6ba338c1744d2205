#pragma once
// Fuzz targets: one per input lasercell parses (tests/fuzz/targets/*.cpp).
//
//   LASERCELL_FUZZ_TARGET(ply, PlySeeds) { ... parse `bytes` ... }
//
// (in a named namespace, not an anonymous one) defines `extern "C" lasercell_fuzz_ply(data,
// size)`, the function libFuzzer calls (through
// harness/entry.cpp, one executable per target in a LASERCELL_FUZZ build) and the replay test
// calls on every seed and kept crasher in every build. The body may throw InputError (bad input
// is expected to be refused that way); anything else escaping it — InternalError, a std::
// exception from a library, a crash, a sanitizer report — is a finding. Checks beyond "no
// crash" (parse -> write -> parse gives the same value) use LASERCELL_FUZZ_ASSERT, which aborts
// so libFuzzer keeps the input.
//
// `PlySeeds` returns valid inputs of the format (built by lasercell's own writers from the
// simulator, or read from the repository's data) that start the corpus.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace lasercell::fuzz {

using TargetFunction = int (*)(const std::uint8_t* data, std::size_t size);
using SeedFunction = std::vector<std::string> (*)();

struct Target {
  TargetFunction run = nullptr;
  SeedFunction seeds = nullptr;
};

/// Adds a target to the registry (static initialisation of each target file).
bool RegisterTarget(const char* name, TargetFunction run, SeedFunction seeds);
/// Every registered target by name.
const std::map<std::string, Target>& Targets();

/// The input the running target was given (for Fail's report); set by LASERCELL_FUZZ_TARGET.
void SetCurrentInput(std::string_view bytes);

/// With LASERCELL_FUZZ_VERBOSE=1 in the environment, prints why an input was refused (to check
/// that seeds are accepted and see what mutants trip over).
void NoteRefusal(const char* target, const InputError& refused);
/// Inputs refused so far by this thread (the replay test checks that seeds are accepted).
std::size_t RefusalCount();

/// Prints `what` and the current input (escaped, at most 4 KiB) and aborts (libFuzzer then keeps
/// the input).
[[noreturn]] void Fail(const char* file, int line, const std::string& what);

/// Runs `parse_again` on bytes lasercell itself wrote; refusing them is a finding, not bad input.
void MustAccept(const char* file, int line, const std::function<void()>& parse_again);

/// Bytes of a file in the repository (LASERCELL_SOURCE_DIR-relative); InternalError if absent.
std::string RepositoryFile(const std::string& relative_path);

/// `selector` followed by `rest`: seeds of targets whose first byte chooses a variant.
std::string WithSelector(char selector, const std::string& rest);

/// A scratch folder for targets whose parser reads files (one per process, created once).
const std::string& ScratchDir();

}  // namespace lasercell::fuzz

#define LASERCELL_FUZZ_ASSERT(cond, what)                             \
  do {                                                                \
    if (!(cond)) ::lasercell::fuzz::Fail(__FILE__, __LINE__, (what)); \
  } while (false)

#define LASERCELL_FUZZ_MUST_ACCEPT(...) \
  ::lasercell::fuzz::MustAccept(__FILE__, __LINE__, [&]() { __VA_ARGS__; })

#define LASERCELL_FUZZ_TARGET(name, seeds)                                           \
  static void LasercellFuzzBody_##name(std::string_view bytes);                      \
  extern "C" int lasercell_fuzz_##name(const std::uint8_t* data, std::size_t size) { \
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);         \
    ::lasercell::fuzz::SetCurrentInput(bytes);                                       \
    try {                                                                            \
      LasercellFuzzBody_##name(bytes);                                               \
    } catch (const ::lasercell::InputError& refused) {                               \
      ::lasercell::fuzz::NoteRefusal(#name, refused);                                \
    }                                                                                \
    return 0;                                                                        \
  }                                                                                  \
  [[maybe_unused]] static const bool lasercell_fuzz_registered_##name =              \
      ::lasercell::fuzz::RegisterTarget(#name, &lasercell_fuzz_##name, &seeds);      \
  static void LasercellFuzzBody_##name(std::string_view bytes)
