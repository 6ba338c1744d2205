#include "core/io/lzf.hpp"

namespace lasercell::io::detail {

std::string LzfDecompress(std::span<const unsigned char> input, std::span<unsigned char> output) {
  const std::size_t in_size = input.size();
  const std::size_t out_size = output.size();
  std::size_t ip = 0;  // read position in input
  std::size_t op = 0;  // write position in output
  while (ip < in_size) {
    const std::size_t chunk_at = ip;
    const unsigned ctrl = input[ip++];
    if (ctrl < 32) {
      const std::size_t run = ctrl + 1;
      if (run > in_size - ip) {
        return "literal run of " + std::to_string(run) + " bytes at input offset " +
               std::to_string(chunk_at) + " runs past the end of the compressed data";
      }
      if (run > out_size - op) {
        return "literal run at input offset " + std::to_string(chunk_at) +
               " would write past the declared uncompressed size " + std::to_string(out_size);
      }
      for (std::size_t k = 0; k < run; ++k) output[op + k] = input[ip + k];
      ip += run;
      op += run;
      continue;
    }
    std::size_t length = ctrl >> 5;
    if (length == 7) {
      if (ip >= in_size) {
        return "back reference at input offset " + std::to_string(chunk_at) +
               " is cut off by the end of the compressed data";
      }
      length += input[ip++];
    }
    if (ip >= in_size) {
      return "back reference at input offset " + std::to_string(chunk_at) +
             " is cut off by the end of the compressed data";
    }
    const std::size_t distance = ((static_cast<std::size_t>(ctrl) & 0x1f) << 8) + input[ip++] + 1;
    length += 2;
    if (distance > op) {
      return "back reference at input offset " + std::to_string(chunk_at) + " points " +
             std::to_string(distance) + " bytes back but only " + std::to_string(op) +
             " bytes have been decompressed";
    }
    if (length > out_size - op) {
      return "back reference at input offset " + std::to_string(chunk_at) +
             " would write past the declared uncompressed size " + std::to_string(out_size);
    }
    // Byte by byte: source and destination overlap when distance < length (run-length case).
    for (std::size_t k = 0; k < length; ++k) output[op + k] = output[op + k - distance];
    op += length;
  }
  if (op != out_size) {
    return "data decompressed to " + std::to_string(op) + " bytes but the header declares " +
           std::to_string(out_size);
  }
  return {};
}

}  // namespace lasercell::io::detail
