#include "core/number_list.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

namespace lasercell {

std::vector<double> ParseNumberList(const std::string& text, const std::string& what,
                                    std::size_t count) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      throw OptionError(what + " is '" + text + "'; '" + item +
                        "' is not a number (expected comma-separated numbers)");
    }
  }
  if (values.empty() || (count > 0 && values.size() != count)) {
    throw OptionError(what + " is '" + text + "'; expected " +
                      (count > 0 ? std::to_string(count) : std::string("one or more")) +
                      " comma-separated numbers");
  }
  return values;
}

}  // namespace lasercell
