// Strict number parsing for scene text: the whole token must be a finite
// number, or the caller reports the file and line.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace yarf::importers {

std::optional<double> ParseDouble(std::string_view text);
std::optional<int64_t> ParseInteger(std::string_view text);
// Numbers separated by commas and/or white space.
std::optional<std::vector<double>> ParseDoubleList(std::string_view text);

}  // namespace yarf::importers
