// Writes that survive a kill: a child process writes a kept file over and over, alternating two
// versions, and is SIGKILLed at a random moment, 200 times per file type. Afterwards the file
// must be one complete version, byte for byte, and at most the killed writer's temporary may be
// left (the next write removes it). Every kept file lasercell writes goes through
// io::WriteFileAtomically; the file types here are written by their own savers: the cell
// (every calibration tool), a .cameramodel, a .ppfm, a job result and a point cloud.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/json_io.hpp"
#include "localize/job_run.hpp"
#include "registration/ppf_model.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell {
namespace {

using Writer = std::function<void(const std::string& path, int version)>;
/// What of a file's bytes must equal one version (the bytes themselves, unless the file holds
/// something that changes on every write, such as a date).
using Comparable = std::function<std::string(const std::string& bytes)>;

constexpr int kKills = 200;

std::size_t TemporariesOf(const std::filesystem::path& file) {
  std::size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(file.parent_path())) {
    if (e.path().filename().string().rfind(file.filename().string() + ".tmp-", 0) == 0) ++n;
  }
  return n;
}

// Kills a writer `kKills` times; records how often it found version 0, version 1, a temporary.
void KillWritersOf(
    const std::string& name, const Writer& write,
    const Comparable& comparable = [](const std::string& b) { return b; }) {
  const test::TestDir dir("kill_during_write");
  const std::string path = dir.File(name);
  write(path, 1);
  const std::string version1 = comparable(io::ReadFileBytes(path));
  write(path, 0);
  const std::string version0 = comparable(io::ReadFileBytes(path));
  ASSERT_NE(version0, version1) << "the two versions must differ for the test to see a change";

  // Kill moments: after 0, 1 or 2 writes the child reports complete, plus a random delay of up to
  // one write's time (fsyncs make it vary). Counting the writes through a pipe keeps the moments
  // spread over the versions however slow the child is to start (a loaded machine, a sanitizer).
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 5; ++i) write(path, i % 2);
  const auto per_write = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start) /
                         5;
  std::mt19937 rng(std::hash<std::string>{}(name));
  std::uniform_int_distribution<int> writes_before(0, 2);
  std::uniform_int_distribution<long> delay_us(0, std::max<long>(per_write.count(), 200));

  int saw[2] = {0, 0};
  int saw_temporary = 0;
  for (int k = 0; k < kKills; ++k) {
    int done[2];
    ASSERT_EQ(::pipe(done), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::close(done[0]);
      for (int v = 1;; v ^= 1) {  // until killed
        write(path, v);
        if (::write(done[1], "w", 1) != 1) ::_exit(3);
      }
    }
    ::close(done[1]);
    char byte = 0;
    for (int w = writes_before(rng); w > 0; --w) ASSERT_EQ(::read(done[0], &byte, 1), 1);
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng)));
    ::kill(child, SIGKILL);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ::close(done[0]);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the writer failed itself";
    const std::string bytes = io::ReadFileBytes(path);
    const std::string now = comparable(bytes);
    ASSERT_TRUE(now == version0 || now == version1)
        << name << ": kill " << k << " left " << bytes.size() << " bytes that are neither version";
    ++saw[now == version1 ? 1 : 0];
    const std::size_t temporaries = TemporariesOf(path);
    ASSERT_LE(temporaries, 1u) << "temporaries of killed writers accumulate";
    saw_temporary += temporaries > 0 ? 1 : 0;
  }
  write(path, 0);
  EXPECT_EQ(TemporariesOf(path), 0u) << "a write removes the temporary a killed writer left";
  // The kills landed at different moments: both versions and half-written temporaries seen.
  EXPECT_GT(saw[0], 0);
  EXPECT_GT(saw[1], 0);
  // Under ThreadSanitizer the instrumented encoding takes nearly all of a write's time and the
  // temporary exists only for its last part (0 of 200 kills found one, seen): the versions
  // and the bound on temporaries above are checked there all the same.
  if (!test::kThreadSanitizerBuild) {
    EXPECT_GT(saw_temporary, 0);
  }
  ::testing::Test::RecordProperty(name + "_kills", kKills);
  ::testing::Test::RecordProperty(
      name + "_old_new_temporary",
      std::to_string(saw[0]) + "/" + std::to_string(saw[1]) + "/" + std::to_string(saw_temporary));
}

TEST(KillDuringWrite, TheCellIsAlwaysOneCompleteVersion) {
  const FrameGraph cell =
      LoadFrameGraph(std::string(LASERCELL_SOURCE_DIR) + "/datasets/demo/cell.yaml");
  KillWritersOf("cell.yaml", [&](const std::string& path, int version) {
    FrameGraph g = cell;
    if (version == 1) g.AddFrame("kill_test_marker");
    SaveFrameGraph(path, g);
  });
}

TEST(KillDuringWrite, TheCameraModelIsAlwaysOneCompleteVersion) {
  const calib::CameraModel a("LENSMODEL_OPENCV8",
                             {1200, 1190, 640.5, 480.25, -0.1, 0.05, 1e-4, -2e-4, 0.01, 0, 0, 0},
                             1280, 960);
  const calib::CameraModel b("LENSMODEL_PINHOLE", {800, 800, 511.5, 383.5}, 1024, 768);
  KillWritersOf("camera.cameramodel", [&](const std::string& path, int version) {
    calib::SaveCameraModel(path, version == 0 ? a : b);
  });
}

TEST(KillDuringWrite, ThePpfModelIsAlwaysOneCompleteVersion) {
  PointCloud sphere;
  for (int i = 0; i < 600; ++i) {
    const double z = -1.0 + 2.0 * (i + 0.5) / 600.0;
    const double phi = 2.399963 * i;
    const Eigen::Vector3d n(std::sqrt(1 - z * z) * std::cos(phi),
                            std::sqrt(1 - z * z) * std::sin(phi), z);
    sphere.positions.push_back(40.0 * n);
    sphere.normals.push_back(n);
  }
  registration::PpfModelOptions coarse;
  coarse.sampling_step_relative = 0.08;
  const auto a = registration::PpfModel::Build(sphere, coarse);
  registration::PpfModelOptions fine;
  fine.sampling_step_relative = 0.05;
  const auto b = registration::PpfModel::Build(sphere, fine);
  KillWritersOf("part.ppfm",
                [&](const std::string& path, int version) { (version == 0 ? a : b).Save(path); });
}

TEST(KillDuringWrite, TheJobResultIsAlwaysOneCompleteVersion) {
  localize::JobResult first;
  localize::JobResult second;
  second.notes = {"the second version"};
  // The result carries the date it was written: compared without it, and a partial file does
  // not parse.
  KillWritersOf(
      "result.json",
      [&](const std::string& path, int version) {
        json::WriteFile(path, localize::JobResultJson(version == 0 ? first : second));
      },
      [](const std::string& bytes) {
        nlohmann::json j = nlohmann::json::parse(bytes, nullptr, false);
        if (j.is_discarded()) return std::string("not JSON: ") + bytes;
        j.erase("date");
        return j.dump();
      });
}

TEST(KillDuringWrite, APointCloudIsAlwaysOneCompleteVersion) {
  PointCloud cloud;
  for (int i = 0; i < 50000; ++i) cloud.positions.emplace_back(i, 0.5 * i, 1.0);
  KillWritersOf("sweep.ply", [&](const std::string& path, int version) {
    PointCloud c = cloud;
    c.positions[0].x() = version;
    io::WritePointCloud(path, c);
  });
}

}  // namespace
}  // namespace lasercell
