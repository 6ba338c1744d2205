#pragma once
// Progress reporting hook for long work (calibration solves, sweeps, matching).
// Libraries never print: they call the hook; the CLI decides how to show it.

#include <functional>
#include <string_view>

namespace lasercell {

/// Called with a stage name and the completed fraction of that stage in [0, 1].
/// May be called from any thread, but never concurrently for one operation.
using ProgressCallback = std::function<void(std::string_view stage, double fraction)>;

/// Calls `callback` if it is set.
inline void ReportProgress(const ProgressCallback& callback, std::string_view stage,
                           double fraction) {
  if (callback) callback(stage, fraction);
}

}  // namespace lasercell
