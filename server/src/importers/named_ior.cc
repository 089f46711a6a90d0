#include "importers/named_ior.h"

#include <array>
#include <utility>

namespace yarf::importers {
namespace {

using Entry = std::pair<const char*, double>;

constexpr std::array kMitsuba = {
    Entry{"vacuum", 1.0},          Entry{"helium", 1.000036},       Entry{"hydrogen", 1.000132},
    Entry{"air", 1.000277},        Entry{"carbon dioxide", 1.00045}, Entry{"water", 1.3330},
    Entry{"acetone", 1.36},        Entry{"ethanol", 1.361},         Entry{"carbon tetrachloride", 1.461},
    Entry{"glycerol", 1.4729},     Entry{"benzene", 1.501},         Entry{"silicone oil", 1.52045},
    Entry{"bromine", 1.661},       Entry{"water ice", 1.31},        Entry{"fused quartz", 1.458},
    Entry{"pyrex", 1.470},         Entry{"acrylic glass", 1.49},    Entry{"polypropylene", 1.49},
    Entry{"bk7", 1.5046},          Entry{"sodium chloride", 1.544}, Entry{"amber", 1.55},
    Entry{"pet", 1.5750},          Entry{"diamond", 2.419},
};

// Schott catalogue nd values of the glasses pbrt-v4 tabulates (its "F5",
// "F10" and "F11" are the dense flints SF5, SF10 and SF11).
constexpr std::array kPbrtGlass = {
    Entry{"glass-BK7", 1.5168},  Entry{"glass-BAF10", 1.6700}, Entry{"glass-FK51A", 1.4866},
    Entry{"glass-LASF9", 1.8503}, Entry{"glass-F5", 1.6727},   Entry{"glass-F10", 1.7283},
    Entry{"glass-F11", 1.7847},
};

template <size_t N>
std::optional<double> Find(const std::array<Entry, N>& table, const std::string& name) {
  for (const auto& [key, value] : table)
    if (name == key) return value;
  return std::nullopt;
}

}  // namespace

std::optional<double> MitsubaNamedIor(const std::string& name) { return Find(kMitsuba, name); }
std::optional<double> PbrtNamedGlassIor(const std::string& name) { return Find(kPbrtGlass, name); }

}  // namespace yarf::importers
