// An absent real data set skips its tests on a developer's machine and fails them where
// $LASERCELL_REQUIRE_SHARED_DATA is set (CI): this binary runs one of its own real-data tests
// with the data root pointed at an empty place, both ways.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <string>

namespace {

struct SelfRun {
  int exit_code = -1;
  std::string output;
};

SelfRun RunSelf(const std::string& env) {
  std::array<char, 4096> self{};
  const ssize_t n = readlink("/proc/self/exe", self.data(), self.size() - 1);
  EXPECT_GT(n, 0);
  const std::string cmd = "env -u LASERCELL_REQUIRE_SHARED_DATA " + env +
                          " LASERCELL_SHARED_DATA=/nonexistent/shared-data '" +
                          std::string(self.data()) +
                          "' --gtest_filter=SphereSectionHandEyeReal.* 2>&1";
  SelfRun run;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) run.output += buf.data();
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

TEST(SharedDataPolicy, AbsentSetSkipsLocallyAndFailsWhenRequired) {
  const SelfRun local = RunSelf("");
  EXPECT_EQ(local.exit_code, 0) << local.output;
  EXPECT_NE(local.output.find("SKIPPED"), std::string::npos) << local.output;
  EXPECT_NE(local.output.find("laser_robot_sphere not found"), std::string::npos) << local.output;
  const SelfRun ci = RunSelf("LASERCELL_REQUIRE_SHARED_DATA=1");
  EXPECT_NE(ci.exit_code, 0) << ci.output;
  EXPECT_NE(ci.output.find("FAILED"), std::string::npos) << ci.output;
  EXPECT_NE(ci.output.find("LASERCELL_REQUIRE_SHARED_DATA is set"), std::string::npos) << ci.output;
}

}  // namespace
