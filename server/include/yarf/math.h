// Numerical interfaces, mirroring proto/yarf/v1/math.proto (component.h
// says how a method names its rpc). Batches are row-major float arrays, as
// on the wire.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "yarf/component.h"
#include "yarf/error.h"
#include "yarf/support/hash.h"

namespace yarf {

// f: R^d -> R^k on batches.
class Function : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Function";

  // d, which the Signature rpc answers together with k.
  // rpc: Signature
  virtual uint32_t InputDimensions() const = 0;
  // k.
  // rpc: Signature
  virtual uint32_t OutputDimensions() const = 0;
  // points: [N, d]; values: [N, k]. EvaluateStream is the same calls on
  // one stream.
  // rpc: Evaluate, EvaluateStream
  virtual void Evaluate(std::span<const float> points, std::span<float> values) = 0;
};

struct IntegrationResult {
  std::vector<double> estimate;
  std::vector<double> standard_error;
  uint64_t evaluations = 0;
  // For integrators that average iterations (vegas, vegas_plus), per
  // output: χ²/dof of the iterations kept about their weighted average
  // (dof = iterations kept − 1), and Q, the probability that a χ² of that
  // many degrees of freedom is at least as large. Q < 0.05 says the
  // iterations disagree beyond their errors, so the error is not to be
  // trusted. NaN with a single iteration kept; empty for one-shot methods.
  std::vector<double> chi2_per_dof;
  std::vector<double> q;
};

class Sampler;
class Transport;
class SceneView;
class RenderTarget;

class Integrator : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Integrator";

  // ∫ f over the box [lower, upper] with about `evaluations` points.
  virtual IntegrationResult Integrate(Function& f, std::span<const double> lower,
                                      std::span<const double> upper, uint64_t evaluations,
                                      uint64_t seed, const Sampler& sampler) = 0;
  // The image mode: integrates a transport algorithm's Function over each
  // pixel's footprint, feeding the target's film pass after pass. An
  // integrator without one says so when a job names it.
  // in-process only: a render runs in yarfd, on the job's scene and film,
  // and is asked for through RenderService.Submit; an integrator in
  // another process renders through Integrate, tile by tile
  // (Remote<Integrator>::Render).
  virtual void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
                      RenderTarget& target) {
    throw Error("integrator '" + Describe().class_name + "' does not render images");
  }
};

// Point sets in [0,1)^d, addressed statelessly so that any coordinate of
// any point can be produced lazily (a path that ends early costs nothing)
// and reproducibly whatever thread asks.
class Sampler : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Sampler";

  // Coordinate `dimension` of point `index` of the sequence for `seed`.
  // in-process only: the wire carries whole points (Generate), from which
  // Remote<Sampler> answers it.
  virtual float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const = 0;
  // Where sample `sample` of pixel (x, y) of a width × height film, of
  // samples_per_pixel in all, lies among the sampler's points: the index
  // and seed Sample takes. By default every pixel has a sequence of its
  // own (the sample's number, and a seed hashed from the job's and the
  // pixel); a sampler of one sequence over the whole film (zsobol) places
  // the pixel's samples in it.
  struct FilmPoint {
    uint64_t index, seed;
  };
  // in-process only: yarfd's render loop places the film's samples; a
  // remote sampler keeps the default.
  virtual FilmPoint AtPixel(uint32_t x, uint32_t y, uint32_t width, uint32_t height, uint64_t sample,
                            uint32_t samples_per_pixel, uint64_t seed) const {
    return {sample, Hash(seed, uint64_t(y) * width + x)};
  }
  // Coordinates 2·pair and 2·pair + 1 of point indices[k] of the sequence
  // for seeds[k], as out[2k] and out[2k + 1]: Sample's values, for many
  // points in one call (a wavefront asks for one dimension of every live
  // path at once). A sampler that makes a pair faster together overrides it.
  // in-process only: Sample's batched form for the wavefront; a remote
  // sampler keeps the default, which calls Sample.
  virtual void SamplePairs(std::span<const uint64_t> indices, std::span<const uint64_t> seeds, uint32_t pair,
                           std::span<float> out) const {
    for (size_t k = 0; k < indices.size(); ++k) {
      out[2 * k] = Sample(indices[k], 2 * pair, seeds[k]);
      out[2 * k + 1] = Sample(indices[k], 2 * pair + 1, seeds[k]);
    }
  }
  // Points first .. first+count-1 as [count, dimensions].
  virtual void Generate(uint64_t first, uint32_t count, uint32_t dimensions, uint64_t seed,
                        std::span<float> out) const {
    for (uint32_t i = 0; i < count; ++i)
      for (uint32_t d = 0; d < dimensions; ++d)
        out[size_t(i) * dimensions + d] = Sample(first + i, d, seed);
  }
};

class Generator : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Generator";

  // out.size() uniform numbers of stream `stream` after skipping `offset`.
  virtual void Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) = 0;
};

struct RootResult {
  double root = 0;
  uint32_t iterations = 0;
};

class RootFinder : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.RootFinder";

  // Throws Error when [lower, upper] brackets no root or it does not converge.
  virtual RootResult FindRoot(Function& f, double lower, double upper, double tolerance,
                              uint32_t max_iterations) = 0;
};

class Warp : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Warp";

  // m, which the Signature rpc answers together with n.
  // rpc: Signature
  virtual uint32_t DomainDimensions() const = 0;
  // n.
  // rpc: Signature
  virtual uint32_t ImageDimensions() const = 0;
  // uniform [N, m] -> points [N, n], pdf [N].
  virtual void Forward(std::span<const float> uniform, std::span<float> points,
                       std::span<float> pdf) const = 0;
  // points [N, n] -> uniform [N, m], pdf [N]. Throws Error when not invertible.
  virtual void Inverse(std::span<const float> points, std::span<float> uniform,
                       std::span<float> pdf) const = 0;
  virtual void Pdf(std::span<const float> points, std::span<float> pdf) const = 0;
};

}  // namespace yarf
