#pragma once
// Byte-order-explicit stores and loads through memcpy (alignment-free), so binary files, datagrams
// and frames are identical on every machine: little-endian for lasercell's own files and the
// profile datagrams (triangulation/profile_io, udp_packet), big-endian for the robot protocol's
// frames (localize/robot_protocol), which robot controllers read as network order.

#include <bit>
#include <cstring>
#include <string>
#include <utility>

namespace lasercell::io {

/// Appends `value` to `out` in little-endian byte order.
template <typename T>
inline void PutLe(std::string* out, T value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  out->append(reinterpret_cast<const char*>(b), sizeof(T));
}

/// Reads a little-endian T at `p` (any alignment); the caller has checked the bytes are there.
template <typename T>
inline T GetLe(const char* p) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, b, sizeof(T));
  return value;
}

/// Appends `value` to `out` in big-endian (network) byte order.
template <typename T>
inline void PutBe(std::string* out, T value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  out->append(reinterpret_cast<const char*>(b), sizeof(T));
}

/// Reads a big-endian T at `p` (any alignment); the caller has checked the bytes are there.
template <typename T>
inline T GetBe(const char* p) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, b, sizeof(T));
  return value;
}

}  // namespace lasercell::io
