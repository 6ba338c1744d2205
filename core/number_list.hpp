#pragma once
// Comma-separated numbers as command-line options and short text fields give them:
// "0,0,-1", "10,20,30".

#include <cstddef>
#include <string>
#include <vector>

namespace lasercell {

/// Parses "a,b,c" into finite numbers. `what` names the input in messages (e.g.
/// "--heights-mm"); `count` > 0 requires exactly that many. OptionError on anything else.
std::vector<double> ParseNumberList(const std::string& text, const std::string& what,
                                    std::size_t count = 0);

}  // namespace lasercell
