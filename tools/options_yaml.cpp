#include "tools/options_yaml.hpp"

#include <cmath>

#include "core/io/file_util.hpp"

namespace lasercell::tools {

OptionsReader::OptionsReader(const std::string& path, const std::string& format, int version)
    : path_(path) {
  const std::string text = io::ReadFileBytes(path);
  try {
    node_ = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileError(path, "not valid YAML: " + e.msg + " (line " +
                              std::to_string(e.mark.line + 1) + ")");
  }
  if (node_.IsNull()) node_ = YAML::Node(YAML::NodeType::Map);  // empty file: all defaults
  if (!node_.IsMap()) throw FileError(path, "expected a mapping of option names to values");
  if (!format.empty()) {
    std::string f = format;
    Get("format", f);
    if (f != format) Fail("format", "is '" + f + "'; expected '" + format + "'");
    int v = version;
    Get("version", v);
    if (v != version) {
      Fail("version", "is " + std::to_string(v) + "; this lasercell reads version " +
                          std::to_string(version));
    }
  }
}

OptionsReader::OptionsReader(std::string path, std::string prefix, YAML::Node node)
    : path_(std::move(path)), prefix_(std::move(prefix)), node_(std::move(node)) {}

YAML::Node OptionsReader::Take(const std::string& key) {
  known_.insert(key);
  const YAML::Node& node = node_;  // const lookup: never inserts the key
  return node[key];
}

std::optional<Eigen::Vector3d> OptionsReader::Vector3(const std::string& key) {
  const YAML::Node n = Take(key);
  if (!n) return std::nullopt;
  if (!n.IsSequence() || n.size() != 3) Fail(key, "must be a list of 3 numbers, e.g. [0, 0, 1]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      v[i] = n[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "must be a list of 3 numbers (" + Dump(n) + ")");
    }
    if (!std::isfinite(v[i])) Fail(key, "must hold finite numbers");
  }
  return v;
}

std::optional<OptionsReader> OptionsReader::Section(const std::string& key) {
  const YAML::Node n = Take(key);
  if (!n) return std::nullopt;
  if (!n.IsMap()) Fail(key, "must be a mapping of option names to values");
  return OptionsReader(path_, prefix_ + key + ".", n);
}

void OptionsReader::Missing(const std::string& key) const { Fail(key, "is required"); }

void OptionsReader::Done() const {
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    if (known_.count(key)) continue;
    std::string known;
    for (const auto& k : known_) known += (known.empty() ? "" : ", ") + k;
    throw FileError(path_, "unknown key '" + prefix_ + key + "'; known keys here: " + known);
  }
}

void OptionsReader::Fail(const std::string& key, const std::string& problem) const {
  throw FileError(path_, "'" + prefix_ + key + "' " + problem);
}

std::string OptionsReader::Dump(const YAML::Node& n) {
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

}  // namespace lasercell::tools
