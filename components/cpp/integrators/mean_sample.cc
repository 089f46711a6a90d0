// mean_sample — the mean-sample Monte Carlo integrator.
//
// Integrate: ∫ f over a box ≈ volume · (1/N) Σ f(x_i), with the points x_i
// drawn from the job's sampler (so with a low-discrepancy sampler this is
// quasi-Monte Carlo); the standard error is volume · s / √N.
//
// Render: for each pixel and each sample index s < spp, the sampler's
// point number s (seeded per pixel) places the sample inside the pixel
// (coordinates 0, 1) and drives the transport (the rest). Pixels go in
// 32×32 tiles, one sample pass over all tiles at a time, tiles in
// parallel; progress is reported and cancellation checked per tile.
//
// Parameters: MeanSampleIntegrator::Parameters() below. More samples per
// pass make larger batches and fewer calls, which matters when the
// transport or its surface models live in other processes; progress is
// reported per pass.

#include <cmath>
#include <vector>

#include "image_passes.h"
#include "integration_box.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

class MeanSampleIntegrator final : public Integrator {
 public:
  // Passes from any first sample, over any crop, with the same seeds per sample.
  static std::vector<std::string> Capabilities() { return {kSamplePassesCapability}; }
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("tile_size").Default(32).Range(1, 1024).Doc("side in pixels of the tiles rendered in parallel"),
        P::Int("samples_per_pass")
            .Default(1)
            .Range(1, 1024)
            .Doc("samples per pixel each tile's batch carries (tile_size² × samples_per_pass at most 262144)"),
    };
  }

  explicit MeanSampleIntegrator(const Properties& props)
      : tile_size_(uint32_t(props.Int("tile_size", 32))),
        samples_per_pass_(uint32_t(props.Int("samples_per_pass", 1))) {
    if (tile_size_ < 1 || tile_size_ > 1024) throw Error("property 'tile_size' must be in [1, 1024]");
    if (samples_per_pass_ < 1 || samples_per_pass_ > 1024)
      throw Error("property 'samples_per_pass' must be in [1, 1024]");
    // A batch's points each hold a path's state in the transport.
    const uint64_t batch = uint64_t(tile_size_) * tile_size_ * samples_per_pass_;
    if (batch > kMaxBatch)
      throw Error("tile_size² × samples_per_pass is " + std::to_string(batch) + " points a batch, above " +
                  std::to_string(kMaxBatch));
  }
  static constexpr uint64_t kMaxBatch = uint64_t(1) << 18;

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckBoxDimensions(lower, upper, d);
    CheckFiniteBounds(lower, upper);
    if (evaluations < 2) throw Error("need at least 2 evaluations");
    // Negative when lower > upper in an odd number of dimensions: the
    // signed integral, as vegas gives it; its error is positive.
    const double volume = BoxVolume(lower, upper);
    std::vector<double> sum(k, 0.0), sum_sq(k, 0.0);
    constexpr uint64_t kBatch = 4096;
    std::vector<float> points, values;
    for (uint64_t first = 0; first < evaluations; first += kBatch) {
      const uint32_t n = uint32_t(std::min(kBatch, evaluations - first));
      points.resize(size_t(n) * d);
      values.resize(size_t(n) * k);
      sampler.Generate(first, n, d, seed, points);
      MapToBox(points, lower, upper);
      f.Evaluate(points, values);
      for (uint32_t i = 0; i < n; ++i)
        for (uint32_t c = 0; c < k; ++c) {
          const double v = values[size_t(i) * k + c];
          sum[c] += v;
          sum_sq[c] += v * v;
        }
    }
    IntegrationResult result;
    result.evaluations = evaluations;
    const double n = double(evaluations);
    for (uint32_t c = 0; c < k; ++c) {
      const double mean = sum[c] / n;
      const double var = std::max(0.0, (sum_sq[c] / n - mean * mean) * n / (n - 1));
      result.estimate.push_back(volume * mean);
      result.standard_error.push_back(std::abs(volume) * std::sqrt(var / n));
    }
    return result;
  }

  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
              RenderTarget& target) override {
    RenderPasses(
        scene, target, tile_size_, samples_per_pass_,
        [&](uint32_t first, uint32_t samples, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1,
            FilmSamples& out) {
          TilePoints points(sampler, first, scene.FilmWidth(), scene.FilmHeight(), target.SamplesPerPixel(),
                            samples);
          points.Reset(x0, y0, x1, y1, target.Seed());
          transport.Evaluate(scene, points, out);
          target.Accumulate(out);
        },
        [](uint32_t) {});
  }

 private:
  uint32_t tile_size_;
  uint32_t samples_per_pass_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::MeanSampleIntegrator>(registrar, "mean_sample", "1.0.0",
                                             "mean-sample Monte Carlo integration");
}
