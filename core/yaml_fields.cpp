#include "core/yaml_fields.hpp"

#include <cmath>
#include <type_traits>

#include "core/io/file_util.hpp"

namespace lasercell::yaml {

Fields Fields::Parse(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw OptionError(name + ": not valid YAML: " + e.msg + " (line " +
                      std::to_string(e.mark.line + 1) + ")");
  }
  return Fields(root, "", name);
}

Fields Fields::Load(const std::string& path) { return Parse(io::ReadFileBytes(path), path); }

Fields::Fields(YAML::Node node, std::string path, std::string file)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    throw OptionError(file_ + ": " +
                      (path_.empty() ? std::string("the document") : "field '" + path_ + "'") +
                      " must be a map of fields");
  }
}

void Fields::ExpectFormat(const std::string& format, int version) {
  std::string f = format;
  int v = version;
  Read("format", &f);
  Read("version", &v);
  if (f != format) Fail("format", "is '" + f + "', expected '" + format + "'");
  if (v != version) {
    Fail("version", "is " + std::to_string(v) + "; this build reads version " +
                        std::to_string(version));
  }
}

bool Fields::Has(const char* key) const {
  const YAML::Node n = Child(key);
  return n && !n.IsNull();
}

Fields Fields::Sub(const char* key) {
  used_.insert(key);
  return Fields(Child(key), Path(key), file_);
}

bool Fields::Read(const char* key, double* out) {
  auto n = Take(key);
  if (n) *out = Scalar<double>(*n, Path(key), "a number");
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
bool Fields::Read(const char* key, std::vector<double>* out, std::size_t exact_size) {
  auto n = Take(key);
  if (n) *out = List(*n, Path(key), exact_size);
  return n.has_value();
}
bool Fields::Read(const char* key, std::vector<Eigen::Vector2d>* out) {
  auto n = Take(key);
  if (!n) return false;
  const std::string path = Path(key);
  if (!n->IsSequence()) Fail(key, "must be a list of [x, y] pairs");
  out->clear();
  for (std::size_t i = 0; i < n->size(); ++i) {
    const std::vector<double> v = List((*n)[i], path + "[" + std::to_string(i) + "]", 2);
    out->emplace_back(v[0], v[1]);
  }
  return true;
}

void Fields::Done() const {
  if (!node_ || node_.IsNull()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    if (used_.count(key) != 0) continue;
    std::string known;
    for (const std::string& k : used_) known += (known.empty() ? "" : ", ") + k;
    throw OptionError(file_ + ": unknown field '" + Path(key) + "' (known fields here: " + known +
                      ")");
  }
}

void Fields::Fail(const std::string& key, const std::string& problem) const {
  throw OptionError(file_ + ": field '" + Path(key) + "' " + problem);
}

std::string Fields::Path(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

YAML::Node Fields::Child(const char* key) const {
  if (!node_ || node_.IsNull()) return YAML::Node();
  const YAML::Node& node = node_;  // const lookup never inserts
  return node[key];
}

std::optional<YAML::Node> Fields::Take(const char* key) {
  used_.insert(key);
  YAML::Node n = Child(key);
  if (!n || n.IsNull()) return std::nullopt;
  return n;
}

template <typename T>
T Fields::Scalar(const YAML::Node& n, const std::string& path, const char* expected) const {
  if (!n.IsScalar()) {
    throw OptionError(file_ + ": field '" + path + "' must be " + expected);
  }
  try {
    T value = n.as<T>();
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) throw YAML::BadConversion(n.Mark());
    }
    return value;
  } catch (const YAML::Exception&) {
    throw OptionError(file_ + ": field '" + path + "' must be " + expected + " (got '" +
                      n.Scalar() + "')");
  }
}

std::vector<double> Fields::List(const YAML::Node& n, const std::string& path,
                                 std::size_t exact_size) const {
  if (!n.IsSequence()) throw OptionError(file_ + ": field '" + path + "' must be a list of numbers");
  if (exact_size > 0 && n.size() != exact_size) {
    throw OptionError(file_ + ": field '" + path + "' must list exactly " +
                      std::to_string(exact_size) + " numbers (got " + std::to_string(n.size()) +
                      ")");
  }
  std::vector<double> v;
  for (std::size_t i = 0; i < n.size(); ++i) {
    v.push_back(Scalar<double>(n[i], path + "[" + std::to_string(i) + "]", "a number"));
  }
  return v;
}

}  // namespace lasercell::yaml
