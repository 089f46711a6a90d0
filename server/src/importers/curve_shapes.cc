#include "importers/curve_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "importers/numbers.h"

namespace yarf::importers {
namespace {

using Point = std::array<double, 3>;

Point Mix(const Point& a, double wa, const Point& b, double wb, const Point& c = {}, double wc = 0) {
  return {wa * a[0] + wb * b[0] + wc * c[0], wa * a[1] + wb * b[1] + wc * c[1], wa * a[2] + wb * b[2] + wc * c[2]};
}

// Appends one cubic Bézier segment whose radius goes linearly from r0 to
// r1: a Bézier reproduces a linear function from values at 0, ⅓, ⅔, 1.
void AddBezier(const std::array<Point, 4>& b, double r0, double r1, v1::Curves& out) {
  out.add_segments(uint32_t(out.points_size() / 4));
  for (int i = 0; i < 4; ++i) {
    for (const double c : b[i]) out.add_points(float(c));
    out.add_points(float(std::max(0.0, r0 + (r1 - r0) * i / 3)));
  }
}

// A quadratic Bézier segment raised to the cubic tracing the same curve.
std::array<Point, 4> Elevated(const Point& a, const Point& b, const Point& c) {
  return {a, Mix(a, 1.0 / 3, b, 2.0 / 3), Mix(c, 1.0 / 3, b, 2.0 / 3), c};
}

}  // namespace

v1::Curves PbrtCurve(const std::vector<double>& p, int degree, std::string_view basis, double width0,
                     double width1, const SourceLocation& where) {
  if (degree != 2 && degree != 3) Fail(where, "curve: degree must be 2 or 3");
  if (basis != "bezier" && basis != "bspline") Fail(where, "curve: basis must be \"bezier\" or \"bspline\"");
  if (!(width0 >= 0 && width1 >= 0 && width0 < 1e30 && width1 < 1e30))
    Fail(where, "curve: widths must be finite and not negative");
  if (p.size() % 3 != 0) Fail(where, "curve: P needs xyz triples");
  for (const double v : p)
    if (!(std::abs(v) < 1e18)) Fail(where, "curve: P's coordinates must lie within ±1e18");
  std::vector<Point> points(p.size() / 3);
  for (size_t i = 0; i < points.size(); ++i) points[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
  const size_t n = points.size(), d = size_t(degree);
  const bool bezier = basis == "bezier";
  if (bezier ? n < d + 1 || (n - 1) % d != 0 : n < d + 1)
    Fail(where, "curve: a degree-" + std::to_string(degree) + " " + std::string(basis) +
                    " curve needs " + (bezier ? "degree × segments + 1" : "at least degree + 1") +
                    " control points, not " + std::to_string(n));
  const size_t segments = bezier ? (n - 1) / d : n - d;
  v1::Curves out;
  out.set_basis(v1::Curves::BASIS_BEZIER);
  for (size_t s = 0; s < segments; ++s) {
    const double r0 = 0.5 * (width0 + (width1 - width0) * double(s) / double(segments));
    const double r1 = 0.5 * (width0 + (width1 - width0) * double(s + 1) / double(segments));
    const Point* q = bezier ? &points[d * s] : &points[s];
    std::array<Point, 4> b;
    if (bezier && d == 3) {
      b = {q[0], q[1], q[2], q[3]};
    } else if (bezier) {
      b = Elevated(q[0], q[1], q[2]);
    } else if (d == 3) {
      // A uniform cubic B-spline segment's Bézier control points.
      b = {Mix(q[0], 1.0 / 6, q[1], 4.0 / 6, q[2], 1.0 / 6), Mix(q[1], 2.0 / 3, q[2], 1.0 / 3),
           Mix(q[1], 1.0 / 3, q[2], 2.0 / 3), Mix(q[1], 1.0 / 6, q[2], 4.0 / 6, q[3], 1.0 / 6)};
    } else {
      b = Elevated(Mix(q[0], 0.5, q[1], 0.5), q[1], Mix(q[1], 0.5, q[2], 0.5));
    }
    AddBezier(b, r0, r1, out);
  }
  return out;
}

v1::Curves MitsubaCurves(std::string_view text, bool linear, const SourceLocation& file) {
  v1::Curves out;
  out.set_basis(linear ? v1::Curves::BASIS_LINEAR : v1::Curves::BASIS_BSPLINE);
  const uint32_t span = linear ? 2 : 4;
  uint32_t first = 0;  // the current curve's first control point
  const auto close = [&](int line) {
    const uint32_t count = uint32_t(out.points_size() / 4) - first;
    if (count > 0 && count < span)
      Fail({file.file, line}, "a curve needs at least " + std::to_string(span) + " control points, this one has " +
                                  std::to_string(count));
    for (uint32_t k = 0; k + span <= count; ++k) out.add_segments(first + k);
    first += count;
  };
  int line = 0;
  for (size_t start = 0; start <= text.size();) {
    const size_t end = std::min(text.find('\n', start), text.size());
    std::string_view row = text.substr(start, end - start);
    start = end + 1;
    ++line;
    row = row.substr(0, row.find('#'));
    const auto numbers = ParseDoubleList(row);
    if (!numbers) Fail({file.file, line}, "a control point is four numbers: x y z radius");
    if (numbers->empty()) {
      close(line);
      continue;
    }
    if (numbers->size() != 4) Fail({file.file, line}, "a control point is four numbers: x y z radius");
    if (!((*numbers)[3] >= 0)) Fail({file.file, line}, "a control point's radius must not be negative");
    for (const double v : *numbers) {
      if (!(std::abs(v) < 1e18)) Fail({file.file, line}, "a control point's numbers must lie within ±1e18");
      out.add_points(float(v));
    }
  }
  close(line);
  if (out.segments_size() == 0) Fail(file, "the curve file holds no curve");
  return out;
}

}  // namespace yarf::importers
