#pragma once
// Number formatting for messages, summaries and reports (one copy for every module). Files that
// must round-trip use FormatDouble (frame_graph.hpp) instead.

#include <string>

namespace lasercell {

/// `value` with `digits` digits after the point ("%.*f"); "n/a" when not finite.
std::string FormatFixed(double value, int digits);

/// `value` with `significant` significant digits ("%.*g"); "n/a" when not finite.
std::string FormatSignificant(double value, int significant);

}  // namespace lasercell
