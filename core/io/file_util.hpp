#pragma once
// Whole-file reads and atomic writes (temp file in the same folder + fsync + rename), so a
// crash or a failed write never leaves a half-written calibration, cell file or cloud behind.

#include <string>
#include <string_view>
#include <vector>

namespace lasercell::io {

/// Reads a whole file into memory. Throws FileError when it is missing or unreadable.
std::string ReadFileBytes(const std::string& path);

/// A read-only memory map of a whole file (no copy into a heap buffer: large clouds load
/// faster). Throws FileError like ReadFileBytes. Move-only; unmaps on destruction.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  MappedFile(MappedFile&& other) noexcept;
  MappedFile& operator=(MappedFile&& other) noexcept;
  /// The file's bytes, valid while this object lives.
  std::string_view bytes() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

/// Writes `bytes` to `path` atomically: to `path.tmp-<pid>-XXXXXX` beside it, fsynced, renamed
/// over `path`, and the folder fsynced. Killed at any moment, `path` is the complete old or the
/// complete new file; a temporary a killed writer left is removed by the next write of `path`.
/// On failure nothing at `path` changes and FileError is thrown.
void WriteFileAtomically(const std::string& path, std::string_view bytes);

/// The files matching a shell pattern (glob(3): *, ?, [...]), sorted by name. `what` names the
/// input in the message (e.g. "--images"); no match is an InputError that says to quote the
/// pattern so the shell does not expand it.
std::vector<std::string> GlobFiles(const std::string& pattern, const std::string& what);

/// Lower-case file extension with the dot, e.g. ".ply" (empty when none).
std::string LowerExtension(const std::string& path);

}  // namespace lasercell::io
