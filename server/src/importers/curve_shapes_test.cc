// pbrt's curves and Mitsuba's curve files made yarf's Curves: the same
// curves, radii and segments, or a refusal naming the line.
#include "importers/curve_shapes.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

namespace yarf::importers {
namespace {

using Point = std::array<double, 3>;

Point Bezier(const v1::Curves& c, int segment, double u) {
  const uint32_t first = c.segments(segment);
  const double w[4] = {(1 - u) * (1 - u) * (1 - u), 3 * u * (1 - u) * (1 - u), 3 * u * u * (1 - u), u * u * u};
  Point p{};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) p[k] += w[i] * c.points(4 * (first + i) + k);
  return p;
}

double BezierRadius(const v1::Curves& c, int segment, double u) {
  const uint32_t first = c.segments(segment);
  const double w[4] = {(1 - u) * (1 - u) * (1 - u), 3 * u * (1 - u) * (1 - u), 3 * u * u * (1 - u), u * u * u};
  double r = 0;
  for (int i = 0; i < 4; ++i) r += w[i] * c.points(4 * (first + i) + 3);
  return r;
}

// The curves pbrt means, evaluated from their own bases.
Point CubicBSpline(const std::vector<double>& p, int segment, double u) {
  const double w[4] = {(1 - u) * (1 - u) * (1 - u) / 6, (3 * u * u * u - 6 * u * u + 4) / 6,
                       (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6, u * u * u / 6};
  Point q{};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) q[k] += w[i] * p[3 * (segment + i) + k];
  return q;
}
Point QuadraticBezier(const std::vector<double>& p, int segment, double u) {
  const double w[3] = {(1 - u) * (1 - u), 2 * u * (1 - u), u * u};
  Point q{};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) q[k] += w[i] * p[3 * (2 * segment + i) + k];
  return q;
}
Point QuadraticBSpline(const std::vector<double>& p, int segment, double u) {
  const double w[3] = {(1 - u) * (1 - u) / 2, (-2 * u * u + 2 * u + 1) / 2, u * u / 2};
  Point q{};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) q[k] += w[i] * p[3 * (segment + i) + k];
  return q;
}

void ExpectSame(const Point& a, const Point& b) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-5);
}

const std::vector<double> kWiggle = {0, 0, 0, 1, 2, 0, 2, -1, 1, 3, 0.5, 2, 4, 3, -1, 5, 0, 0, 6, 1, 1};  // 7 points

TEST(PbrtCurve, EveryBasisAndDegreeBecomesTheSameCurveInBezierSegments) {
  const SourceLocation where{"scene.pbrt", 3};
  struct Case {
    int degree;
    const char* basis;
    int segments;
    Point (*curve)(const std::vector<double>&, int, double);
  };
  const Case cases[] = {{3, "bspline", 4, CubicBSpline},
                        {2, "bezier", 3, QuadraticBezier},
                        {2, "bspline", 5, QuadraticBSpline}};
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.basis) + " of degree " + std::to_string(c.degree));
    const v1::Curves curves = PbrtCurve(kWiggle, c.degree, c.basis, 0.2, 0.2, where);
    EXPECT_EQ(curves.basis(), v1::Curves::BASIS_BEZIER);
    ASSERT_EQ(curves.segments_size(), c.segments);
    for (int s = 0; s < c.segments; ++s)
      for (const double u : {0.0, 0.3, 0.5, 0.9, 1.0}) ExpectSame(Bezier(curves, s, u), c.curve(kWiggle, s, u));
  }
  // Cubic Bézier segments share their ends and stay as they are.
  const std::vector<double> two(kWiggle.begin(), kWiggle.end());
  const v1::Curves cubic = PbrtCurve(two, 3, "bezier", 1, 1, where);
  ASSERT_EQ(cubic.segments_size(), 2);
  ExpectSame(Bezier(cubic, 0, 1), Bezier(cubic, 1, 0));
  ExpectSame(Bezier(cubic, 1, 1), {6, 1, 1});
}

TEST(PbrtCurve, WidthGoesLinearlyFromStartToEndAsRadius) {
  const v1::Curves curves = PbrtCurve(kWiggle, 3, "bspline", 0.2, 1.0, {"scene.pbrt", 1});
  // Four segments: the radius is half the width, 0.1 to 0.5 in steps of 0.1.
  for (int s = 0; s < 4; ++s)
    for (const double u : {0.0, 0.25, 1.0})
      EXPECT_NEAR(BezierRadius(curves, s, u), 0.5 * (0.2 + 0.8 * (s + u) / 4), 1e-6) << s << " " << u;
}

TEST(PbrtCurve, MalformedCurvesAreRefused) {
  const SourceLocation where{"scene.pbrt", 9};
  const auto error = [&](const std::vector<double>& p, int degree, const char* basis, double w0, double w1) {
    try {
      PbrtCurve(p, degree, basis, w0, w1, where);
    } catch (const ImportError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(kWiggle, 3, "bezier", 1, 1), "accepted");
  EXPECT_EQ(error(kWiggle, 4, "bezier", 1, 1), "scene.pbrt:9: curve: degree must be 2 or 3");
  EXPECT_EQ(error(kWiggle, 3, "catmullrom", 1, 1), "scene.pbrt:9: curve: basis must be \"bezier\" or \"bspline\"");
  EXPECT_EQ(error({0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4}, 3, "bezier", 1, 1),
            "scene.pbrt:9: curve: a degree-3 bezier curve needs degree × segments + 1 control points, not 5");
  EXPECT_EQ(error({0, 0, 0, 1, 1, 1}, 3, "bspline", 1, 1),
            "scene.pbrt:9: curve: a degree-3 bspline curve needs at least degree + 1 control points, not 2");
  EXPECT_EQ(error(kWiggle, 3, "bezier", -1, 1), "scene.pbrt:9: curve: widths must be finite and not negative");
  EXPECT_EQ(error(kWiggle, 3, "bezier", 1, NAN), "scene.pbrt:9: curve: widths must be finite and not negative");
  EXPECT_EQ(error({0, 0}, 3, "bezier", 1, 1), "scene.pbrt:9: curve: P needs xyz triples");
}

TEST(MitsubaCurves, EmptyLinesSeparateCurvesAndEachGivesItsSegments) {
  const std::string text =
      "# two curves\n"
      "0 0 0 0.1\n1 0 0 0.1\n2 0 0 0.1\n3 0 0 0.1\n4 0 0 0.2\n"
      "\n\n"
      "0 5 0 0.1  # the second\n1 5 0 0.1\n2 5 0 0.1\n3 5 0 0.1\n";
  const v1::Curves spline = MitsubaCurves(text, false, {"hair.txt", 0});
  EXPECT_EQ(spline.basis(), v1::Curves::BASIS_BSPLINE);
  EXPECT_EQ(spline.points_size(), 4 * 9);
  EXPECT_EQ(std::vector<uint32_t>(spline.segments().begin(), spline.segments().end()),
            (std::vector<uint32_t>{0, 1, 5}));
  EXPECT_FLOAT_EQ(spline.points(4 * 4 + 3), 0.2f);
  const v1::Curves lines = MitsubaCurves(text, true, {"hair.txt", 0});
  EXPECT_EQ(lines.basis(), v1::Curves::BASIS_LINEAR);
  EXPECT_EQ(std::vector<uint32_t>(lines.segments().begin(), lines.segments().end()),
            (std::vector<uint32_t>{0, 1, 2, 3, 5, 6, 7}));
}

TEST(MitsubaCurves, MalformedFilesFailWithTheirLine) {
  const auto error = [](const std::string& text, bool linear = false) {
    try {
      MitsubaCurves(text, linear, {"hair.txt", 0});
    } catch (const ImportError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error("0 0 0 1\n1 0 0 1\n", true), "accepted");
  EXPECT_EQ(error("0 0 0 1\n1 0 0\n"), "hair.txt:2: a control point is four numbers: x y z radius");
  EXPECT_EQ(error("0 0 0 1\n1 0 zero 1\n"), "hair.txt:2: a control point is four numbers: x y z radius");
  EXPECT_EQ(error("0 0 0 1\n1 0 nan 1\n"), "hair.txt:2: a control point is four numbers: x y z radius");
  EXPECT_EQ(error("0 0 0 -1\n"), "hair.txt:1: a control point's radius must not be negative");
  EXPECT_EQ(error("0 0 0 1\n1 0 0 1\n2 0 0 1\n\n"),
            "hair.txt:4: a curve needs at least 4 control points, this one has 3");
  EXPECT_EQ(error("1e300 0 0 1\n"), "hair.txt:1: a control point's numbers must lie within ±1e18");
  EXPECT_EQ(error("# nothing\n"), "hair.txt: the curve file holds no curve");
}

}  // namespace
}  // namespace yarf::importers
