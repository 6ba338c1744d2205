#pragma once
// The one in-memory 8-bit image of the toolkit: rendered by the simulator, decoded from files for
// board detection and the laser-stripe calibration. Row-major, channels interleaved (1: gray;
// 3: BGR, the order OpenCV decodes colour files in), no padding: channel c of pixel (x, y) at
// pixels[(y * width + x) * channels + c].

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lasercell {

/// An 8-bit image of `channels` interleaved channels, row-major.
struct Image8 {
  int width = 0;
  int height = 0;
  int channels = 1;                  ///< 1 (gray) or 3 (BGR).
  std::vector<std::uint8_t> pixels;  ///< width * height * channels values, row-major.

  /// Channel `c` of pixel (x, y).
  std::uint8_t at(int x, int y, int c = 0) const {
    const std::size_t pixel =
        static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
    return pixels[pixel * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)];
  }
};

}  // namespace lasercell
