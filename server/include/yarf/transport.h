// Light transport as integration (ARCHITECTURE, "Rendering is
// integration"): a Transport is a batch Function from points of primary
// sample space to film contributions; the kernel's SceneView is what it
// may ask of the scene; an Integrator feeds a RenderTarget with the results.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "yarf/component.h"
#include "yarf/geometry.h"
#include "yarf/surface.h"

namespace yarf {

// N points of [0,1)^d. Coordinates 0 and 1 place the sample on the film
// (x to the right, y down, over the whole image), 2 and 3 on the lens; the
// rest belong to the transport. Produced lazily in process.
class PrimarySamples {
 public:
  virtual ~PrimarySamples() = default;
  virtual size_t Count() const = 0;
  virtual float Get(size_t i, uint32_t dimension) const = 0;
};

// Film contributions of a batch: raster positions in pixels, RGB
// radiance, and the point of the batch each came from (so that an
// integrator can weight it, e.g. by its map's Jacobian).
struct FilmSamples {
  std::vector<float> xy;
  std::vector<Vec3> rgb;
  std::vector<uint32_t> point;

  void Clear() {
    xy.clear();
    rgb.clear();
    point.clear();
  }
  void Add(uint32_t from_point, float x, float y, Vec3 value) {
    xy.push_back(x);
    xy.push_back(y);
    rgb.push_back(value);
    point.push_back(from_point);
  }
  size_t Count() const { return rgb.size(); }
};

struct EmitterSample {
  Vec3 position;
  Vec3 normal;
  // Density with respect to area, 1/unit².
  float pdf_area = 0;
  uint32_t shape = kNoShape;
  float u = 0, v = 0;
};

// What a transport algorithm may ask of the scene of its job.
class SceneView : public Intersector {
 public:
  // Materials are numbered 0..MaterialCount()-1 so that a wavefront can
  // group queries by material and call each SurfaceModel once per batch.
  virtual uint32_t MaterialCount() const = 0;
  virtual const SurfaceModel& Material(uint32_t material) const = 0;
  virtual uint32_t MaterialOf(uint32_t shape) const = 0;
  // nullptr when the shape does not emit.
  virtual const Emitter* EmitterOf(uint32_t shape) const = 0;
  virtual bool HasEmitters() const = 0;
  // A point on the emitting surfaces, uniform in area.
  virtual EmitterSample SampleEmitter(float u0, float u1, float u2) const = 0;
  // The area density SampleEmitter has at any point of `shape`.
  virtual float EmitterPdfArea(uint32_t shape) const = 0;
  // The camera ray through film position (x, y) ∈ [0,1)² and lens (u, v).
  virtual Ray CameraRay(float film_x, float film_y, float lens_u, float lens_v) const = 0;
  virtual uint32_t FilmWidth() const = 0;
  virtual uint32_t FilmHeight() const = 0;
};

class Transport : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Transport";
  static constexpr const char* kMethods[] = {"Prepare", "Evaluate"};

  // Once per job before any Evaluate (photon shooting, cache building...).
  virtual void Prepare(const SceneView&) {}
  // Number of primary-sample dimensions one sample may use.
  virtual uint32_t Dimensions() const = 0;
  // Appends the film contributions of every point to `out`.
  virtual void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) = 0;
};

// The job side of rendering: the film, progress and cancellation.
class RenderTarget {
 public:
  virtual ~RenderTarget() = default;
  virtual uint32_t SamplesPerPixel() const = 0;
  virtual uint64_t Seed() const = 0;
  virtual bool Cancelled() const = 0;
  // Adds a batch of film contributions; safe to call from many threads.
  virtual void Accumulate(const FilmSamples& samples) = 0;
  // Every pixel has `samples_done` samples now.
  virtual void PassDone(uint32_t samples_done) = 0;
};

}  // namespace yarf
