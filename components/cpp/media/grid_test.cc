// Tests of the grid medium, loaded through the registry as yarfd loads
// it: grid files and inline grids read back (voxel centres, trilinear
// midpoints, both edge rules), coefficients of a constant grid, majorants
// that bound the extinction and cover exactly the part of a ray in the
// box (tight for a constant grid: exact transmittance), the albedo grid,
// OpenVDB files where the build reads them, and an Error for every bad
// input. Then pbrt-v4's procedural cloud: its density within [0, 1] and
// full below y = 0, and its one majorant over its box.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "../textures/temporary_folder.h"
#include "components/properties_proto.h"
#include "components/registry.h"
#include "yarf/geometry.h"
#include "yarf/support/hash.h"
#include "yarf/medium.h"

#ifdef YARF_HAVE_OPENVDB
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#endif

namespace yarf {
namespace {

float Uniform(uint64_t i, uint64_t j) { return ToUnitFloat(uint32_t(Hash(i, j))); }

// The .vol file of a grid; `box` is its bounding box (min then max).
std::string VolBytes(int nx, int ny, int nz, int channels, const std::vector<float>& values,
                     std::array<float, 6> box = {0, 0, 0, 1, 1, 1}) {
  std::string bytes = "VOL";
  bytes += char(3);
  const auto put = [&](const void* p, size_t n) { bytes.append(static_cast<const char*>(p), n); };
  const int32_t header[5] = {1, nx, ny, nz, channels};
  put(header, sizeof header);
  put(box.data(), sizeof(float) * 6);
  put(values.data(), sizeof(float) * values.size());
  return bytes;
}

Transform Affine(Vec3 scale, Vec3 translation) {
  Transform t;
  for (int a = 0; a < 3; ++a) {
    t.m[5 * a] = scale[a];
    t.m[4 * a + 3] = translation[a];
  }
  return t;
}

// A rotation about (1, 1, 1) after a non-uniform scale, then a shift.
Transform Skewed() {
  const double c = std::cos(0.6), s = std::sin(0.6), k = (1 - c) / 3, r = s / std::sqrt(3.0);
  const double rotation[9] = {c + k, k - r, k + r, k + r, c + k, k - r, k - r, k + r, c + k};
  const double scale[3] = {2.0, 0.5, 1.5}, shift[3] = {-1.0, 0.3, 2.0};
  Transform t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.m[4 * i + j] = rotation[3 * i + j] * scale[j];
    t.m[4 * i + 3] = shift[i];
  }
  return t;
}

class GridMediumTest : public testing::Test {
 protected:
  GridMediumTest() : folder_("yarf-grid-test") { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Medium> Make(const Properties& props) const { return registry_.CreateAs<Medium>("grid", props); }
  std::string CreationError(const Properties& props) const {
    try {
      registry_.Create("grid", props);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path Write(const std::string& name, const std::string& bytes) const {
    const std::filesystem::path path = folder_.path() / name;
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
  }

  // σ_a, σ_s, emission at world points.
  struct Sample {
    std::vector<float> sigma_a, sigma_s, emission;
    Vec3 A(size_t k) const { return Vec3::Load(&sigma_a[3 * k]); }
    Vec3 S(size_t k) const { return Vec3::Load(&sigma_s[3 * k]); }
    Vec3 E(size_t k) const { return Vec3::Load(&emission[3 * k]); }
  };
  static Sample At(const Medium& medium, const std::vector<Vec3>& points) {
    std::vector<float> position;
    for (const Vec3& p : points) position.insert(position.end(), {p.x, p.y, p.z});
    Sample s{std::vector<float>(position.size()), std::vector<float>(position.size()),
             std::vector<float>(position.size())};
    medium.Coefficients(position, s.sigma_a, s.sigma_s, s.emission);
    return s;
  }

  Registry registry_;
  textures::TemporaryFolder folder_;
};

TEST_F(GridMediumTest, VolFileReadsBackAtVoxelCentresAndBetweenThem) {
  const int nx = 3, ny = 2, nz = 4;
  std::vector<float> d(nx * ny * nz);
  for (size_t i = 0; i < d.size(); ++i) d[i] = 0.1f + Uniform(i, 1);
  Properties props;
  props.Set("filename", Write("d.vol", VolBytes(nx, ny, nz, 1, d)));
  const Transform to_world = Affine(Vec3(2, 3, 4), Vec3(1, -1, 0.5f));
  props.Set("to_world", to_world);
  const auto medium = Make(props);
  EXPECT_EQ(medium->Describe().interfaces, std::vector<std::string>{Medium::kInterface});
  std::vector<Vec3> centres, midpoints;
  std::vector<float> expected_mid;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        centres.push_back(to_world.Point(Vec3((x + 0.5f) / nx, (y + 0.5f) / ny, (z + 0.5f) / nz)));
        if (x + 1 < nx) {
          midpoints.push_back(to_world.Point(Vec3((x + 1.0f) / nx, (y + 0.5f) / ny, (z + 0.5f) / nz)));
          expected_mid.push_back(0.5f * (d[(z * ny + y) * nx + x] + d[(z * ny + y) * nx + x + 1]));
        }
      }
  const Sample c = At(*medium, centres), m = At(*medium, midpoints);
  for (size_t i = 0; i < centres.size(); ++i) {
    EXPECT_NEAR(c.S(i).x, d[i], 1e-5f) << i;
    EXPECT_NEAR(c.S(i).z, d[i], 1e-5f) << i;
    EXPECT_EQ(c.A(i).y, 0);  // sigma_a defaults to 0, sigma_s to 1
    EXPECT_EQ(c.E(i).x, 0);
  }
  for (size_t i = 0; i < midpoints.size(); ++i) EXPECT_NEAR(m.S(i).y, expected_mid[i], 1e-5f) << i;
  EXPECT_FALSE(medium->Emits());
}

TEST_F(GridMediumTest, RgbVolFileMultipliesPerChannelAndItsBoxPlacesItWhenAsked) {
  // One voxel per axis: the value everywhere in the box (edge "clamp").
  const std::vector<float> rgb{0.5f, 1.0f, 2.0f};
  Properties props;
  props.Set("filename", Write("rgb.vol", VolBytes(1, 1, 1, 3, rgb, {1, 0, 0, 2, 1, 3})));
  props.Set("sigma_a", Rgb{Vec3(0.1f, 0.2f, 0.3f)});
  props.Set("sigma_s", 0.5);
  props.Set("use_grid_bbox", true);
  const auto medium = Make(props);
  const Sample s = At(*medium, {Vec3(1.5f, 0.5f, 2.9f), Vec3(0.5f, 0.5f, 0.5f), Vec3(1.01f, 0.99f, 0.01f)});
  for (size_t k : {size_t(0), size_t(2)}) {
    EXPECT_NEAR(s.A(k).x, 0.05f, 1e-6f);
    EXPECT_NEAR(s.A(k).z, 0.6f, 1e-6f);
    EXPECT_NEAR(s.S(k).y, 0.5f, 1e-6f);
  }
  EXPECT_EQ(s.S(1).x, 0);  // outside the file's box
}

TEST_F(GridMediumTest, ConstantGridIsScaleTimesDensityTimesSigmaInsideAndNothingOutside) {
  Properties props;
  props.Set("density", std::vector<float>(2 * 3 * 2, 0.7f));
  props.Set("nx", int64_t(2));
  props.Set("ny", int64_t(3));
  props.Set("nz", int64_t(2));
  props.Set("sigma_a", Rgb{Vec3(0.1f, 0.2f, 0.3f)});
  props.Set("sigma_s", Rgb{Vec3(1, 0.5f, 0.25f)});
  props.Set("scale", 2.0);
  props.Set("emission", Rgb{Vec3(3, 2, 1)});
  const Transform to_world = Skewed();
  props.Set("to_world", to_world);
  const auto medium = Make(props);
  EXPECT_TRUE(medium->Emits());
  std::vector<Vec3> inside, outside;
  for (int i = 0; i < 200; ++i) {
    const Vec3 u(Uniform(i, 2), Uniform(i, 3), Uniform(i, 4));
    inside.push_back(to_world.Point(u * 0.998f + Vec3(0.001f, 0.001f, 0.001f)));
    Vec3 v = u * 3 - Vec3(1, 1, 1);  // in [-1, 2)³, pushed out of the cube along one axis
    const int axis = i % 3;
    const float out = v[axis] < 0.5f ? std::min(v[axis], -0.01f) : std::max(v[axis], 1.01f);
    v = Vec3(axis == 0 ? out : v.x, axis == 1 ? out : v.y, axis == 2 ? out : v.z);
    outside.push_back(to_world.Point(v));
  }
  const Sample in = At(*medium, inside), out = At(*medium, outside);
  for (size_t k = 0; k < inside.size(); ++k) {
    EXPECT_NEAR(in.A(k).x, 1.4f * 0.1f, 1e-5f);
    EXPECT_NEAR(in.A(k).z, 1.4f * 0.3f, 1e-5f);
    EXPECT_NEAR(in.S(k).y, 1.4f * 0.5f, 1e-5f);
    EXPECT_NEAR(in.E(k).x, 3.0f, 1e-6f);
    EXPECT_EQ(out.A(k).x + out.S(k).y + out.E(k).z, 0) << k;
  }
}

TEST_F(GridMediumTest, InlineGridsInterpolateAndFollowTheEdgeRule) {
  // Two voxels along x, centred at 0.25 and 0.75; rgb values.
  const std::vector<float> values{1, 2, 3, 3, 6, 9};
  for (const std::string edge : {"clamp", "zero"}) {
    Properties props;
    props.Set("sigma_s", values);
    props.Set("nx", int64_t(2));
    props.Set("ny", int64_t(1));
    props.Set("nz", int64_t(1));
    props.Set("edge", edge);
    const auto medium = Make(props);
    const Sample s = At(*medium, {Vec3(0.25f, 0.5f, 0.5f), Vec3(0.5f, 0.5f, 0.5f), Vec3(0.125f, 0.5f, 0.5f),
                                  Vec3(0.875f, 0.5f, 0.5f)});
    EXPECT_NEAR(s.S(0).y, 2, 1e-6f);
    EXPECT_NEAR(s.S(1).x, 2, 1e-6f);
    EXPECT_NEAR(s.S(1).z, 6, 1e-6f);
    // A quarter voxel past the outer centre: the border voxel, or 3/4 of
    // it (pbrt-v4 interpolates toward a zero voxel beyond).
    const float keep = edge == "clamp" ? 1.0f : 0.75f;
    EXPECT_NEAR(s.S(2).z, keep * 3, 1e-6f) << edge;
    EXPECT_NEAR(s.S(3).x, keep * 3, 1e-6f) << edge;
    EXPECT_EQ(s.A(0).x, 0);
  }
}

TEST_F(GridMediumTest, AlbedoGridSplitsTheExtinction) {
  Properties props;
  props.Set("density", 2.0);
  props.Set("sigma_a", 0.25);
  props.Set("sigma_s", 0.75);  // σ_t = 2
  props.Set("albedo_filename", Write("albedo.vol", VolBytes(2, 1, 1, 3, {0.1f, 0.5f, 0.9f, 0.3f, 0.5f, 1.7f})));
  const auto medium = Make(props);
  const Sample s = At(*medium, {Vec3(0.25f, 0.5f, 0.5f), Vec3(0.5f, 0.5f, 0.5f)});
  EXPECT_NEAR(s.S(0).x, 0.2f, 1e-6f);
  EXPECT_NEAR(s.A(0).x, 1.8f, 1e-6f);
  EXPECT_NEAR(s.S(0).z, 1.8f, 1e-6f);
  EXPECT_NEAR(s.S(1).x, 0.4f, 1e-6f);
  EXPECT_NEAR(s.S(1).z, 1.9f, 1e-6f);  // the albedo voxel 1.7 counts as 1
  EXPECT_NEAR(s.A(1).z + s.S(1).z, 2.0f, 1e-6f);
}

// Segments of every ray: ordered, within [0, tmax), covering exactly the
// part of the ray in the box, and σ_t ≤ σ_maj at points along each.
void CheckMajorants(const Medium& medium, const Transform& to_world, bool axis_aligned, int rays, uint64_t seed,
                    int* segments_seen) {
  std::vector<float> origin, direction, tmax;
  for (int i = 0; i < rays; ++i) {
    const Vec3 o = to_world.Point(Vec3(Uniform(seed + i, 5), Uniform(seed + i, 6), Uniform(seed + i, 7)) * 3 -
                                  Vec3(1, 1, 1));
    const float z = 1 - 2 * Uniform(seed + i, 8), phi = 2 * kPi * Uniform(seed + i, 9);
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
    origin.insert(origin.end(), {o.x, o.y, o.z});
    direction.insert(direction.end(), {d.x, d.y, d.z});
    tmax.push_back(i % 4 == 0 ? kInfinity : 8 * Uniform(seed + i, 10));
  }
  MajorantSegments out;
  out.segments.push_back({0, 1, Vec3(1, 1, 1)});  // replaced, not appended to
  medium.Majorants(origin, direction, tmax, out);
  ASSERT_EQ(out.offsets.size(), size_t(rays) + 1);
  ASSERT_EQ(out.offsets[0], 0u);
  for (int i = 0; i < rays; ++i) {
    const Vec3 o = Vec3::Load(&origin[3 * i]), d = Vec3::Load(&direction[3 * i]);
    const auto segments = out.Of(i);
    *segments_seen += int(segments.size());
    std::vector<Vec3> points;
    std::vector<size_t> owner;
    for (size_t s = 0; s < segments.size(); ++s) {
      const MajorantSegment& seg = segments[s];
      ASSERT_LT(seg.t0, seg.t1);
      ASSERT_GE(seg.t0, 0);
      ASSERT_LE(seg.t1, tmax[i]);
      if (s > 0) {
        ASSERT_GE(seg.t0, segments[s - 1].t1);
      }
      for (int q = 0; q < 16; ++q) {
        const float u = q == 0 ? 0.0f : (q == 15 ? 0.99999f : Uniform(seed * 131 + i * 17 + s, q));
        points.push_back(o + d * (seg.t0 + u * (seg.t1 - seg.t0)));
        owner.push_back(s);
      }
    }
    if (axis_aligned) {
      // The world box of an axis-aligned to_world, by a slab test in double.
      double t0 = 0, t1 = tmax[i];
      for (int a = 0; a < 3; ++a) {
        const double lo = to_world.m[4 * a + 3], hi = lo + to_world.m[5 * a];
        if (d[a] == 0) {
          if (o[a] < lo || o[a] > hi) t1 = -1;
          continue;
        }
        double n = (lo - o[a]) / d[a], f = (hi - o[a]) / d[a];
        if (n > f) std::swap(n, f);
        t0 = std::max(t0, n);
        t1 = std::min(t1, f);
      }
      if (t1 - t0 > 1e-4) {
        ASSERT_FALSE(segments.empty()) << "ray " << i;
        EXPECT_NEAR(segments.front().t0, t0, 1e-4) << "ray " << i;
        EXPECT_NEAR(segments.back().t1, t1, 1e-4) << "ray " << i;
        for (size_t s = 1; s < segments.size(); ++s) EXPECT_EQ(segments[s].t0, segments[s - 1].t1) << "ray " << i;
      } else if (t1 - t0 < -1e-4) {
        EXPECT_TRUE(segments.empty()) << "ray " << i;
      }
    }
    if (points.empty()) continue;
    std::vector<float> position, sa(3 * points.size()), ss(3 * points.size()), e(3 * points.size());
    for (const Vec3& p : points) position.insert(position.end(), {p.x, p.y, p.z});
    medium.Coefficients(position, sa, ss, e);
    for (size_t k = 0; k < points.size(); ++k) {
      const Vec3 sigma_t = Vec3::Load(&sa[3 * k]) + Vec3::Load(&ss[3 * k]);
      const Vec3 maj = segments[owner[k]].sigma_maj;
      for (int c = 0; c < 3; ++c)
        ASSERT_LE(sigma_t[c], maj[c] * (1 + 1e-5f) + 1e-6f) << "ray " << i << " segment " << owner[k];
    }
  }
}

TEST_F(GridMediumTest, MajorantsBoundTheExtinctionAlongRandomRays) {
  const int nx = 23, ny = 7, nz = 40;
  std::vector<float> d(nx * ny * nz * 3);
  for (size_t i = 0; i < d.size(); ++i) {
    const float u = Uniform(i, 11);
    d[i] = u < 0.3f ? 0.0f : (u > 0.97f ? 20 * u : u);  // empty voxels and spikes
  }
  const std::filesystem::path file = Write("random.vol", VolBytes(nx, ny, nz, 3, d));
  int segments_seen = 0;
  for (const bool skewed : {false, true})
    for (const std::string edge : {"clamp", "zero"}) {
      Properties props;
      props.Set("filename", file);
      props.Set("sigma_a", Rgb{Vec3(0.5f, 0.1f, 0)});
      props.Set("sigma_s", Rgb{Vec3(0.5f, 1, 2)});
      props.Set("scale", 3.0);
      props.Set("edge", edge);
      const Transform to_world = skewed ? Skewed() : Affine(Vec3(2, 0.5f, 1.25f), Vec3(-0.5f, 1, 0));
      props.Set("to_world", to_world);
      const auto medium = Make(props);
      CheckMajorants(*medium, to_world, !skewed, 150, skewed ? 1000 : 2000, &segments_seen);
    }
  EXPECT_GT(segments_seen, 400);  // the rays do cross many cells
}

TEST_F(GridMediumTest, MajorantOfAConstantGridGivesTheExactTransmittance) {
  Properties props;
  props.Set("density", std::vector<float>(5 * 4 * 3, 0.8f));
  props.Set("nx", int64_t(5));
  props.Set("ny", int64_t(4));
  props.Set("nz", int64_t(3));
  props.Set("sigma_a", Rgb{Vec3(0.2f, 0.3f, 0.4f)});
  props.Set("sigma_s", Rgb{Vec3(1, 0.5f, 0.1f)});
  const Transform to_world = Affine(Vec3(1.5f, 2, 0.75f), Vec3(0, -1, 0.25f));
  props.Set("to_world", to_world);
  const auto medium = Make(props);
  const Vec3 sigma_t = Vec3(1.2f, 0.8f, 0.5f) * 0.8f;
  int crossing = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 target = to_world.Point(Vec3(Uniform(i, 12), Uniform(i, 13), Uniform(i, 14)));
    const Vec3 o = target + Normalize(Vec3(Uniform(i, 15) - 0.5f, Uniform(i, 16) - 0.5f, Uniform(i, 17) - 0.5f)) * 6;
    const Vec3 d = Normalize(target - o);
    const std::vector<float> origin{o.x, o.y, o.z}, direction{d.x, d.y, d.z}, tmax{i % 2 ? kInfinity : 7.0f};
    MajorantSegments out;
    medium->Majorants(origin, direction, tmax, out);
    // The chord through the box, by a slab test.
    double t0 = 0, t1 = tmax[0];
    for (int a = 0; a < 3; ++a) {
      const double lo = to_world.m[4 * a + 3], hi = lo + to_world.m[5 * a];
      double n = (lo - o[a]) / d[a], f = (hi - o[a]) / d[a];
      if (n > f) std::swap(n, f);
      t0 = std::max(t0, n);
      t1 = std::min(t1, f);
    }
    const double length = std::max(0.0, t1 - t0);
    crossing += length > 0;
    for (int c = 0; c < 3; ++c) {
      double optical = 0;
      for (const MajorantSegment& s : out.Of(0)) optical += double(s.sigma_maj[c]) * (s.t1 - s.t0);
      EXPECT_NEAR(std::exp(-optical), std::exp(-sigma_t[c] * length), 1e-5) << "ray " << i;
    }
  }
  EXPECT_GT(crossing, 150);
}

TEST_F(GridMediumTest, NegativeVoxelsCountAsZero) {
  Properties props;
  props.Set("filename", Write("negative.vol", VolBytes(2, 1, 1, 1, {-1e-7f, -3})));
  const auto medium = Make(props);
  const Sample s = At(*medium, {Vec3(0.5f, 0.5f, 0.5f)});
  EXPECT_EQ(s.S(0).x, 0);
}

TEST_F(GridMediumTest, EveryBadInputIsAnError) {
  const std::vector<float> one{1};
  struct Case {
    std::string name, bytes, expected;
  };
  std::string wrong_version = VolBytes(1, 1, 1, 1, one), wrong_encoding = wrong_version;
  wrong_version[3] = 2;
  wrong_encoding[4] = 2;
  const std::string huge_header = VolBytes(1 << 20, 1 << 20, 1 << 20, 1, one);
  const std::vector<Case> cases{
      {"magic.vol", "NOT A GRID FILE AT ALL, JUST SOME TEXT OF ANY LENGTH AT ALL", "neither"},
      {"version.vol", wrong_version, "version 2"},
      {"encoding.vol", wrong_encoding, "encoding 2"},
      {"truncated.vol", VolBytes(2, 2, 2, 1, {1, 2, 3}), "truncated"},
      {"header.vol", VolBytes(2, 2, 2, 1, {}).substr(0, 30), "truncated"},
      {"trailing.vol", VolBytes(1, 1, 1, 1, {1, 2}), "bytes more"},
      {"channels.vol", VolBytes(1, 1, 1, 2, {1, 2}), "channels"},
      {"zero.vol", VolBytes(0, 1, 1, 1, {}), "at least 1"},
      {"negative.vol", VolBytes(-4, 1, 1, 1, {}), "at least 1"},
      {"huge.vol", huge_header, "larger than"},
      {"nan.vol", VolBytes(2, 1, 1, 1, {1, std::nanf("")}), "finite"},
      {"inf.vol", VolBytes(1, 1, 1, 1, {INFINITY}), "finite"},
      {"empty.vol", "", "neither"},
  };
  for (const Case& c : cases) {
    Properties props;
    props.Set("filename", Write(c.name, c.bytes));
    EXPECT_NE(CreationError(props).find(c.expected), std::string::npos) << c.name << ": " << CreationError(props);
  }

  Properties missing;
  missing.Set("filename", folder_.path() / "missing.vol");
  EXPECT_NE(CreationError(missing).find("'filename'"), std::string::npos) << CreationError(missing);

  const auto inline_grid = [](std::vector<float> values, int64_t nx) {
    Properties props;
    props.Set("density", std::move(values));
    props.Set("nx", nx);
    props.Set("ny", int64_t(1));
    props.Set("nz", int64_t(1));
    return props;
  };
  EXPECT_NE(CreationError(inline_grid({1, 2, 3}, 2)).find("has 3 values"), std::string::npos);
  EXPECT_NE(CreationError(inline_grid({1}, 0)).find("at least 1"), std::string::npos);
  EXPECT_NE(CreationError(inline_grid({1}, int64_t(1) << 40)).find("larger than"), std::string::npos);
  EXPECT_NE(CreationError(inline_grid({1, NAN}, 2)).find("finite"), std::string::npos);
  Properties no_resolution;
  no_resolution.Set("density", std::vector<float>{1, 2});
  EXPECT_NE(CreationError(no_resolution).find("nx, ny, nz"), std::string::npos);

  Properties singular = inline_grid({1, 2}, 2);
  singular.Set("to_world", Affine(Vec3(1, 0, 1), Vec3(0, 0, 0)));
  EXPECT_NE(CreationError(singular).find("singular"), std::string::npos);
  Properties both = inline_grid({1, 2}, 2);
  both.Set("filename", Write("both.vol", VolBytes(1, 1, 1, 1, one)));
  EXPECT_NE(CreationError(both).find("give one"), std::string::npos);
  Properties edge = inline_grid({1, 2}, 2);
  edge.Set("edge", std::string("mirror"));
  EXPECT_NE(CreationError(edge).find("'edge'"), std::string::npos);
  Properties albedo = inline_grid({1, 2}, 2);
  albedo.Set("albedo", 1.5);
  EXPECT_NE(CreationError(albedo).find("'albedo'"), std::string::npos);
  Properties bbox = inline_grid({1, 2}, 2);
  bbox.Set("use_grid_bbox", true);
  EXPECT_NE(CreationError(bbox).find("use_grid_bbox"), std::string::npos);
  Properties unused = inline_grid({1, 2}, 2);
  unused.Set("filter_type", std::string("nearest"));
  EXPECT_NE(CreationError(unused).find("filter_type"), std::string::npos);
  Properties no_grid;
  no_grid.Set("sigma_s", 2.0);
  EXPECT_NE(CreationError(no_grid).find("homogeneous"), std::string::npos);
}

#ifdef YARF_HAVE_OPENVDB
TEST_F(GridMediumTest, OpenVdbGridIsSampledAtItsVoxelsAndPlacedByItsTransform) {
  openvdb::initialize();
  const auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("smoke");
  grid->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
  auto accessor = grid->getAccessor();
  accessor.setValue(openvdb::Coord(2, -1, 4), 1.5f);
  accessor.setValue(openvdb::Coord(4, -1, 4), 3.0f);
  accessor.setValue(openvdb::Coord(3, 0, 5), 0.5f);
  const std::filesystem::path path = folder_.path() / "smoke.vdb";
  openvdb::io::File file(path.string());
  file.write(openvdb::GridPtrVec{grid});
  file.close();

  Properties props;
  props.Set("filename", path);
  props.Set("grid_name", std::string("smoke"));
  props.Set("use_grid_bbox", true);
  const auto medium = Make(props);
  // Voxel (i, j, k) is centred at 0.5·(i, j, k) in the grid's world.
  const Sample s = At(*medium, {Vec3(1, -0.5f, 2), Vec3(2, -0.5f, 2), Vec3(1.5f, 0, 2.5f), Vec3(1.5f, -0.5f, 2),
                                Vec3(0.5f, -0.5f, 2)});
  EXPECT_NEAR(s.S(0).x, 1.5f, 1e-5f);
  EXPECT_NEAR(s.S(1).y, 3.0f, 1e-5f);
  EXPECT_NEAR(s.S(2).z, 0.5f, 1e-5f);
  EXPECT_NEAR(s.S(3).x, 0.0f, 1e-5f);  // an inactive voxel: the background
  EXPECT_EQ(s.S(4).x, 0);              // outside the active voxels' box

  props.Set("grid_name", std::string("density"));
  EXPECT_NE(CreationError(props).find("no grid named 'density'"), std::string::npos) << CreationError(props);
}
#endif

class CloudMediumTest : public testing::Test {
 protected:
  CloudMediumTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }
  std::unique_ptr<Medium> Make(const Properties& props) const { return registry_.CreateAs<Medium>("cloud", props); }
  Registry registry_;
};

TEST_F(CloudMediumTest, DensityLiesInTheUnitIntervalAndIsFullBelowZero) {
  Properties props;
  props.Set("p0", Vec3(-1, -0.5f, -1));
  props.Set("p1", Vec3(1, 1.5f, 1));
  props.Set("sigma_a", Rgb{Vec3(0.5f, 1, 2)});
  props.Set("sigma_s", 3.0);
  props.Set("density", 2.0);
  props.Set("scale", 0.5);
  const Transform to_world = Skewed();
  props.Set("to_world", to_world);
  const auto medium = Make(props);
  EXPECT_FALSE(medium->Emits());
  const Vec3 sigma_a(0.25f, 0.5f, 1), sigma_s(1.5f, 1.5f, 1.5f);
  std::vector<float> position;
  std::vector<Vec3> local;
  for (int i = 0; i < 2000; ++i) {
    // The box and a margin around it.
    const Vec3 p(-1.2f + 2.4f * Uniform(i, 20), -0.7f + 2.4f * Uniform(i, 21), -1.2f + 2.4f * Uniform(i, 22));
    local.push_back(p);
    const Vec3 w = to_world.Point(p);
    position.insert(position.end(), {w.x, w.y, w.z});
  }
  std::vector<float> sa(position.size()), ss(position.size()), e(position.size());
  medium->Coefficients(position, sa, ss, e);
  int partial = 0;
  for (size_t k = 0; k < local.size(); ++k) {
    const Vec3 p = local[k];
    const float d = ss[3 * k] / sigma_s.x;
    ASSERT_GE(d, 0);
    ASSERT_LE(d, 1 + 1e-6f);
    EXPECT_NEAR(sa[3 * k + 2], d * sigma_a.z, 1e-5f);
    EXPECT_EQ(e[3 * k], 0);
    const bool inside = std::abs(p.x) < 0.999f && std::abs(p.z) < 0.999f && p.y > -0.499f && p.y < 1.499f;
    const bool outside = std::abs(p.x) > 1.001f || std::abs(p.z) > 1.001f || p.y < -0.501f || p.y > 1.501f;
    if (outside) {
      EXPECT_EQ(d, 0) << p.x << " " << p.y << " " << p.z;
    }
    if (inside && p.y < 0) {
      EXPECT_NEAR(d, 1, 1e-6f);
    }
    partial += inside && d > 0.05f && d < 0.95f;
  }
  EXPECT_GT(partial, 100);  // between the two: clouds, neither empty nor full
}

TEST_F(CloudMediumTest, OneMajorantOverTheBox) {
  Properties props;
  props.Set("p0", Vec3(2, 1, 0));
  props.Set("p1", Vec3(0, 0, 3));  // either corner first, as pbrt's Bounds3f takes them
  props.Set("sigma_a", 0.5);
  props.Set("sigma_s", Rgb{Vec3(1, 2, 3)});
  props.Set("wispiness", 0.0);
  props.Set("frequency", 2.0);
  const Transform to_world = Affine(Vec3(1, 1, 1), Vec3(0, 0, 0));
  props.Set("to_world", to_world);
  const auto medium = Make(props);
  // The box [0, 2]×[0, 1]×[0, 3] as the image of the unit cube, for the
  // coverage check.
  int segments_seen = 0;
  CheckMajorants(*medium, Affine(Vec3(2, 1, 3), Vec3(0, 0, 0)), true, 300, 3000, &segments_seen);
  EXPECT_GT(segments_seen, 10);  // some of the random rays do cross the box
  const std::vector<float> origin{1, 0.5f, -1}, direction{0, 0, 1}, tmax{10};
  MajorantSegments out;
  medium->Majorants(origin, direction, tmax, out);
  ASSERT_EQ(out.Of(0).size(), 1u);
  EXPECT_NEAR(out.Of(0)[0].t0, 1, 1e-6f);
  EXPECT_NEAR(out.Of(0)[0].t1, 4, 1e-6f);
  EXPECT_NEAR(out.Of(0)[0].sigma_maj.z, 3.5f, 1e-6f);
}

TEST_F(CloudMediumTest, RefusesBadProperties) {
  const auto fails = [&](const char* key, Properties::Value value) {
    Properties props;
    props.Set(key, std::move(value));
    EXPECT_THROW(Make(props), Error) << key;
  };
  fails("p1", Vec3(1, 0, 1));  // flat against p0 = (0, 0, 0)
  fails("sigma_s", -1.0);
  fails("density", double(NAN));
  fails("frequency", double(INFINITY));
  fails("to_world", Affine(Vec3(1, 1, 0), Vec3(0, 0, 0)));
  fails("scale", -1.0);
}

TEST(PropertiesProto, FloatArrayReachesTheComponent) {
  v1::Properties message;
  for (float v : {0.5f, -2.0f, 3.25f})
    (*message.mutable_values())["density"].mutable_float_array_value()->add_values(v);
  const Properties props = FromProto(message);
  EXPECT_TRUE(props.HasFloatArray("density"));
  EXPECT_EQ(props.FloatArray("density"), (std::vector<float>{0.5f, -2.0f, 3.25f}));
  EXPECT_THROW(props.Float("density"), Error);
}

}  // namespace
}  // namespace yarf
