#pragma once
// What a calibration tool records about its run (EdgeProvenance in core/frame_graph.hpp): the
// UTC time of the run and a digest that identifies the input bytes.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace lasercell {

/// The current time as ISO 8601 UTC to the second, e.g. "2026-11-26T10:00:00Z".
std::string UtcTimestampIso();

/// FNV-1a 64 over byte strings fed in order: identifies inputs, it is not a security digest.
class InputDigest {
 public:
  void Add(std::string_view bytes);
  /// Adds the whole content of a file (FileError when it cannot be read).
  void AddFile(const std::string& path);
  std::uint64_t value() const { return h_; }
  /// "fnv1a64:<16 hex digits>".
  std::string Text() const;

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

/// FNV-1a 64 of one byte string (the same hash as InputDigest).
std::uint64_t Fnv1a64(std::string_view bytes);

}  // namespace lasercell
