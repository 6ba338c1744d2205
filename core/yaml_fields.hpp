#pragma once
// Strict reading of YAML files that users write (options, simulator configs, records): every
// key is optional unless Require()d, but an unknown key or a value of the wrong type is an
// OptionError naming the file and the dotted field path, e.g.
//   "opts.yaml: unknown field 'matching.refrence_stride' (known fields here: ...)",
// so a typo never falls back silently to a default. One walker per YAML map; Sub() descends.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace lasercell::yaml {

class Fields {
 public:
  /// Parses YAML text; a syntax error is an OptionError naming `name` and the line. An empty
  /// document is an empty map (all defaults).
  static Fields Parse(const std::string& text, const std::string& name);
  /// Reads and parses a file (FileError when it cannot be read).
  static Fields Load(const std::string& path);
  /// A walker over `node` (a map, or null/absent for "no fields"); `path` is the dotted prefix
  /// of this map in the file ("" at the root), `file` names the file in messages.
  Fields(YAML::Node node, std::string path, std::string file);

  /// Optional `format` and `version` keys must equal the given values when present.
  void ExpectFormat(const std::string& format, int version);
  /// True when the key is present and not null.
  bool Has(const char* key) const;
  /// The sub-map at `key` (absent -> a walker without fields); throws when it is not a map.
  Fields Sub(const char* key);

  // Each Read leaves *out unchanged when the key is absent and returns whether it was present.
  bool Read(const char* key, double* out);
  bool Read(const char* key, int* out);
  bool Read(const char* key, std::int64_t* out);
  bool Read(const char* key, std::uint32_t* out);
  bool Read(const char* key, std::uint64_t* out);
  bool Read(const char* key, bool* out);
  bool Read(const char* key, std::string* out);
  /// A list of numbers; exact_size > 0 requires that many.
  bool Read(const char* key, std::vector<double>* out, std::size_t exact_size = 0);
  bool Read(const char* key, std::vector<Eigen::Vector2d>* out);
  template <int N>
  bool Read(const char* key, Eigen::Matrix<double, N, 1>* out) {
    std::vector<double> v;
    if (!Read(key, &v, N)) return false;
    for (int i = 0; i < N; ++i) (*out)[i] = v[static_cast<std::size_t>(i)];
    return true;
  }
  template <std::size_t N>
  bool Read(const char* key, std::array<double, N>* out) {
    std::vector<double> v;
    if (!Read(key, &v, N)) return false;
    for (std::size_t i = 0; i < N; ++i) (*out)[i] = v[i];
    return true;
  }
  /// Like Read, but an absent key is an error ("field 'x' is required").
  template <typename T>
  void ReadRequired(const char* key, T* out) {
    if (!Read(key, out)) Fail(key, "is required");
  }

  /// Marks a key as known without reading it (read elsewhere, e.g. through node()).
  void Known(const char* key) { used_.insert(key); }
  /// Rejects keys that were never read or marked known.
  void Done() const;
  /// Throws OptionError "<file>: field '<path.key>' <problem>".
  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const;
  /// Dotted path of a key in this map.
  std::string Path(const std::string& key) const;
  /// The underlying node (for sequences of maps: iterate and wrap each item in a Fields).
  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }

 private:
  YAML::Node Child(const char* key) const;
  std::optional<YAML::Node> Take(const char* key);
  template <typename T>
  T Scalar(const YAML::Node& n, const std::string& path, const char* expected) const;
  std::vector<double> List(const YAML::Node& n, const std::string& path,
                           std::size_t exact_size) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
  std::set<std::string> used_;
};

}  // namespace lasercell::yaml
