// Curves as the source renderers describe them, made yarf's Curves: pbrt's
// `curve` shape and the control-point files of Mitsuba's `bsplinecurve`
// and `linearcurve`.
#pragma once

#include <string_view>
#include <vector>

#include "importers/import_error.h"
#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

// pbrt's curve of `degree` (2 or 3) through control points `p` (xyz
// triples) in pbrt's `basis` ("bezier": segments sharing their ends;
// "bspline"), as cubic Bézier segments (pbrt's own conversion), its width
// going linearly from width0 at its start to width1 at its end.
v1::Curves PbrtCurve(const std::vector<double>& p, int degree, std::string_view basis, double width0,
                     double width1, const SourceLocation& where);

// A Mitsuba curve file: a control point "x y z radius" per line, curves
// apart by empty lines, `#` starting a comment; each curve cubic B-spline
// segments (`bsplinecurve`) or straight ones (`linearcurve`, `linear`).
v1::Curves MitsubaCurves(std::string_view text, bool linear, const SourceLocation& file);

}  // namespace yarf::importers
