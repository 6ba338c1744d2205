#pragma once
// Where the profiles of a scan come from. A job asks its source for the next complete sweep; a
// file source holds exactly one (the whole .lcp file), a stream source (a network sensor)
// delivers sweeps as they end. Sources account for what they lost in the ProfileSet itself
// (sequence numbers: SweepResult::sequence_gaps counts the jumps).

#include <memory>
#include <optional>
#include <string>

#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {

/// A source of sweeps of laser profiles.
class ProfileSource {
 public:
  virtual ~ProfileSource() = default;
  /// The next complete sweep; std::nullopt when the source has no more. Throws FileError /
  /// InputError when what it reads is not a valid sweep.
  virtual std::optional<ProfileSet> NextSweep() = 0;
  /// What the source reads, for messages and result files, e.g. "file seat_000.lcp".
  virtual std::string Describe() const = 0;
  /// What the last sweep lost on its way, in one line ("" when nothing was lost); a job keeps
  /// it among its result's notes.
  virtual std::string LastSweepLoss() const { return ""; }
};

/// One .lcp file (profile_io.hpp) as one sweep.
class FileProfileSource : public ProfileSource {
 public:
  explicit FileProfileSource(std::string path) : path_(std::move(path)) {}
  /// The file's profiles the first time (read then, not at construction), nullopt afterwards.
  std::optional<ProfileSet> NextSweep() override {
    if (done_) return std::nullopt;
    done_ = true;
    return ReadProfiles(path_);
  }
  std::string Describe() const override { return "file " + path_; }
  /// The file.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool done_ = false;
};

}  // namespace lasercell::triangulation
