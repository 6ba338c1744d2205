#pragma once
// Monte-Carlo tests run every draw in the normal build, where their statistics are asserted.
// Under AddressSanitizer (10-30x slower in these loops) they run a few draws of the same code,
// which is what the sanitizer build is for (memory errors, undefined behaviour); their
// statistical assertions hold only over the full draw count, so they are skipped there.

namespace lasercell::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizerBuild = true;
#else
inline constexpr bool kSanitizerBuild = false;
#endif

/// Monte-Carlo draws to run: `n` in the normal build, at most 3 under the sanitizer.
constexpr int Draws(int n) { return kSanitizerBuild && n > 3 ? 3 : n; }

/// True when a Monte-Carlo test asserts its statistics (the normal build).
constexpr bool StatisticsAsserted() { return !kSanitizerBuild; }

}  // namespace lasercell::test
