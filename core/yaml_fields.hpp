#pragma once
// Strict reading of YAML files that users write (options, simulator configs, records, cell
// files): every key is optional unless Require()d, but an unknown key, a key given twice or a
// value of the wrong type is an error naming the file, the line and the field path, e.g.
//   "opts.yaml: line 4: unknown field 'matching.refrence_stride' (known fields here: ...)",
//   "cell.yaml: line 12: field 'edges[2].parent_from_child.rotation_wxyz' has norm 1.2; ...",
// so a typo never falls back silently to a default. One walker per YAML map; Sub() descends,
// List() walks a list of maps (paths `key[i]`, counted from 0). An unknown key that is a known
// one in another unit says so ("did you mean 'radius_mm'? (lasercell uses millimetres)").
// Units in files: mm and rad.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"

namespace lasercell::yaml {

/// `text` as a YAML double-quoted scalar, escaping quotes, backslashes and control bytes: how
/// every lasercell YAML writer writes a name, a path or a description, so that any text reads
/// back as written (Fields refuses control bytes other than tab and newline on reading).
std::string Quoted(const std::string& text);

/// Which exception a walker throws: OptionError (options, configs) or FileError (data files;
/// path() is the file). The message is the same.
enum class ErrorKind { kOption, kFile };

class Fields {
 public:
  /// Parses YAML text; a syntax error names `name` and the line. An empty document is an empty
  /// map (all defaults).
  static Fields Parse(const std::string& text, const std::string& name,
                      ErrorKind errors = ErrorKind::kOption);
  /// Reads and parses a file (FileError when it cannot be read).
  static Fields Load(const std::string& path, ErrorKind errors = ErrorKind::kOption);
  /// A walker over `node` (a map, or null/absent for "no fields"); `path` is the dotted prefix
  /// of this map in the file ("" at the root), `file` names the file in messages.
  Fields(YAML::Node node, std::string path, std::string file,
         ErrorKind errors = ErrorKind::kOption);

  /// Optional `format` and `version` keys must equal the given values when present.
  void ExpectFormat(const std::string& format, int version);
  /// Required `format` and `version` keys, e.g. for `lasercell.touches` version 1:
  ///   "touches.yaml: line 1: field 'format' is required, expected 'lasercell.touches'",
  ///   "touches.yaml: line 1: field 'format' is 'foo', expected 'lasercell.touches'",
  ///   "touches.yaml: line 2: field 'version' is 2; this build reads lasercell.touches version 1"
  /// (and "field 'version' is required; this build reads ..." when it is absent). `hint`, when
  /// given, ends the two format messages (e.g. "is this a lasercell cell file?").
  void RequireFormat(const std::string& expected_format, int version, const std::string& hint = "");
  /// A required `version` key equal to `version`, with RequireFormat's messages; `what` names
  /// what is versioned ("this build reads <what> version 1"), e.g. a section of a file.
  void RequireVersion(int version, const std::string& what);
  /// True when the key is present and not null.
  bool Has(const char* key) const;
  /// The sub-map at `key` (absent -> a walker without fields); throws when it is not a map.
  Fields Sub(const char* key);
  /// The maps of the list at `key`, each a walker with path `key[i]` (absent or null -> empty);
  /// throws when it is not a list or an item is not a map.
  std::vector<Fields> List(const char* key);
  /// The keys of this map in file order (for maps keyed by name, e.g. robots); read each
  /// through Sub(key.c_str()).
  std::vector<std::string> Keys() const;

  // Each Read leaves *out unchanged when the key is absent and returns whether it was present.
  bool Read(const char* key, double* out);
  bool Read(const char* key, int* out);
  bool Read(const char* key, std::int64_t* out);
  bool Read(const char* key, std::uint32_t* out);
  bool Read(const char* key, std::uint64_t* out);
  bool Read(const char* key, bool* out);
  bool Read(const char* key, std::string* out);
  /// A list of strings.
  bool Read(const char* key, std::vector<std::string>* out);
  /// A list of numbers; exact_size > 0 requires that many.
  bool Read(const char* key, std::vector<double>* out, std::size_t exact_size = 0);
  bool Read(const char* key, std::vector<Eigen::Vector2d>* out);
  /// A list of [x, y, z] triples.
  bool Read(const char* key, std::vector<Eigen::Vector3d>* out);
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
  /// An R x C matrix (R, C > 1) as one flat list of R * C numbers, row by row (covariances).
  template <int R, int C>
  requires(R > 1 && C > 1) bool Read(const char* key, Eigen::Matrix<double, R, C>* out) {
    std::vector<double> v;
    if (!Read(key, &v, static_cast<std::size_t>(R * C))) return false;
    for (int r = 0; r < R; ++r) {
      for (int c = 0; c < C; ++c) (*out)(r, c) = v[static_cast<std::size_t>(r * C + c)];
    }
    return true;
  }
  /// A pose `{translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]}` kept exactly as written
  /// (not renormalized); |q| must be within kUnitQuaternionTolerance of 1.
  bool ReadPose(const char* key, QuaternionPose* out);
  /// The same pose as a matrix (QuaternionPose::ToIsometry: the quaternion normalized).
  bool ReadPose(const char* key, Eigen::Isometry3d* out);
  /// The pose fields `translation_mm` and `rotation_wxyz` of this map itself (both required,
  /// checked as ReadPose does), for entries that hold a pose beside other fields.
  QuaternionPose ReadPoseFields();
  /// Angles in radians: a value beyond 2 pi (+1e-6) looks like degrees and is an error.
  bool ReadRadians(const char* key, std::vector<double>* out);
  /// A positive length in mm; a value below `metres_below_mm` looks like metres (an error).
  bool ReadMillimetres(const char* key, double* out, double metres_below_mm);
  /// Like Read, but an absent key is an error ("field 'x' is required", at the map's line).
  template <typename T>
  void ReadRequired(const char* key, T* out) {
    if (!Read(key, out)) Fail(key, "is required");
  }
  /// ReadPose, required.
  template <typename T>
  void ReadRequiredPose(const char* key, T* out) {
    if (!ReadPose(key, out)) Fail(key, "is required");
  }

  /// Marks a key as known without reading it (read elsewhere, e.g. through node()).
  void Known(const char* key);
  /// Marks several keys as known: call it and Done() first to report a typo before the
  /// problems it causes (e.g. a misspelt required key).
  void Known(std::initializer_list<const char*> keys);
  /// Rejects keys that were never read or marked known, and keys given twice.
  void Done() const;
  /// Throws "<file>: line N: field '<path.key>' <problem>", N the line of the key's value (of
  /// this map when the key is absent); a problem starting with ':' or ';' follows the quote
  /// directly ("field 'edges[0].child': frame 'x' is not listed").
  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const;
  /// Throws "<file>: line N: field '<path>' <problem>" about this map itself.
  [[noreturn]] void FailHere(const std::string& problem) const;
  /// Throws "<file>: line N: <problem>" at `node` (no line when it has no mark).
  [[noreturn]] void FailAt(const YAML::Node& node, const std::string& problem) const;
  /// Dotted path of a key in this map.
  std::string Path(const std::string& key) const;
  /// The 1-based line of the key's value, of this map when absent; 0 when unknown.
  int Line(const std::string& key) const;
  /// The underlying node.
  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

 private:
  YAML::Node Child(const std::string& key) const;
  std::optional<YAML::Node> Take(const char* key);
  template <typename T>
  T Scalar(const YAML::Node& n, const std::string& path, const char* expected) const;
  std::vector<double> Numbers(const YAML::Node& n, const std::string& path,
                              std::size_t exact_size) const;
  [[noreturn]] void Throw(const YAML::Node& at, const std::string& message) const;
  /// Throws naming `what` when the scalar holds a control byte other than tab and newline.
  void CheckText(const YAML::Node& n, const std::string& what) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
  ErrorKind errors_ = ErrorKind::kOption;
  std::set<std::string> used_;
  std::vector<std::string> used_order_;  // known keys in the order the reader names them
};

/// The hint for an unknown key that is a known one in another unit: " (did you mean
/// 'radius_mm'? (lasercell uses millimetres))" for `radius_m` when `radius_mm` is known,
/// radians for `*_deg`; a generic " (a field in 'm': lasercell files are in mm and rad)" for
/// another unit suffix without a known counterpart; "" otherwise.
std::string UnitHint(const std::string& key, const std::set<std::string>& known);

}  // namespace lasercell::yaml
