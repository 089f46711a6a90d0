#include <gtest/gtest.h>

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

}  // namespace
}  // namespace yarf
