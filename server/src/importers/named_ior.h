// Indices of refraction that scene files name instead of giving a number.
#pragma once

#include <optional>
#include <string>

namespace yarf::importers {

// Mitsuba's named media ("bk7", "air", "water", "diamond"...): nullopt when
// the name is unknown.
std::optional<double> MitsubaNamedIor(const std::string& name);

// pbrt-v4's named glass spectra ("glass-BK7"...) reduced to their index at
// the sodium d line (587.6 nm), where catalogues quote nd.
std::optional<double> PbrtNamedGlassIor(const std::string& name);

}  // namespace yarf::importers
