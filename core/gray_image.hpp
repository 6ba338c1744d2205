#pragma once
// The one in-memory 8-bit gray image of the toolkit: rendered by the simulator, decoded from
// files for board detection. Row-major, no padding, pixel (x, y) at pixels[y * width + x].

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lasercell {

/// An 8-bit gray image, row-major.
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< width * height values, row-major.
  std::uint8_t at(int x, int y) const {
    return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                  static_cast<std::size_t>(x)];
  }
};

}  // namespace lasercell
