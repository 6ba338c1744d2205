#include "core/yaml_fields.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <type_traits>

#include "core/io/file_util.hpp"

namespace lasercell::yaml {
namespace {

// Shortest text that reads back as the same double.
std::string Shortest(double v) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  std::string text(buffer, result.ptr);
  if (const auto at = text.find("e-0"); at != std::string::npos) text.erase(at + 2, 1);
  return text;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

int LineOf(const YAML::Node& n) {
  if (!n.IsDefined() || n.Mark().is_null()) return 0;
  return n.Mark().line + 1;
}

std::string HintTail(const std::string& hint) { return hint.empty() ? "" : " (" + hint + ")"; }

std::string FormatMismatch(const std::string& found, const std::string& expected,
                           const std::string& hint) {
  return "is '" + found + "', expected '" + expected + "'" + HintTail(hint);
}

std::string ReadsVersion(const std::string& what, int version) {
  return "this build reads " + what + " version " + std::to_string(version);
}

}  // namespace

std::string Quoted(const std::string& text) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out = "\"";
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c < 0x20 || c == 0x7f) {
      out += std::string("\\x") + kHex[c >> 4] + kHex[c & 15];
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string UnitHint(const std::string& key, const std::set<std::string>& known) {
  struct Unit {
    const char* suffix;
    const char* expected;  // the suffix lasercell uses instead, or nullptr
    const char* word;
  };
  static constexpr Unit kUnits[] = {{"_m", "_mm", "millimetres"},    {"_cm", "_mm", "millimetres"},
                                    {"_um", "_mm", "millimetres"},   {"_in", "_mm", "millimetres"},
                                    {"_inch", "_mm", "millimetres"}, {"_deg", "_rad", "radians"},
                                    {"_degrees", "_rad", "radians"}};
  for (const Unit& u : kUnits) {
    if (!EndsWith(key, u.suffix)) continue;
    const std::string stem = key.substr(0, key.size() - std::string(u.suffix).size());
    const std::string candidate = stem + u.expected;
    if (known.count(candidate) != 0) {
      return "; did you mean '" + candidate + "'? (lasercell uses " + u.word + ")";
    }
    return std::string(" (a field in '") + (u.suffix + 1) + "': lasercell files are in mm and rad)";
  }
  return "";
}

Fields Fields::Parse(const std::string& text, const std::string& name, ErrorKind errors) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    const std::string message =
        "not valid YAML: " + e.msg + " (line " + std::to_string(e.mark.line + 1) + ")";
    if (errors == ErrorKind::kFile) throw FileError(name, message);
    throw OptionError(name + ": " + message);
  }
  return Fields(root, "", name, errors);
}

Fields Fields::Load(const std::string& path, ErrorKind errors) {
  return Parse(io::ReadFileBytes(path), path, errors);
}

Fields::Fields(YAML::Node node, std::string path, std::string file, ErrorKind errors)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)), errors_(errors) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    Throw(node_, (path_.empty() ? std::string("the document") : "field '" + path_ + "'") +
                     " must be a map of fields");
  }
}

void Fields::ExpectFormat(const std::string& format, int version) {
  // Both keys optional; a present one is checked as RequireFormat checks it.
  std::string f = format;
  Read("format", &f);
  if (f != format) Fail("format", FormatMismatch(f, format, ""));
  if (Has("version")) RequireVersion(version, format);
}

void Fields::RequireFormat(const std::string& expected_format, int version,
                           const std::string& hint) {
  std::string format;
  if (!Read("format", &format)) {
    Fail("format", "is required, expected '" + expected_format + "'" + HintTail(hint));
  }
  if (format != expected_format) Fail("format", FormatMismatch(format, expected_format, hint));
  RequireVersion(version, expected_format);
}

void Fields::RequireVersion(int version, const std::string& what) {
  int v = 0;
  if (!Read("version", &v)) Fail("version", "is required; " + ReadsVersion(what, version));
  if (v != version) Fail("version", "is " + std::to_string(v) + "; " + ReadsVersion(what, version));
}

bool Fields::Has(const char* key) const {
  const YAML::Node n = Child(key);
  return n && !n.IsNull();
}

Fields Fields::Sub(const char* key) {
  Known(key);
  return Fields(Child(key), Path(key), file_, errors_);
}

std::vector<Fields> Fields::List(const char* key) {
  std::vector<Fields> items;
  auto n = Take(key);
  if (!n) return items;
  if (!n->IsSequence()) Fail(key, "must be a list of maps");
  const std::string path = Path(key);
  for (std::size_t i = 0; i < n->size(); ++i) {
    const YAML::Node item = (*n)[i];
    const std::string item_path = path + "[" + std::to_string(i) + "]";
    if (!item.IsMap()) Throw(item, "field '" + item_path + "' must be a map of fields");
    items.emplace_back(item, item_path, file_, errors_);
  }
  return items;
}

std::vector<std::string> Fields::Keys() const {
  std::vector<std::string> keys;
  if (!node_ || node_.IsNull()) return keys;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) Throw(entry.first, "keys must be names");
    CheckText(entry.first, "a key");
    keys.push_back(entry.first.Scalar());
  }
  return keys;
}

bool Fields::Read(const char* key, double* out) {
  auto n = Take(key);
  if (n) *out = Scalar<double>(*n, Path(key), "a finite number");
  return n.has_value();
}
bool Fields::Read(const char* key, int* out) {
  auto n = Take(key);
  if (n) *out = Scalar<int>(*n, Path(key), "an integer");
  return n.has_value();
}
bool Fields::Read(const char* key, std::int64_t* out) {
  auto n = Take(key);
  if (n) *out = Scalar<std::int64_t>(*n, Path(key), "an integer");
  return n.has_value();
}
bool Fields::Read(const char* key, std::uint32_t* out) {
  auto n = Take(key);
  if (n) *out = Scalar<std::uint32_t>(*n, Path(key), "a non-negative integer");
  return n.has_value();
}
bool Fields::Read(const char* key, std::uint64_t* out) {
  auto n = Take(key);
  if (n) *out = Scalar<std::uint64_t>(*n, Path(key), "a non-negative integer");
  return n.has_value();
}
bool Fields::Read(const char* key, bool* out) {
  auto n = Take(key);
  if (n) *out = Scalar<bool>(*n, Path(key), "true or false");
  return n.has_value();
}
bool Fields::Read(const char* key, std::string* out) {
  auto n = Take(key);
  if (n) *out = Scalar<std::string>(*n, Path(key), "a string");
  return n.has_value();
}
bool Fields::Read(const char* key, std::vector<std::string>* out) {
  auto n = Take(key);
  if (!n) return false;
  if (!n->IsSequence()) Fail(key, "must be a list of names");
  const std::string path = Path(key);
  out->clear();
  for (std::size_t i = 0; i < n->size(); ++i) {
    out->push_back(Scalar<std::string>((*n)[i], path + "[" + std::to_string(i) + "]", "a name"));
  }
  return true;
}
bool Fields::Read(const char* key, std::vector<double>* out, std::size_t exact_size) {
  auto n = Take(key);
  if (n) *out = Numbers(*n, Path(key), exact_size);
  return n.has_value();
}
bool Fields::Read(const char* key, std::vector<Eigen::Vector2d>* out) {
  auto n = Take(key);
  if (!n) return false;
  const std::string path = Path(key);
  if (!n->IsSequence()) Fail(key, "must be a list of [x, y] pairs");
  out->clear();
  for (std::size_t i = 0; i < n->size(); ++i) {
    const std::vector<double> v = Numbers((*n)[i], path + "[" + std::to_string(i) + "]", 2);
    out->emplace_back(v[0], v[1]);
  }
  return true;
}
bool Fields::Read(const char* key, std::vector<Eigen::Vector3d>* out) {
  auto n = Take(key);
  if (!n) return false;
  const std::string path = Path(key);
  if (!n->IsSequence()) Fail(key, "must be a list of [x, y, z] triples");
  out->clear();
  for (std::size_t i = 0; i < n->size(); ++i) {
    const std::vector<double> v = Numbers((*n)[i], path + "[" + std::to_string(i) + "]", 3);
    out->emplace_back(v[0], v[1], v[2]);
  }
  return true;
}

bool Fields::ReadPose(const char* key, QuaternionPose* out) {
  if (!Has(key)) {
    Known(key);
    return false;
  }
  Fields pose = Sub(key);
  pose.Known({"translation_mm", "rotation_wxyz"});
  pose.Done();
  *out = pose.ReadPoseFields();
  return true;
}

QuaternionPose Fields::ReadPoseFields() {
  Eigen::Vector3d t;
  Eigen::Vector4d q;
  ReadRequired("translation_mm", &t);
  ReadRequired("rotation_wxyz", &q);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
    Fail("rotation_wxyz", "has norm " + Shortest(norm) +
                              "; expected a unit quaternion (norm within " +
                              Shortest(kUnitQuaternionTolerance) + " of 1), w first");
  }
  return QuaternionPose{Eigen::Quaterniond(q[0], q[1], q[2], q[3]), t};
}

bool Fields::ReadPose(const char* key, Eigen::Isometry3d* out) {
  QuaternionPose pose;
  if (!ReadPose(key, &pose)) return false;
  *out = pose.ToIsometry();
  return true;
}

bool Fields::ReadRadians(const char* key, std::vector<double>* out) {
  std::vector<double> v;
  if (!Read(key, &v)) return false;
  for (double x : v) {
    if (std::abs(x) > 2 * std::numbers::pi + 1e-6) {
      Fail(key,
           "holds " + std::to_string(x) + ", beyond +-2 pi: it looks like degrees; give radians");
    }
  }
  *out = std::move(v);
  return true;
}

bool Fields::ReadMillimetres(const char* key, double* out, double metres_below_mm) {
  double v = 0;
  if (!Read(key, &v)) return false;
  if (!(v > 0)) Fail(key, "must be positive");
  if (v < metres_below_mm) {
    Fail(key, "is " + Child(key).Scalar() + ", which looks like metres; give millimetres");
  }
  *out = v;
  return true;
}

void Fields::Known(const char* key) {
  if (used_.insert(key).second) used_order_.emplace_back(key);
}

void Fields::Known(std::initializer_list<const char*> keys) {
  for (const char* k : keys) Known(k);
}

void Fields::Done() const {
  if (!node_ || node_.IsNull()) return;
  std::set<std::string> seen;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) Throw(entry.first, "keys must be names");
    const std::string key = entry.first.Scalar();
    if (used_.count(key) == 0) {
      const std::string hint = UnitHint(key, used_);
      std::string known;
      for (const std::string& k : used_order_) known += (known.empty() ? "" : ", ") + k;
      Throw(entry.first,
            "unknown field '" + Path(key) + "'" + hint +
                (hint.rfind("; did you mean", 0) == 0 ? std::string()
                                                      : " (known fields here: " + known + ")"));
    }
    if (!seen.insert(key).second) {
      Throw(entry.first, "field '" + Path(key) + "' appears twice; keep one");
    }
  }
}

namespace {
// "field 'x' is ...", but "field 'x': ..." when the problem starts with ':' or ';'.
std::string FieldProblem(const std::string& path, const std::string& problem) {
  const bool punct = !problem.empty() && (problem[0] == ':' || problem[0] == ';');
  return "field '" + path + "'" + (punct ? "" : " ") + problem;
}
}  // namespace

void Fields::Fail(const std::string& key, const std::string& problem) const {
  const YAML::Node n = Child(key);
  Throw(n.IsDefined() ? n : node_, FieldProblem(Path(key), problem));
}

void Fields::FailHere(const std::string& problem) const {
  Throw(node_, FieldProblem(path_.empty() ? std::string("(top level)") : path_, problem));
}

void Fields::FailAt(const YAML::Node& node, const std::string& problem) const {
  Throw(node, problem);
}

void Fields::Throw(const YAML::Node& at, const std::string& message) const {
  const int line = LineOf(at);
  const std::string text = (line > 0 ? "line " + std::to_string(line) + ": " : "") + message;
  if (errors_ == ErrorKind::kFile) throw FileError(file_, text);
  throw OptionError(file_ + ": " + text);
}

std::string Fields::Path(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

int Fields::Line(const std::string& key) const {
  const YAML::Node n = Child(key);
  return LineOf(n.IsDefined() ? n : node_);
}

YAML::Node Fields::Child(const std::string& key) const {
  if (!node_ || node_.IsNull()) return YAML::Node();
  const YAML::Node& node = node_;  // const lookup never inserts
  return node[key];
}

std::optional<YAML::Node> Fields::Take(const char* key) {
  Known(key);
  YAML::Node n = Child(key);
  if (!n || n.IsNull()) return std::nullopt;
  return n;
}

template <typename T>
T Fields::Scalar(const YAML::Node& n, const std::string& path, const char* expected) const {
  if (!n.IsScalar()) Throw(n, "field '" + path + "' must be " + expected);
  const auto bad = [&]() {
    Throw(n, "field '" + path + "' must be " + expected + " (got '" + n.Scalar() + "')");
  };
  if constexpr (std::is_floating_point_v<T>) {
    // Exact (shortest round-trip) and strict: no unit suffix, no overflow, finite.
    std::string_view text = n.Scalar();
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    T value = 0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || result.ec != std::errc() || result.ptr != text.data() + text.size() ||
        !std::isfinite(value)) {
      bad();
    }
    return value;
  } else {
    if constexpr (std::is_same_v<T, std::string>) CheckText(n, "field '" + path + "'");
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      bad();
    }
    return T{};
  }
}

// Text fields (names, paths, descriptions) hold no control bytes but tab and newline: a NUL or
// an escape byte in a path or a name is damage, and would not survive being written again.
void Fields::CheckText(const YAML::Node& n, const std::string& what) const {
  for (const char c : n.Scalar()) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && c != '\t' && c != '\n') || byte == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", byte);
      Throw(n, what + " contains the control byte " + hex + "; the file is text: remove it");
    }
  }
}

std::vector<double> Fields::Numbers(const YAML::Node& n, const std::string& path,
                                    std::size_t exact_size) const {
  if (!n.IsSequence()) Throw(n, "field '" + path + "' must be a list of numbers");
  if (exact_size > 0 && n.size() != exact_size) {
    Throw(n, "field '" + path + "' must list exactly " + std::to_string(exact_size) +
                 " numbers (got " + std::to_string(n.size()) + ")");
  }
  std::vector<double> v;
  for (std::size_t i = 0; i < n.size(); ++i) {
    v.push_back(Scalar<double>(n[i], path + "[" + std::to_string(i) + "]", "a finite number"));
  }
  return v;
}

}  // namespace lasercell::yaml
