#pragma once
// Where the tests find the real development data sets that may NOT be bundled in datasets/
// (no licence stated: laser_stripe_chessboard, handeye_kuka2; see /work/shared/data/PROVENANCE.md
// and datasets/real/README.md). They are read from $LASERCELL_SHARED_DATA, else from
// <repo>/../shared/data (CI clones next to shared/). Absent: the test calls
// LASERCELL_SHARED_DATA_ABSENT(SharedDataMissing(set)) — a clear skip, never a silent pass, and a
// failure when $LASERCELL_REQUIRE_SHARED_DATA is set (.ci/run sets it: a CI without the data
// must not go green).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace lasercell::shared_data {

/// The shared data root: $LASERCELL_SHARED_DATA when set, else <repo>/../shared/data.
inline std::string SharedDataRoot() {
  if (const char* env = std::getenv("LASERCELL_SHARED_DATA"); env != nullptr && *env != '\0') {
    return env;
  }
  return std::string(LASERCELL_SOURCE_DIR) + "/../shared/data";
}

/// Folder of the set, or "" when it is not a directory.
inline std::string SharedDataSet(const std::string& set) {
  const std::string dir = SharedDataRoot() + "/" + set;
  return std::filesystem::is_directory(dir) ? dir : std::string();
}

/// True when $LASERCELL_REQUIRE_SHARED_DATA is set to anything but "" or "0": an absent set
/// fails the test instead of skipping it.
inline bool SharedDataRequired() {
  const char* env = std::getenv("LASERCELL_REQUIRE_SHARED_DATA");
  return env != nullptr && *env != '\0' && std::string(env) != "0";
}

/// The skip message for an absent set.
inline std::string SharedDataMissing(const std::string& set) {
  return "real data set " + set + " not found at " + SharedDataRoot() + "/" + set +
         " (not redistributable: no licence); put the development data at ../shared/data next "
         "to the source tree or set LASERCELL_SHARED_DATA to run this test";
}

/// Records the end of a test for an absent set: a failure when SharedDataRequired(), else a
/// skip, with `message` (usually SharedDataMissing(set)). Use LASERCELL_SHARED_DATA_ABSENT.
inline void ReportAbsentSet(const std::string& message) {
  if (SharedDataRequired()) {
    GTEST_FAIL() << message << " ($LASERCELL_REQUIRE_SHARED_DATA is set)";
  }
  GTEST_SKIP() << message;
}

}  // namespace lasercell::shared_data

/// Ends the calling test for an absent set (see ReportAbsentSet). A statement:
/// `if (dir.empty()) LASERCELL_SHARED_DATA_ABSENT(SharedDataMissing("set"));`.
#define LASERCELL_SHARED_DATA_ABSENT(message) \
  return ::lasercell::shared_data::ReportAbsentSet(message)
