#pragma once
// lasercell error hierarchy (ARCHITECTURE.md "Errors, three tiers").
//  (1) invalid input or options   -> InputError (or a subclass); the CLI exits 2.
//  (2) expected algorithmic outcome -> reported in a ...Result struct, never thrown.
//  (3) broken internal invariant  -> InternalError via LASERCELL_CHECK; the CLI exits 1.
// Messages name the input (file, option, field), say what is wrong and what to do.

#include <stdexcept>
#include <string>

namespace lasercell {

/// Base of every exception lasercell throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Invalid input data or options supplied by the caller (tier 1).
class InputError : public Error {
 public:
  using Error::Error;
};

/// A file that cannot be read, parsed or written. what() starts with the path.
class FileError : public InputError {
 public:
  FileError(const std::string& path, const std::string& problem)
      : InputError(path + ": " + problem), path_(path) {}
  /// The offending file.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// An options struct field out of range. what() names the struct and field.
class OptionError : public InputError {
 public:
  using InputError::InputError;
};

/// A broken internal invariant (a bug in lasercell, tier 3).
class InternalError : public Error {
 public:
  using Error::Error;
};

namespace internal {
[[noreturn]] void ThrowCheckFailure(const char* condition, const char* file, int line,
                                    const std::string& message);
}  // namespace internal

}  // namespace lasercell

/// Tier-3 invariant check: throws lasercell::InternalError with location when cond is false.
#define LASERCELL_CHECK(cond, message)                                                           \
  do {                                                                                           \
    if (!(cond)) ::lasercell::internal::ThrowCheckFailure(#cond, __FILE__, __LINE__, (message)); \
  } while (false)
