#include "kernel/film.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <utility>

#include "yarf/error.h"

namespace yarf {

namespace {

// A filter parameter that is finite and within [lo, hi], else Error.
double Checked(const char* name, double value, double lo, double hi) {
  if (!(std::isfinite(value) && value >= lo && value <= hi))
    throw Error(std::string("film.filter.") + name + " " + std::to_string(value) + " is out of range (" +
                std::to_string(lo) + " to " + std::to_string(hi) + ")");
  return value;
}

// sin(πx)/(πx).
float Sinc(float x) {
  if (std::abs(x) < 1e-5f) return 1;
  const float px = kPi * x;
  return std::sin(px) / px;
}

// The kind's support radius when the filter gives none.
double DefaultRadius(const v1::ReconstructionFilter& filter, double stddev, double lobes) {
  switch (filter.kind()) {
    case v1::ReconstructionFilter::TENT:
      return 1;
    case v1::ReconstructionFilter::GAUSSIAN:
      return 4 * stddev;
    case v1::ReconstructionFilter::MITCHELL:
      return 2;
    case v1::ReconstructionFilter::LANCZOS:
      return lobes;
    default:
      return 0.5;
  }
}

double StddevOf(const v1::ReconstructionFilter& filter) {
  return filter.stddev() > 0 ? filter.stddev() : 0.5;
}

double LobesOf(const v1::ReconstructionFilter& filter) { return filter.lobes() > 0 ? filter.lobes() : 3; }

// The radius along x, then y, checked.
std::pair<float, float> RadiiOf(const v1::ReconstructionFilter& filter) {
  // Proto3 enums carry any number.
  if (!v1::ReconstructionFilter::Kind_IsValid(filter.kind()))
    throw Error("film.filter.kind " + std::to_string(int(filter.kind())) +
                " is not BOX, TENT, GAUSSIAN, MITCHELL or LANCZOS");
  Checked("radius", filter.radius(), 0, ReconstructionFilter::kMaxRadius);
  Checked("radius_y", filter.radius_y(), 0, ReconstructionFilter::kMaxRadius);
  Checked("stddev", filter.stddev(), 0, 1e3);
  Checked("lobes", filter.lobes(), 0, 1e3);
  const double fallback = DefaultRadius(filter, StddevOf(filter), LobesOf(filter));
  if (filter.radius() == 0 && fallback > ReconstructionFilter::kMaxRadius)
    throw Error("film.filter: the default radius " + std::to_string(fallback) + " (4 stddev, or lobes) is above " +
                std::to_string(int(ReconstructionFilter::kMaxRadius)) + " pixels: give a radius");
  const double x = filter.radius() > 0 ? filter.radius() : fallback;
  return {float(x), float(filter.radius_y() > 0 ? filter.radius_y() : x)};
}

}  // namespace

FilterAxis::FilterAxis(const v1::ReconstructionFilter& filter, float radius)
    : kind_(filter.kind()), radius_(radius) {
  if (kind_ == v1::ReconstructionFilter::GAUSSIAN) {
    const double stddev = StddevOf(filter);
    gaussian_alpha_ = float(-1 / (2 * stddev * stddev));
    gaussian_offset_ = std::exp(gaussian_alpha_ * radius_ * radius_);
  } else if (kind_ == v1::ReconstructionFilter::MITCHELL) {
    const float b = float(Checked("b", filter.has_b() ? filter.b() : 1.0 / 3, -100, 100));
    const float c = float(Checked("c", filter.has_c() ? filter.c() : 1.0 / 3, -100, 100));
    inner_ = {(12 - 9 * b - 6 * c) / 6, (-18 + 12 * b + 6 * c) / 6, 0, (6 - 2 * b) / 6};
    outer_ = {(-b - 6 * c) / 6, (6 * b + 30 * c) / 6, (-12 * b - 48 * c) / 6, (8 * b + 24 * c) / 6};
  } else if (kind_ == v1::ReconstructionFilter::LANCZOS) {
    lobes_ = float(LobesOf(filter));
  }
  // A negative lobe is fine; a filter whose centre or mass is not
  // positive would make a pixel the negative of its samples' average.
  if (!(Weight(0) > 0 && Mass(0, -radius_, radius_) > 0))
    throw Error("film.filter: these parameters make a filter whose centre or integral is not positive");
}

float FilterAxis::Mass(float centre, float lo, float hi) const {
  lo = std::max(lo, centre - radius_), hi = std::min(hi, centre + radius_);
  if (!(hi > lo)) return 0;
  // Midpoint rule: the weights are smooth enough for 4096 steps.
  constexpr int kSteps = 4096;
  double sum = 0;
  for (int i = 0; i < kSteps; ++i) sum += Weight(lo + (i + 0.5f) * (hi - lo) / kSteps - centre);
  return float(sum * (hi - lo) / kSteps);
}

float FilterAxis::Weight(float d) const {
  d = std::abs(d);
  if (d >= radius_) return 0;
  switch (kind_) {
    case v1::ReconstructionFilter::TENT:
      return 1 - d / radius_;
    case v1::ReconstructionFilter::GAUSSIAN:
      return std::exp(gaussian_alpha_ * d * d) - gaussian_offset_;
    case v1::ReconstructionFilter::MITCHELL: {
      const float x = 2 * d / radius_;
      const std::array<float, 4>& k = x <= 1 ? inner_ : outer_;
      return ((k[0] * x + k[1]) * x + k[2]) * x + k[3];
    }
    case v1::ReconstructionFilter::LANCZOS:
      return Sinc(d) * Sinc(d / lobes_);
    default:
      return 1;
  }
}

ReconstructionFilter::ReconstructionFilter(const v1::ReconstructionFilter& filter)
    : ReconstructionFilter(filter, RadiiOf(filter)) {}

Film::Film(uint32_t width, uint32_t height, const v1::ReconstructionFilter& filter)
    : width_(width), height_(height), filter_spec_(filter), filter_(filter), pixels_(size_t(width) * height) {}

PixelWindow Film::Footprint(float x, float y) const {
  if (!(std::isfinite(x) && std::isfinite(y))) return {0, 0, 0, 0};
  // Pixel i has its centre at i + 0.5. Clamped as floats: a position far
  // off the film does not fit an int.
  const auto span = [](float at, float r, uint32_t size) -> std::pair<uint32_t, uint32_t> {
    const float first = std::max(0.0f, std::ceil(at - r - 0.5f));
    // At most kMaxFootprintSide pixels even where floats round coarsely.
    const float last = std::min({float(size) - 1, std::floor(at + r - 0.5f), first + float(kMaxFootprintSide - 1)});
    if (!(first <= last)) return {0, 0};
    return {uint32_t(first), uint32_t(last) + 1};
  };
  const auto [x0, x1] = span(x, filter_.x().radius(), width_);
  const auto [y0, y1] = span(y, filter_.y().radius(), height_);
  if (x0 == x1 || y0 == y1) return {0, 0, 0, 0};
  return {x0, y0, x1, y1};
}

template <typename Visit>
void Film::ForEachPixelInFilter(float x, float y, const PixelWindow& pixels, Visit&& visit) const {
  // The filter is separable: a weight per column and one per row, each
  // made once, rather than two per pixel (exponentials, for a Gaussian).
  std::array<float, kMaxFootprintSide> column_weight, row_weight;
  const uint32_t columns = pixels.x1 - pixels.x0, rows = pixels.y1 - pixels.y0;
  for (uint32_t i = 0; i < columns; ++i) column_weight[i] = filter_.x().Weight(float(pixels.x0 + i) + 0.5f - x);
  for (uint32_t j = 0; j < rows; ++j) row_weight[j] = filter_.y().Weight(float(pixels.y0 + j) + 0.5f - y);
  for (uint32_t j = 0; j < rows; ++j) {
    if (row_weight[j] == 0) continue;
    const uint32_t y = pixels.y0 + j;
    const size_t row = size_t(y) * width_;
    for (uint32_t i = 0; i < columns; ++i) {
      const double w = column_weight[i] * row_weight[j];
      if (w != 0) visit(row + pixels.x0 + i, pixels.x0 + i, y, w);
    }
  }
}

namespace {
bool Finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
}  // namespace

void Film::Add(float x, float y, Vec3 value, const PixelWindow& pixels) {
  if (!Finite(value)) return;
  ForEachPixelInFilter(x, y, pixels, [&](size_t k, uint32_t, uint32_t, double w) {
    Pixel& p = pixels_[k];
    p.weight += w;
    p.weight_sq += w * w;
    for (int c = 0; c < 3; ++c) {
      const double l = value[c];
      p.sum[c] += w * l;
      p.sum_wsq[c] += w * w * l;
      p.sum_sq[c] += w * w * l * l;
    }
  });
}

void Film::AddEstimate(uint32_t px, uint32_t py, Vec3 value, Vec3 variance, uint32_t samples) {
  if (!Finite(value) || !Finite(variance) || samples == 0 || px >= width_ || py >= height_) return;
  // n samples L_i of mean v whose mean has variance s²: Σ L_i = n v and
  // Σ (L_i − v)² = (n − 1) · n s², so Σ L_i² = n v² + n (n − 1) s².
  const double n = samples;
  Pixel& p = pixels_[size_t(py) * width_ + px];
  p.weight += n;
  p.weight_sq += n;
  for (int c = 0; c < 3; ++c) {
    const double v = value[c], s2 = std::max(0.0f, variance[c]);
    p.sum[c] += n * v;
    p.sum_wsq[c] += n * v;
    p.sum_sq[c] += n * v * v + n * (n - 1) * s2;
  }
}

void Film::PrepareSplats() {
  if (splats_.pass.empty()) {
    splats_.pass.assign(pixels_.size() * 3, 0.0);
    splats_.sum.assign(pixels_.size() * 3, 0.0);
    splats_.sum_sq.assign(pixels_.size() * 3, 0.0);
  }
  PrepareMasses();
}

void Film::PrepareMasses() {
  if (column_mass_.empty()) {
    // Made at the first splat or pixel weight (a resumed film's too):
    // within a radius of the border a pixel's filter is cut; elsewhere whole.
    const auto masses = [](const FilterAxis& axis, uint32_t count) {
      const float r = axis.radius();
      std::vector<float> mass(count, axis.Mass(0, -r, r));
      for (uint32_t i = 0; i < count; ++i)
        if (i + 0.5f < r || i + 0.5f + r > float(count)) mass[i] = axis.Mass(i + 0.5f, 0, float(count));
      return mass;
    };
    column_mass_ = masses(filter_.x(), width_);
    row_mass_ = masses(filter_.y(), height_);
  }
}

void Film::Splat(float x, float y, Vec3 value) {
  // A film that never had a splat that counts has no splat images to save.
  if (!Finite(value) || !(std::isfinite(x) && std::isfinite(y))) return;
  PrepareSplats();
  Splat(x, y, value, Footprint(x, y));
}

void Film::Splat(float x, float y, Vec3 value, const PixelWindow& pixels) {
  if (!Finite(value)) return;
  ForEachPixelInFilter(x, y, pixels, [&](size_t k, uint32_t column, uint32_t row, double w) {
    const double scale = 1.0 / (double(column_mass_[column]) * row_mass_[row]);
    for (int c = 0; c < 3; ++c) splats_.pass[3 * k + c] += w * scale * value[c];
  });
}

void Film::EndPass(uint32_t samples) {
  ++passes_;
  if (splats_.pass.empty()) return;
  const double scale = 1.0 / std::max(samples, 1u);
  for (size_t i = 0; i < splats_.pass.size(); ++i) {
    const double estimate = splats_.pass[i] * scale;
    splats_.sum[i] += estimate;
    splats_.sum_sq[i] += estimate * estimate;
    splats_.pass[i] = 0;
  }
  splats_.passes = passes_;
}

std::vector<float> Film::Pixels() const {
  std::vector<float> out(pixels_.size() * 3, 0.0f);
  for (size_t k = 0; k < pixels_.size(); ++k)
    if (pixels_[k].weight > 0)
      for (int c = 0; c < 3; ++c) out[k * 3 + c] = float(pixels_[k].sum[c] / pixels_[k].weight);
  if (splats_.passes > 0)
    for (size_t i = 0; i < out.size(); ++i) out[i] += float(splats_.sum[i] / splats_.passes);
  return out;
}

std::vector<float> Film::Variances() const {
  // Var of Σ w L / Σ w with L's variance estimated from the samples:
  // Σ w² (L − m)² / (Σ w)², scaled by n/(n−1) (effective n).
  std::vector<float> out(pixels_.size() * 3, 0.0f);
  for (size_t k = 0; k < pixels_.size(); ++k) {
    const Pixel& p = pixels_[k];
    if (p.weight <= 0 || p.weight_sq <= 0) continue;
    const double n_eff = p.weight * p.weight / p.weight_sq;
    if (n_eff <= 1) continue;
    for (int c = 0; c < 3; ++c) {
      const double m = p.sum[c] / p.weight;
      const double ss = p.sum_sq[c] - 2 * m * p.sum_wsq[c] + m * m * p.weight_sq;
      out[k * 3 + c] = float(std::max(0.0, ss) / (p.weight * p.weight) * n_eff / (n_eff - 1));
    }
  }
  // The splat value is a mean over passes: the variance of that mean.
  const double n = splats_.passes;
  if (n > 1)
    for (size_t i = 0; i < out.size(); ++i) {
      const double m = splats_.sum[i] / n;
      out[i] += float(std::max(0.0, splats_.sum_sq[i] / n - m * m) / (n - 1));
    }
  return out;
}

// Saved film: "YARFFILM", format version, then little-endian u32 width,
// height, passes, splat passes, whether there are splat images, the
// filter's proto size and bytes, then the doubles of every pixel's
// accumulators and, if any, of the three splat images.
namespace {

constexpr char kFilmMagic[8] = {'Y', 'A', 'R', 'F', 'F', 'I', 'L', 'M'};
constexpr uint32_t kFilmVersion = 1;
constexpr uint32_t kMaxSavedFilter = 4096;
static_assert(std::endian::native == std::endian::little, "saved films are little-endian");

void Put(std::string& out, const void* data, size_t size) { out.append(static_cast<const char*>(data), size); }
void PutU32(std::string& out, uint32_t value) { Put(out, &value, sizeof value); }

class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  void Get(void* data, size_t size) {
    if (size > bytes_.size() - offset_) throw Error("saved film is truncated");
    if (size == 0) return;  // `data` may be an empty vector's null pointer
    std::memcpy(data, bytes_.data() + offset_, size);
    offset_ += size;
  }
  uint32_t U32() {
    uint32_t value;
    Get(&value, sizeof value);
    return value;
  }
  std::string_view Take(size_t size) {
    if (size > bytes_.size() - offset_) throw Error("saved film is truncated");
    offset_ += size;
    return bytes_.substr(offset_ - size, size);
  }
  size_t Left() const { return bytes_.size() - offset_; }

 private:
  std::string_view bytes_;
  size_t offset_ = 0;
};

}  // namespace

std::string Film::Save() const {
  std::string out;
  const std::string filter = filter_spec_.SerializeAsString();
  const bool splats = !splats_.pass.empty();
  out.reserve(64 + filter.size() + pixels_.size() * sizeof(Pixel) + (splats ? 9 * pixels_.size() * sizeof(double) : 0));
  Put(out, kFilmMagic, sizeof kFilmMagic);
  for (uint32_t value :
       {kFilmVersion, width_, height_, passes_, splats_.passes, uint32_t(splats), uint32_t(filter.size())})
    PutU32(out, value);
  out += filter;
  static_assert(sizeof(Pixel) == 11 * sizeof(double));
  Put(out, pixels_.data(), pixels_.size() * sizeof(Pixel));
  if (splats)
    for (const std::vector<double>* image : {&splats_.pass, &splats_.sum, &splats_.sum_sq})
      Put(out, image->data(), image->size() * sizeof(double));
  return out;
}

Film Film::Load(std::string_view bytes) {
  Reader in(bytes);
  char magic[sizeof kFilmMagic];
  in.Get(magic, sizeof magic);
  if (std::memcmp(magic, kFilmMagic, sizeof magic) != 0) throw Error("not a saved film");
  if (const uint32_t version = in.U32(); version != kFilmVersion)
    throw Error("saved film has format version " + std::to_string(version) + ", not " + std::to_string(kFilmVersion));
  const uint32_t width = in.U32(), height = in.U32(), passes = in.U32(), splat_passes = in.U32();
  const uint32_t splats = in.U32(), filter_size = in.U32();
  // A saved filter is a few bytes; a large size would overflow the int below.
  if (filter_size > kMaxSavedFilter)
    throw Error("saved film has a filter of " + std::to_string(filter_size) + " bytes");
  v1::ReconstructionFilter filter;
  if (!filter.ParseFromArray(in.Take(filter_size).data(), int(filter_size)))
    throw Error("saved film has an unreadable filter");
  // Pixels() reads the splat sums whenever there are splat passes: a film
  // without splat images has none, and none has more than its passes.
  if (splat_passes > passes || (!splats && splat_passes != 0))
    throw Error("saved film has " + std::to_string(splat_passes) + " splat passes of " + std::to_string(passes) +
                " passes" + (splats ? "" : " and no splat images"));
  if (height != 0 && width > in.Left() / sizeof(Pixel) / height) throw Error("saved film is truncated");
  const size_t pixels = size_t(width) * height;
  const size_t expected = pixels * sizeof(Pixel) + (splats ? 3 * pixels * 3 * sizeof(double) : 0);
  if (splats > 1 || in.Left() != expected)
    throw Error("saved film of " + std::to_string(width) + "x" + std::to_string(height) + " pixels has " +
                std::to_string(in.Left()) + " bytes of data, not " + std::to_string(expected));
  // The filter throws Error for a kind or radius out of range.
  Film film(width, height, filter);
  in.Get(film.pixels_.data(), pixels * sizeof(Pixel));
  if (splats)
    for (std::vector<double>* image : {&film.splats_.pass, &film.splats_.sum, &film.splats_.sum_sq}) {
      image->resize(pixels * 3);
      in.Get(image->data(), image->size() * sizeof(double));
    }
  film.passes_ = passes;
  film.splats_.passes = splat_passes;
  return film;
}

}  // namespace yarf
