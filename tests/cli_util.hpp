#pragma once
// Helpers shared by the tests that run processes and touch files: running the `lasercell`
// binary (or any shell command) and capturing its exit code and output, reading and writing
// whole files, and per-test scratch folders.
//
// Conventions: commands are shell text (arguments are passed to /bin/sh as written, so quotes
// and globs in them work as on a command line); an exit code of -1 means the process could not
// be started or did not exit normally (killed by a signal). LASERCELL_CLI (the path of the built
// `lasercell` binary) is defined for every test binary by tests/CMakeLists.txt.

#include <gtest/gtest.h>
#include <stdlib.h>  // mkstemp (POSIX)
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

namespace lasercell::test {

/// What one run of a command reported.
struct CommandResult {
  int exit_code = -1;  ///< the process's exit status; -1 when it did not start or exit normally
  std::string out;     ///< standard output (both streams, interleaved, for RunCliMerged)
  std::string err;     ///< standard error (empty for RunCliMerged and RunCommand)
};

/// The whole content of a file, bytes as stored; "" when it cannot be opened (tests compare or
/// parse it, so a missing file shows up as a failed expectation, not an exception).
inline std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes `text` to `path` (created or truncated), bytes as given.
inline void Spit(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// The exit code of a std::system / pclose status (-1 when the process did not exit normally).
inline int ExitCode(int status) {
  return status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Runs the shell command `command` and returns its exit code and standard output (standard
/// error is not redirected: append " 2>&1" to capture it too, or " 2>/dev/null" to drop it).
inline CommandResult RunCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    result.err = "popen failed for: " + command;
    return result;
  }
  char buffer[4096];
  while (const std::size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) {
    result.out.append(buffer, n);
  }
  result.exit_code = ExitCode(pclose(pipe));
  return result;
}

namespace detail {

/// A new empty file <tmp>/lasercell_<tag>_XXXXXX, unique even across parallel test processes.
inline std::filesystem::path UniqueTempFile(const std::string& tag) {
  std::string name =
      (std::filesystem::temp_directory_path() / ("lasercell_" + tag + "_XXXXXX")).string();
  const int fd = mkstemp(name.data());
  if (fd < 0) {
    ADD_FAILURE() << "mkstemp failed for " << name;
    return {};
  }
  ::close(fd);
  return name;
}

}  // namespace detail

/// Runs `lasercell <args>` and returns its exit code, standard output and standard error, each
/// captured separately (in temporary files that are removed afterwards, so nothing is left in
/// the folders the test looks at).
inline CommandResult RunCli(const std::string& args) {
  const std::filesystem::path out = detail::UniqueTempFile("cli_out");
  const std::filesystem::path err = detail::UniqueTempFile("cli_err");
  CommandResult result;
  if (out.empty() || err.empty()) return result;
  const std::string command =
      std::string(LASERCELL_CLI) + " " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  result.exit_code = ExitCode(std::system(command.c_str()));
  result.out = Slurp(out);
  result.err = Slurp(err);
  std::error_code ignored;
  std::filesystem::remove(out, ignored);
  std::filesystem::remove(err, ignored);
  return result;
}

/// Runs `lasercell <args> 2>&1`: `out` holds standard output and standard error interleaved in
/// the order the process wrote them; `err` stays empty.
inline CommandResult RunCliMerged(const std::string& args) {
  return RunCommand(std::string(LASERCELL_CLI) + " " + args + " 2>&1");
}

/// Loads the HTML page at `path` in Debian's headless chromium started with the extra command
/// line `flags` (e.g. "--use-angle=swiftshader --enable-unsafe-swiftshader --screenshot=FILE
/// --window-size=1000,800" for WebGL and a PNG of the window) and returns the DOM after its
/// scripts ran; "" when chromium did not run (scripts/install-deps installs it).
inline std::string HeadlessChromium(const std::string& path, const std::string& flags) {
  const std::string command = "chromium --headless --no-sandbox --disable-dev-shm-usage " + flags +
                              " --dump-dom 'file://" + path + "' 2>/dev/null";
  return RunCommand(command).out;
}

/// HeadlessChromium without a GPU: the DOM of the page at `path` after its scripts ran.
inline std::string HeadlessChromiumDom(const std::string& path) {
  return HeadlessChromium(path, "--disable-gpu");
}

/// A fresh, empty folder <tmp>/lasercell_<tag>_<test name>_<pid> for the running test (without
/// the test name outside a test, e.g. in SetUpTestSuite); a leftover of an earlier run is removed
/// first. The pid keeps parallel test processes (ctest -j) apart.
inline std::filesystem::path MakeTestDir(const std::string& tag) {
  std::string name = "lasercell_" + tag + "_";
  if (const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info()) {
    std::string test = info->name();
    std::replace(test.begin(), test.end(), '/', '_');  // parameterized tests: Name/0
    name += test + "_";
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / (name + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Removes a folder made by MakeTestDir, unless the environment sets LASERCELL_KEEP_TEST_FILES
/// (then the inputs and outputs of the test stay there to look at).
inline void RemoveTestDir(const std::filesystem::path& dir) {
  if (std::getenv("LASERCELL_KEEP_TEST_FILES") != nullptr) return;
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
}

/// A MakeTestDir folder owned by a scope: removed (see RemoveTestDir) when it goes out of scope.
class TestDir {
 public:
  explicit TestDir(const std::string& tag) : path_(MakeTestDir(tag)) {}
  ~TestDir() { RemoveTestDir(path_); }
  TestDir(const TestDir&) = delete;
  TestDir& operator=(const TestDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  /// Path of `name` inside the folder, as a string.
  std::string File(const std::string& name) const { return (path_ / name).string(); }
  /// How many entries (files and folders) the folder holds directly.
  std::size_t Entries() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(path_),
                                                  std::filesystem::directory_iterator()));
  }

 private:
  std::filesystem::path path_;
};

}  // namespace lasercell::test
