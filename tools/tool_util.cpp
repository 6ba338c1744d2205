// Small helpers the subcommands share (tools/commands.hpp).
#include <cstdio>
#include <string_view>

#include "tools/commands.hpp"

namespace lasercell::tools {

ProgressCallback StderrProgress(int width) {
  return [width](std::string_view stage, double fraction) {
    std::fprintf(stderr, "\r%-*.*s %5.1f %%", width, static_cast<int>(stage.size()), stage.data(),
                 100.0 * fraction);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
  };
}

}  // namespace lasercell::tools
