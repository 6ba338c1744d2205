// Under ThreadSanitizer, OpenCV runs its own parallel loops on the calling thread. Its loops
// (the chessboard detectors, remap, calibrateCamera) run on Debian's uninstrumented libtbb, whose
// hand-overs TSan cannot see: a buffer filled on an OpenCV worker and read back on the caller
// was reported as a race inside libopencv_calib3d with no lasercell frame in either stack, and
// neither a race: nor a called_from_lib: suppression of the OpenCV libraries silenced it (nor
// did OPENCV_FOR_THREADS_NUM=1). No lasercell code runs inside cv::parallel_for_, so this hides
// none of lasercell's own threads; the normal and ASan builds keep OpenCV's threads.
#include <gtest/gtest.h>

#include <opencv2/core/utility.hpp>

#include "tests/sanitizer_scale.hpp"

namespace {

class OpenCvSerialUnderTsan : public ::testing::Environment {
 public:
  void SetUp() override {
    if (lasercell::test::kThreadSanitizerBuild) cv::setNumThreads(0);
  }
};

[[maybe_unused]] ::testing::Environment* const kOpenCvSerialUnderTsan =
    ::testing::AddGlobalTestEnvironment(new OpenCvSerialUnderTsan);

}  // namespace
