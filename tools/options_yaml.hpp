#pragma once
// Strict reader for the CLI's options files (YAML): every key is optional, but an unknown key
// or a value of the wrong type is an InputError naming the file and the key path
// ("opts.yaml: unknown key 'matching.refrence_stride'; known keys: ..."), so typos never
// silently fall back to defaults.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <optional>
#include <set>
#include <string>

#include "core/error.hpp"

namespace lasercell::tools {

class OptionsReader {
 public:
  /// Loads `path`; when `format` is non-empty, a `format` key must match it if present and a
  /// `version` key must equal `version` if present.
  OptionsReader(const std::string& path, const std::string& format, int version);

  /// Reads `key` into `value` when present (value unchanged otherwise).
  template <typename T>
  void Get(const std::string& key, T& value) {
    const YAML::Node n = Take(key);
    if (!n) return;
    try {
      value = n.as<T>();
    } catch (const YAML::Exception&) {
      Fail(key, "has a value of the wrong type (" + Dump(n) + ")");
    }
  }
  /// A 3-vector [x, y, z] when present.
  std::optional<Eigen::Vector3d> Vector3(const std::string& key);
  /// A nested mapping when present.
  std::optional<OptionsReader> Section(const std::string& key);
  /// Throws: `key` is required in this section.
  [[noreturn]] void Missing(const std::string& key) const;
  /// Throws when the section holds keys that were never asked for.
  void Done() const;

 private:
  OptionsReader(std::string path, std::string prefix, YAML::Node node);
  YAML::Node Take(const std::string& key);
  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const;
  static std::string Dump(const YAML::Node& n);

  std::string path_;
  std::string prefix_;  // "matching." for nested sections
  YAML::Node node_;
  std::set<std::string> known_;
};

}  // namespace lasercell::tools
