#pragma once
// Internal to core/io: LZF decompression for PCD "DATA binary_compressed" (PCL writes it with
// liblzf). Our own bounds-checked decoder; no third-party code.
//
// LZF stream (liblzf lzf_d.c): a sequence of chunks, each starting with a control byte c.
//   c < 32:  literal run; the next c + 1 bytes are copied to the output.
//   c >= 32: back reference; length L = c >> 5 (when L == 7 the next byte is added to it), then
//            one more byte b; copy L + 2 bytes from `output_pos - ((c & 31) << 8) - b - 1`
//            (the source may overlap the bytes being written, as in run-length coding).

#include <cstddef>
#include <span>
#include <string>

namespace lasercell::io::detail {

/// Decompresses `input` into `output`, which must be exactly the expected decompressed size.
/// Returns an empty string on success, otherwise what is wrong (a literal run or back
/// reference past the end of the input or output, a back reference before the start of the
/// output, or fewer bytes produced than `output` holds), with the input offset.
std::string LzfDecompress(std::span<const unsigned char> input, std::span<unsigned char> output);

/// Largest output an LZF stream of `compressed_bytes` can produce: a 3-byte back reference
/// yields at most 264 bytes. Used to reject absurd declared sizes before allocating.
inline std::size_t LzfMaxDecompressedSize(std::size_t compressed_bytes) {
  return compressed_bytes / 3 * 264 + 264;
}

}  // namespace lasercell::io::detail
