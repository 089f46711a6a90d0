#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "kernel/film.h"
#include "yarf/error.h"

namespace yarf {
namespace {

v1::ReconstructionFilter Gaussian() {
  v1::ReconstructionFilter f;
  f.set_kind(v1::ReconstructionFilter::GAUSSIAN);
  f.set_radius(1.5);
  return f;
}

// Adds `passes` passes of camera samples and splats drawn from `rng`.
void Render(Film& film, std::mt19937& rng, int passes) {
  std::uniform_real_distribution<float> u(0, 1);
  for (int pass = 0; pass < passes; ++pass) {
    for (int i = 0; i < 200; ++i) {
      film.Add(u(rng) * film.width(), u(rng) * film.height(), {u(rng), 2 * u(rng), 0.5f});
      film.Splat(u(rng) * film.width(), u(rng) * film.height(), {u(rng), u(rng), u(rng)});
    }
    film.EndPass(2);
  }
}

TEST(FilmSave, AFilmLoadedFromItsSaveGoesOnExactlyAsTheOriginal) {
  Film original(7, 5, Gaussian());
  std::mt19937 rng(11);
  Render(original, rng, 3);
  Film loaded = Film::Load(original.Save());
  EXPECT_EQ(loaded.width(), 7u);
  EXPECT_EQ(loaded.height(), 5u);
  EXPECT_EQ(loaded.Pixels(), original.Pixels());
  EXPECT_EQ(loaded.Variances(), original.Variances());
  // The same later passes give bit-identical estimates: every accumulator
  // and the pass counts came back.
  std::mt19937 rng_a(5), rng_b(5);
  Render(original, rng_a, 2);
  Render(loaded, rng_b, 2);
  EXPECT_EQ(loaded.Pixels(), original.Pixels());
  EXPECT_EQ(loaded.Variances(), original.Variances());
  EXPECT_EQ(loaded.Save(), original.Save());
}

TEST(FilmSave, AFilmWithoutSplatsRoundTrips) {
  Film film(3, 3, Gaussian());
  film.Add(1.5f, 1.5f, {1, 1, 1});
  film.EndPass();
  EXPECT_EQ(Film::Load(film.Save()).Pixels(), film.Pixels());
}

TEST(FilmSave, DamagedBytesAreRefusedWithAnError) {
  Film film(4, 4, Gaussian());
  std::mt19937 rng(1);
  Render(film, rng, 1);
  const std::string saved = film.Save();
  EXPECT_THROW(Film::Load(saved.substr(0, saved.size() - 1)), Error);
  EXPECT_THROW(Film::Load(saved + "x"), Error);
  EXPECT_THROW(Film::Load("not a film at all"), Error);
  EXPECT_THROW(Film::Load(""), Error);
  std::string other_version = saved;
  other_version[8] = 9;
  EXPECT_THROW(Film::Load(other_version), Error);
}

// Saved-film header fields: u32s after the 8-byte magic, then the filter.
constexpr size_t kPassesAt = 20, kSplatPassesAt = 24, kFilterSizeAt = 32, kFilterAt = 36;

uint32_t GetU32(const std::string& bytes, size_t at) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + at, sizeof value);
  return value;
}

std::string WithU32(std::string bytes, size_t at, uint32_t value) {
  std::memcpy(bytes.data() + at, &value, sizeof value);
  return bytes;
}

// `saved` with its filter bytes replaced by `filter`'s.
std::string WithFilter(const std::string& saved, const v1::ReconstructionFilter& filter) {
  const std::string bytes = filter.SerializeAsString();
  std::string out = WithU32(saved, kFilterSizeAt, uint32_t(bytes.size())).substr(0, kFilterAt) + bytes;
  return out + saved.substr(kFilterAt + GetU32(saved, kFilterSizeAt));
}

TEST(FilmSave, SplatPassesWithoutSplatImagesOrBeyondThePassesAreRefused) {
  Film plain(3, 3, Gaussian());
  plain.Add(1.5f, 1.5f, {1, 1, 1});
  plain.EndPass();
  const std::string saved = plain.Save();
  ASSERT_EQ(GetU32(saved, kSplatPassesAt), 0u);
  // Pixels() would read splat sums that were never saved.
  EXPECT_THROW(Film::Load(WithU32(saved, kSplatPassesAt, 1)), Error);

  Film splatted(4, 4, Gaussian());
  std::mt19937 rng(3);
  Render(splatted, rng, 2);
  const std::string with_splats = splatted.Save();
  ASSERT_EQ(GetU32(with_splats, kPassesAt), 2u);
  EXPECT_NO_THROW(Film::Load(with_splats));
  EXPECT_THROW(Film::Load(WithU32(with_splats, kSplatPassesAt, 3)), Error);
}

TEST(FilmSave, AFilterOfUnknownKindOrBadRadiusOrHugeSizeIsRefused) {
  Film film(4, 4, Gaussian());
  std::mt19937 rng(2);
  Render(film, rng, 1);
  const std::string saved = film.Save();
  v1::ReconstructionFilter filter = Gaussian();
  ASSERT_NO_THROW(Film::Load(WithFilter(saved, filter)));
  filter.set_kind(static_cast<v1::ReconstructionFilter::Kind>(1000000000));
  EXPECT_THROW(Film::Load(WithFilter(saved, filter)), Error);
  for (double radius : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -1.0,
                        1e9}) {
    filter = Gaussian();
    filter.set_radius(radius);
    EXPECT_THROW(Film::Load(WithFilter(saved, filter)), Error) << radius;
  }
  // A filter size past what any filter needs, with the bytes there.
  std::string huge = WithU32(saved, kFilterSizeAt, 5000);
  huge.insert(kFilterAt, std::string(5000 - GetU32(saved, kFilterSizeAt), '\0'));
  EXPECT_THROW(Film::Load(huge), Error);
  EXPECT_THROW(Film::Load(WithU32(saved, kFilterSizeAt, 0xffffffffu)), Error);
}

TEST(ReconstructionFilter, AnUnknownKindOrARadiusOutOfRangeIsAnError) {
  v1::ReconstructionFilter filter;
  filter.set_kind(static_cast<v1::ReconstructionFilter::Kind>(1000000000));
  EXPECT_THROW(ReconstructionFilter{filter}, Error);
  filter.set_kind(static_cast<v1::ReconstructionFilter::Kind>(-1));
  EXPECT_THROW(ReconstructionFilter{filter}, Error);
  filter.set_kind(v1::ReconstructionFilter::TENT);
  for (double radius : {std::nan(""), -0.5, 16.5, 1e30}) {
    filter.set_radius(radius);
    EXPECT_THROW(ReconstructionFilter{filter}, Error) << radius;
  }
  filter.set_radius(16);
  EXPECT_FLOAT_EQ(ReconstructionFilter(filter).radius(), 16);
  filter.set_radius(0);
  EXPECT_FLOAT_EQ(ReconstructionFilter(filter).radius(), 1);  // the tent's default
}

}  // namespace
}  // namespace yarf
