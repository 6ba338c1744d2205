#pragma once
// Monte-Carlo tests run every draw in the normal build, where their statistics are asserted.
// Under AddressSanitizer or ThreadSanitizer (10-30x slower in these loops) they run a few draws of
// the same code, which is what the sanitizer build is for (memory errors, undefined behaviour);
// their statistical assertions hold only over the full draw count, so they are skipped there.

namespace lasercell::test {

// GCC defines __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__; clang 14 only answers __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitizerBuild = true;
#elif defined(__has_feature)
inline constexpr bool kSanitizerBuild =
    __has_feature(address_sanitizer) || __has_feature(thread_sanitizer);
#else
inline constexpr bool kSanitizerBuild = false;
#endif

// ThreadSanitizer alone (scripts/test-threads).
#if defined(__SANITIZE_THREAD__)
inline constexpr bool kThreadSanitizerBuild = true;
#elif defined(__has_feature)
inline constexpr bool kThreadSanitizerBuild = __has_feature(thread_sanitizer);
#else
inline constexpr bool kThreadSanitizerBuild = false;
#endif

// AddressSanitizer's allocator (clang 14's, seen; GCC's libasan is treated alike) takes none of
// its locks around fork(): a child forked while another thread of the parent held one deadlocks
// on its first allocation (seen in the CAD reader's isolated child). glibc's malloc, the normal
// build's, is fork-safe.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAllocatorForkSafe = false;
#elif defined(__has_feature)
inline constexpr bool kAllocatorForkSafe = !__has_feature(address_sanitizer);
#else
inline constexpr bool kAllocatorForkSafe = true;
#endif

/// Monte-Carlo draws to run: `n` in the normal build, at most 3 under the sanitizer.
constexpr int Draws(int n) { return kSanitizerBuild && n > 3 ? 3 : n; }

/// True when a Monte-Carlo test asserts its statistics (the normal build).
constexpr bool StatisticsAsserted() { return !kSanitizerBuild; }

}  // namespace lasercell::test
