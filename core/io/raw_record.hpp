#pragma once
// Fixed-layout binary records of lasercell's own data: values and arrays of plain types copied
// bytewise in the machine's byte order (x86-64 and arm64: little-endian). Used by the `.ppfm`
// model file (registration/ppf_model_io.cpp, which pins little-endian) and by results passed
// between processes (localize/cad_import.cpp). Arrays are a u64 count and the raw elements.
// Element types must be trivially copyable records (double, u32, Eigen fixed-size vectors).

#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace lasercell::io {

/// Appends values and arrays to a byte string.
class RawWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    out_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <typename T>
  void PutArray(const std::vector<T>& values) {
    Put(static_cast<std::uint64_t>(values.size()));
    if (!values.empty()) {
      out_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
    }
  }
  void PutString(std::string_view text) {
    Put(static_cast<std::uint64_t>(text.size()));
    out_.append(text);
  }
  /// The bytes so far (append a header or a checksum directly).
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

/// Reads what RawWriter wrote. A read past the end calls `fail` with the problem (e.g.
/// "truncated at field 'points'"); `fail` must throw (the reader throws InternalError if it
/// returns).
class RawReader {
 public:
  RawReader(std::string_view bytes, std::function<void(const std::string& problem)> fail)
      : bytes_(bytes), fail_(std::move(fail)) {}
  template <typename T>
  T Get(const char* field) {
    Need(sizeof(T), field);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  template <typename T>
  std::vector<T> GetArray(const char* field) {
    const auto count = Get<std::uint64_t>(field);
    if (count > (bytes_.size() - pos_) / sizeof(T))
      Fail(std::string("truncated array '") + field + "'");
    std::vector<T> values(static_cast<std::size_t>(count));
    if (count > 0) {
      std::memcpy(static_cast<void*>(values.data()), bytes_.data() + pos_,
                  values.size() * sizeof(T));
    }
    pos_ += values.size() * sizeof(T);
    return values;
  }
  std::string GetString(const char* field) {
    const auto size = Get<std::uint64_t>(field);
    if (size > bytes_.size() - pos_) Fail(std::string("truncated string '") + field + "'");
    std::string text(bytes_.substr(pos_, static_cast<std::size_t>(size)));
    pos_ += text.size();
    return text;
  }
  /// Bytes read so far.
  std::size_t position() const { return pos_; }
  /// True when every byte was read.
  bool AtEnd() const { return pos_ == bytes_.size(); }
  /// Reports `problem` through the failure function.
  [[noreturn]] void Fail(const std::string& problem) const {
    fail_(problem);
    throw InternalError("RawReader: the failure function returned for: " + problem);
  }

 private:
  void Need(std::size_t n, const char* field) const {
    if (bytes_.size() - pos_ < n) Fail(std::string("truncated at field '") + field + "'");
  }
  std::string_view bytes_;
  std::function<void(const std::string&)> fail_;
  std::size_t pos_ = 0;
};

}  // namespace lasercell::io
