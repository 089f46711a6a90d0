// Light transport as integration (ARCHITECTURE, "Rendering is
// integration"): a Transport is a batch Function from points of primary
// sample space to film contributions; the kernel's SceneView is what it
// may ask of the scene; an Integrator feeds a RenderTarget with the results.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "yarf/component.h"
#include "yarf/geometry.h"
#include "yarf/medium.h"
#include "yarf/surface.h"
#include "yarf/surface_points.h"

namespace yarf {

// N points of [0,1)^d. Coordinates 0 and 1 place the sample on the film
// (x to the right, y down, over the whole image), 2 and 3 on the lens, 4 in
// the shutter interval; 5 is unused, so that the transport's own
// coordinates, from 6 on, come in the pairs (2k, 2k+1) that samplers
// stratify jointly. Produced lazily in process.
inline constexpr uint32_t kFilmDimension = 0, kLensDimension = 2, kTimeDimension = 4,
                           kTransportDimension = 6;

class PrimarySamples {
 public:
  virtual ~PrimarySamples() = default;
  virtual size_t Count() const = 0;
  virtual float Get(size_t i, uint32_t dimension) const = 0;
  // Coordinate `dimension` of each of `points`, into out (as long): what a
  // wavefront transport asks for a whole batch at once; by default, Get
  // per point.
  virtual void Gather(std::span<const uint32_t> points, uint32_t dimension, std::span<float> out) const {
    for (size_t k = 0; k < points.size(); ++k) out[k] = Get(points[k], dimension);
  }
  // Which sample of its pixel point i is (0, 1, 2... in the order of the
  // sample passes), for progressive methods whose estimate changes from
  // pass to pass; 0 when the points are not in passes.
  virtual uint64_t SampleIndex(size_t i) const { return 0; }
};

// Film contributions of a batch: raster positions in pixels, RGB
// radiance, and the point of the batch each came from (so that an
// integrator can weight it, e.g. by its map's Jacobian).
//
// Camera samples (the default) estimate the radiance at their position:
// the film averages them per pixel under its filter. Splats (`splats`
// set; methods that start paths at the lights) are summed instead, each
// spread by the normalised filter and the sum divided by the number of
// passes: one pass of W×H points must give each pixel's value once.
struct FilmSamples {
  std::vector<float> xy;
  std::vector<Vec3> rgb;
  std::vector<uint32_t> point;
  bool splats = false;

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

// A point on a light, to start a light path (SampleLight).
struct LightSample {
  Vec3 position;
  // A surface's normal there; a point light's axis (+z of its frame). The
  // emitter's local frame is Frame(normal), but for lights at infinity.
  Vec3 normal;
  // Density of the choice: per unit area on a surface; for a point light
  // (delta_position), the probability of choosing it; for a light at
  // infinity, the probability of choosing it (its disk is chosen later).
  float pdf = 0;
  bool delta_position = false;
  // A light at infinity (constant, envmap, directional): light paths leave
  // it from a disk facing their direction (SceneView::InfiniteLightOrigin);
  // its emitter's local frame is `frame`.
  bool infinite = false;
  // A directional light: one direction only, frame.n.
  bool delta_direction = false;
  Frame frame{Vec3(0, 0, 1)};
  // nullptr when there was nothing to sample.
  const Emitter* emitter = nullptr;
  // The emitting shape and its surface parameters (surfaces only).
  uint32_t shape = kNoShape;
  float u = 0, v = 0;
};

// A light seen from a point p of the scene, for next-event estimation
// (SampleLightsFrom).
struct LightDirection {
  // nullptr when there was nothing to sample.
  const Emitter* emitter = nullptr;
  // Unit, world space, from p toward the light.
  Vec3 direction;
  // To the light's point; kInfinity for a light at infinity.
  float distance = 0;
  // Density per unit solid angle at p, the choice of the light included,
  // so that a light's contribution is always f·L·|cos|/pdf. A delta light
  // has none: for a point or spot light it is the probability of choosing
  // it times distance² (which turns intensity into irradiance at p), for a
  // directional light the probability alone.
  float pdf = 0;
  bool delta = false;
  // The direction the light travels toward p, in the emitter's local
  // frame: the `w` of Emitter::Radiance.
  Vec3 w;
  // Finite lights: the point and its normal (a point light's axis).
  Vec3 position, normal;
  // The emitting shape and its surface parameters (surfaces only).
  uint32_t shape = kNoShape;
  float u = 0, v = 0;
  bool AtInfinity() const { return !(distance < kInfinity); }
};

// The camera seen from a point of the scene, for paths from the lights.
struct CameraConnection {
  // The point of the lens the connection ends at, and the view axis.
  Vec3 lens_point;
  Vec3 axis;
  // Where the point appears on the film, in pixels.
  float raster_x = 0, raster_y = 0;
  // W = 1/(A cos³θ): radiance L leaving the point toward the lens, at
  // distance d and cosine cos_p to its surface, splats L·W·cos_p/d² (A is
  // the film's area on the plane at distance 1; θ the angle to the axis).
  // The same value is the density, per solid angle, of the camera's ray
  // directions over the whole film.
  float importance = 0;
};

// What a transport algorithm may ask of the scene of its job; its meshes'
// attributes answer the textures that read them. yarfd serves it, with
// Intersect, to transports in other processes: the small questions about
// the scene as a whole travel in Layout, the rest in batches.
class SceneView : public Intersector, public SurfaceAttributes {
 public:
  static constexpr const char* kInterface = "yarf.v1.SceneView";

  // Materials are numbered 0..MaterialCount()-1 so that a wavefront can
  // group queries by material and call each SurfaceModel once per batch.
  // rpc: Layout
  virtual uint32_t MaterialCount() const = 0;
  // rpc: Layout
  virtual const SurfaceModel& Material(uint32_t material) const = 0;
  // rpc: Layout
  virtual uint32_t MaterialOf(uint32_t shape) const = 0;
  // nullptr when the shape does not emit.
  // rpc: Layout
  virtual const Emitter* EmitterOf(uint32_t shape) const = 0;
  // Lights are the emitting shapes, the point and spot lights and the
  // lights at infinity (directional, and at most one environment:
  // constant or envmap). Each is chosen with a probability: by power, or
  // uniformly (Scene.light_sampler).
  // rpc: Layout
  virtual bool HasLights() const = 0;
  // A light chosen by u_choice, then a point on it uniform in area (u0,
  // u1), for paths that start at the lights. Lights at infinity leave
  // their point to InfiniteLightOrigin.
  // rpc: SampleLightPoints
  virtual LightSample SampleLight(float u_choice, float u0, float u1) const = 0;
  // The area density SampleLight has at any point of the emitting `shape`.
  virtual float LightPdfArea(uint32_t shape) const = 0;
  // Where a light path from a light at infinity travelling along world
  // direction d starts: a point (u0, u1) of the disk of the scene's
  // bounding sphere facing d, and the disk's area density.
  // rpc: InfiniteLightOrigins
  virtual Vec3 InfiniteLightOrigin(Vec3 d, float u0, float u1, float& pdf_area) const = 0;
  // For each point p: a light chosen by uniform[3k] and a direction
  // toward it from p (uniform[3k+1], uniform[3k+2]): spheres by the solid
  // angle they subtend, triangles by area, an environment by its own
  // SampleDirection. Batched, as an environment's emitter is called once
  // for the whole batch. Every element of `out` is written (emitter
  // nullptr where nothing was sampled), whatever it held.
  // rpc: SampleLights
  virtual void SampleLightsFrom(std::span<const Vec3> points, std::span<const float> uniform,
                                std::span<LightDirection> out) const = 0;
  // The solid-angle density SampleLightsFrom has, at the origin of `ray`,
  // for the emitting surface point `hit` the ray meets.
  // rpc: Emission
  virtual float LightPdfFrom(const Ray& ray, const Hit& hit) const = 0;
  // Rays that leave the scene along `directions` (world, unit): the
  // environment's radiance arriving back along each, and the density
  // SampleLightsFrom has for the direction; zero without an environment.
  // rpc: Layout
  virtual bool HasEnvironment() const = 0;
  // rpc: Emission
  virtual void Escaped(std::span<const Vec3> directions, std::span<Vec3> radiance,
                       std::span<float> pdf) const = 0;
  // Light `light` of LightCount() gathered into one point as seen from p,
  // for methods that want hard shadows, with pdf as SampleLightsFrom's for
  // a choice of probability 1: a mesh light's area-weighted centroid and
  // mean normal, as if it had its area there; a sphere's point facing p,
  // as if its cross-section πr² emitted there; point, spot and
  // directional lights as they are. An environment is not gathered: it
  // answers no emitter.
  // rpc: Layout
  virtual uint32_t LightCount() const = 0;
  // rpc: LightPoints
  virtual LightDirection LightPoint(uint32_t light, Vec3 seen_from) const = 0;
  // The time in the shutter interval for primary coordinate u.
  // rpc: ShutterTimes
  virtual float ShutterTime(float u) const = 0;
  // The camera ray through film position (x, y) ∈ [0,1)² and lens (u, v)
  // at `time`.
  // rpc: CameraRays
  virtual Ray CameraRay(float film_x, float film_y, float lens_u, float lens_v, float time) const = 0;
  // The camera seen from p through lens position (u, v): false when p is
  // off the film, behind the camera or outside its clip range.
  virtual bool ConnectToCamera(Vec3 p, float lens_u, float lens_v, CameraConnection& out) const = 0;
  // How far one film sample's step moves a point p of a surface with
  // normal n, seen from the camera: dp/dx, dp/dy on its tangent plane, for
  // texture footprints at any depth of a path (pbrt-v4's approximation: a
  // pixel's step at p's distance and angle, shrunk for many samples per
  // pixel). Zero when unknown or the plane is seen edge-on.
  virtual void SampleSpacing(Vec3 p, Vec3 n, Vec3& dpdx, Vec3& dpdy) const { dpdx = dpdy = Vec3(); }
  // Whether anything reads texture footprints (SurfaceSite::footprint):
  // the scene has textures, or materials in other processes, which may
  // filter their own. When not, transports may leave them zero.
  // in-process only: it spares ShadingPoint work; a transport in another
  // process asks SampleSpacing where it wants a footprint.
  virtual bool FootprintsRead() const { return true; }
  // Whether anything reads the positions of points on surfaces without a
  // parameterisation (SurfaceSite::positioned): a solid texture, or a
  // texture or material in another process.
  // in-process only: it spares ShadingPoint work; a transport in another
  // process knows its points' positions.
  virtual bool PositionsRead() const { return true; }
  // Whether the lens has area (thin lens) or is a point (pinhole).
  // rpc: Layout
  virtual bool CameraHasLens() const = 0;
  // Whether camera rays depend on the lens coordinates (a thin lens, an
  // irradiance meter), and on the time coordinate (an open shutter): CameraRayOf
  // leaves those they ignore undrawn.
  // in-process only: it spares the sampler a pair per camera ray; a
  // transport in another process draws them all.
  virtual bool CameraReadsLens() const { return true; }
  // in-process only: as CameraReadsLens.
  virtual bool CameraReadsTime() const { return true; }
  // Why light paths cannot reach the camera (an orthographic camera's
  // rays are parallel; a radiance or irradiance meter has no lens and film
  // to land on), empty when they can: ConnectToCamera never succeeds then,
  // and methods that connect light paths to the camera cannot render.
  // rpc: Layout
  virtual std::string_view CameraUnreachableReason() const = 0;
  // Density per solid angle of camera ray directions over the whole
  // film, 1/(A cos³θ) (CameraConnection::importance), 0 off the film.
  virtual float CameraDirectionPdf(Vec3 direction) const = 0;
  // rpc: Layout
  virtual uint32_t FilmWidth() const = 0;
  // rpc: Layout
  virtual uint32_t FilmHeight() const = 0;
  // The scene's surfaces as triangles, for methods that mesh them
  // (radiosity): shapes 0..ShapeCount()-1 (Hit::shape numbers them), each
  // of PrimitiveCount(shape) primitives; Triangle gives a primitive's
  // corners in world space (at shutter open), false for a sphere.
  // rpc: Layout
  virtual uint32_t ShapeCount() const = 0;
  // rpc: Layout
  virtual uint32_t PrimitiveCount(uint32_t shape) const = 0;
  // rpc: Triangles
  virtual bool Triangle(uint32_t shape, uint32_t primitive, Vec3 corners[3]) const = 0;
  // Participating media (Scene.media), numbered 0..MediumCount()-1;
  // kNoMedium is vacuum. Methods that know media follow a ray from the
  // camera's medium through the boundaries it crosses (MediaOf).
  // rpc: Layout
  virtual uint32_t MediumCount() const { return 0; }
  // rpc: Layout
  virtual const Medium& MediumAt(uint32_t medium) const = 0;
  // rpc: Layout
  virtual MediumInterface MediaOf(uint32_t shape) const { return {}; }
  // rpc: Layout
  virtual uint32_t CameraMedium() const { return kNoMedium; }
  // The handle under which the server's SceneView and Intersect services
  // serve this scene to out-of-process transports; 0 when not served.
  // in-process only: on the wire it is the handle every call names.
  virtual uint64_t ServiceHandle() const { return 0; }
  // SurfaceAttributes: none, unless the scene keeps them.
  // in-process only: the materials Layout names read them in yarfd.
  void Attribute(std::string_view, std::span<const SurfaceLocation>, std::span<float> rgb) const override {
    std::fill(rgb.begin(), rgb.end(), 0.0f);
  }
};

class Transport : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Transport";

  // Once per job before any Evaluate (photon shooting, cache building...).
  virtual void Prepare(const SceneView&) {}
  // Number of primary-sample dimensions one sample may use.
  virtual uint32_t Dimensions() const = 0;
  // Appends the film contributions of every point to `out`.
  virtual void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) = 0;
};

// The job side of rendering: the film, progress and cancellation.
// Pixels [x0, x1) × [y0, y1) of the film.
struct PixelWindow {
  uint32_t x0, y0, x1, y1;
};

class RenderTarget {
 public:
  virtual ~RenderTarget() = default;
  virtual uint32_t SamplesPerPixel() const = 0;
  // The first sample index to render (a share of a job on a render node,
  // or the pass after a checkpoint): samples FirstSample()..SamplesPerPixel()-1.
  virtual uint32_t FirstSample() const { return 0; }
  // The pixels to render; the whole film when empty.
  virtual std::optional<PixelWindow> Crop() const { return std::nullopt; }
  virtual uint64_t Seed() const = 0;
  virtual bool Cancelled() const = 0;
  // Adds a batch of film contributions; safe to call from many threads.
  virtual void Accumulate(const FilmSamples& samples) = 0;
  // Every pixel has `samples_done` samples now.
  virtual void PassDone(uint32_t samples_done) = 0;

  // For integrators that estimate whole pixels themselves instead of
  // adding camera samples (a numerical integrator in another process,
  // tile by tile). How far the film's reconstruction filter reaches from
  // a pixel's centre, in pixels along each axis...
  virtual float FilterRadius() const = 0;
  // ...and the weight radiance at raster position (x, y) has in pixel
  // (px, py)'s value: the filter around the pixel's centre over its mass
  // on the film, so that a pixel's weights integrate to 1 over the film
  // and ∫ L·weight is the value its camera samples converge to. Safe to
  // call from many threads.
  virtual float PixelWeight(uint32_t px, uint32_t py, float x, float y) const = 0;
  // Estimates of the pixels of `window`, row by row, each from `samples`
  // samples per pixel, with the variance of each estimate: the film shows
  // them as they are (estimates of a pixel average by their samples).
  // Safe to call from many threads.
  virtual void AddPixelEstimates(const PixelWindow& window, uint32_t samples, std::span<const Vec3> values,
                                 std::span<const Vec3> variances) = 0;
};

}  // namespace yarf
