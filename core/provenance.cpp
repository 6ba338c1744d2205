#include "core/provenance.hpp"

#include <cstdio>
#include <ctime>

#include "core/io/file_util.hpp"

namespace lasercell {

std::string UtcTimestampIso() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void InputDigest::Add(std::string_view bytes) {
  for (const char c : bytes) {
    h_ ^= static_cast<unsigned char>(c);
    h_ *= 1099511628211ull;
  }
}

void InputDigest::AddFile(const std::string& path) { Add(io::ReadFileBytes(path)); }

std::string InputDigest::Text() const {
  char buf[40];
  std::snprintf(buf, sizeof buf, "fnv1a64:%016llx", static_cast<unsigned long long>(h_));
  return buf;
}

std::uint64_t Fnv1a64(std::string_view bytes) {
  InputDigest d;
  d.Add(bytes);
  return d.value();
}

}  // namespace lasercell
