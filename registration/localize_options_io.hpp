#pragma once
// The localize options file (YAML, format `lasercell.localize_options`, version 1): every field
// of LocalizeOptions (localize_in_cloud.hpp) and of the PPF model's PpfModelOptions
// (ppf_model.hpp, under `model:`), with the names, defaults and units of those structs. Every
// key is optional; an unknown key or a value of the wrong type is an OptionError naming the file
// and the dotted field (core/yaml_fields.hpp). The README lists the keys.
//
// Not in the file: LocalizeOptions.progress (a callback) and the per-stage `threads` and
// `viewpoint` fields, which LocalizeInCloud overrides with the top-level `threads` and viewpoint.
// `roi` present sets use_roi. Values are read, not checked: LocalizeOptions::Check and
// PpfModelOptions::Check name a field out of range.

#include <string>

#include "core/yaml_fields.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::registration {

/// What an options file sets: the localization and the model build (when the model is built
/// from a cloud or mesh rather than loaded from a .ppfm).
struct LocalizeSettings {
  LocalizeOptions localize;  ///< Defaults where the file is silent.
  PpfModelOptions model;     ///< Defaults where the file is silent.
};

/// Parses the text of an options file; `name` appears in errors. Throws OptionError naming the
/// field for unknown keys, wrong types, a wrong format/version or a rotation that is not a unit
/// quaternion.
LocalizeSettings ParseLocalizeOptions(const std::string& text, const std::string& name);

/// Reads and parses an options file (FileError when it cannot be read).
LocalizeSettings ReadLocalizeOptions(const std::string& path);

/// The options of a map already open in a larger file (a job's `localize:` section): the same
/// keys as an options file, `format`/`version` optional.
LocalizeSettings LocalizeSettingsFromFields(yaml::Fields fields);
/// The PpfModelOptions keys of the map `fields` (an options file's `model:`, a part file's
/// `model_options:`); unknown keys are rejected (fields.Done()).
void ReadPpfModelOptionFields(yaml::Fields& fields, PpfModelOptions* out);
/// The voxel normal mode named as in the options file ("average", "nearest_point", "none");
/// OptionError starting with `field` otherwise.
VoxelNormalMode ParseVoxelNormalMode(const std::string& name, const std::string& field);

/// Every PpfModelOptions key as YAML lines, each starting with `indent`; reads back through
/// ReadPpfModelOptionFields to the same options.
std::string PpfModelOptionsYaml(const PpfModelOptions& options, const std::string& indent);

}  // namespace lasercell::registration
