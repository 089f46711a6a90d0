#include "service/job_scene_service.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "components/array_codec.h"
#include "yarf/error.h"
#include "yarf/vecmath.h"

namespace yarf {
namespace {

// Largest batch one call may carry, in rays.
constexpr uint32_t kMaxRays = 1u << 22;
// CrossSection stops after this many hits along one ray.
constexpr uint32_t kMaxCrossings = 256;

// Runs `call` on the served scene `handle`; maps an unknown handle and bad
// input to gRPC statuses.
template <typename Call>
grpc::Status WithScene(const JobScenes& scenes, uint64_t handle, Call&& call) {
  std::shared_ptr<const ServedScene> served = scenes.Find(handle);
  if (!served) return {grpc::StatusCode::NOT_FOUND, "no running job's scene has handle " + std::to_string(handle)};
  try {
    call(*served);
    return grpc::Status::OK;
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  }
}

void CheckRows(uint32_t n) {
  if (n > kMaxRays) throw Error("batch of " + std::to_string(n) + " rays exceeds " + std::to_string(kMaxRays));
}

std::vector<Ray> RaysOf(const v1::RayBatch& batch) {
  BatchDecoder decoder;
  const auto origins = decoder.Floats(batch.origins(), {3}, "origins");
  const auto directions = decoder.Floats(batch.directions(), {3}, "directions");
  const uint32_t n = decoder.rows();
  CheckRows(n);
  const bool has_intervals = batch.has_intervals(), has_times = batch.has_times();
  const auto intervals = has_intervals ? decoder.Floats(batch.intervals(), {2}, "intervals") : std::vector<float>{};
  const auto times = has_times ? decoder.Floats(batch.times(), {}, "times") : std::vector<float>{};
  std::vector<Ray> rays(n);
  for (uint32_t i = 0; i < n; ++i) {
    Ray& r = rays[i];
    r.origin = Vec3::Load(&origins[3 * i]);
    r.direction = Vec3::Load(&directions[3 * i]);
    const float length = Length(r.direction);
    if (!std::isfinite(length) || length == 0 || !std::isfinite(r.origin.x + r.origin.y + r.origin.z))
      throw Error("ray " + std::to_string(i) + " has a non-finite origin or a zero direction");
    r.direction = r.direction / length;
    if (has_intervals) {
      r.tnear = intervals[2 * i];
      r.tfar = intervals[2 * i + 1];
    }
    if (has_times) r.time = std::clamp(times[i], 0.0f, 1.0f);
  }
  return rays;
}

void FillHits(const std::vector<Hit>& hits, v1::IntersectReply* reply) {
  const uint32_t n = uint32_t(hits.size());
  std::vector<float> t(n), normals(3 * n), uv(2 * n);
  std::vector<uint32_t> shapes(n), primitives(n);
  for (uint32_t i = 0; i < n; ++i) {
    t[i] = hits[i].t;
    hits[i].normal.Store(&normals[3 * i]);
    uv[2 * i] = hits[i].u;
    uv[2 * i + 1] = hits[i].v;
    shapes[i] = hits[i].shape;
    primitives[i] = hits[i].primitive;
  }
  *reply->mutable_t() = FloatArray(t, {n});
  *reply->mutable_normals() = FloatArray(normals, {n, 3});
  *reply->mutable_uv() = FloatArray(uv, {n, 2});
  *reply->mutable_shape_ids() = Uint32Array(shapes, {n});
  *reply->mutable_primitive_ids() = Uint32Array(primitives, {n});
}

// Rows of `columns` numbers in [0,1), as a sampler's uniform numbers must be.
void CheckUniform(const std::vector<float>& u, size_t columns, const std::string& what) {
  for (size_t i = 0; i < u.size(); ++i)
    if (!(u[i] >= 0 && u[i] < 1)) throw Error(what + " " + std::to_string(i / columns) + " is not in [0, 1)");
}

std::vector<Vec3> PointsOf(const std::vector<float>& xyz, const std::string& what) {
  std::vector<Vec3> points(xyz.size() / 3);
  for (size_t k = 0; k < points.size(); ++k) {
    points[k] = Vec3::Load(&xyz[3 * k]);
    if (!std::isfinite(points[k].x + points[k].y + points[k].z))
      throw Error(what + " " + std::to_string(k) + " is not finite");
  }
  return points;
}

// Directions, made unit; a zero or non-finite one is refused.
std::vector<Vec3> UnitVectorsOf(const std::vector<float>& xyz, const std::string& what) {
  std::vector<Vec3> vectors = PointsOf(xyz, what);
  for (size_t k = 0; k < vectors.size(); ++k) {
    const float length = Length(vectors[k]);
    if (!(length > 0) || !std::isfinite(length)) throw Error(what + " " + std::to_string(k) + " has no direction");
    vectors[k] = vectors[k] / length;
  }
  return vectors;
}

// `shape` (of request row `row`), when the scene has it.
uint32_t CheckedShape(const ServedScene& served, uint32_t shape, uint32_t row) {
  if (shape >= served.scene().ShapeCount())
    throw Error("shape " + std::to_string(shape) + " (row " + std::to_string(row) + ") is not one of the scene's " +
                std::to_string(served.scene().ShapeCount()) + " shapes");
  return shape;
}

// The surface a sampling request names; a shape without area has no
// density to sample by.
const ShapeSurface& SampledSurface(const ServedScene& served, uint32_t shape) {
  const ShapeSurface& surface = served.Surface(shape);
  if (!(surface.Area() > 0)) throw Error("shape " + std::to_string(shape) + " has no area to sample");
  return surface;
}

void FillSurfaceSamples(const std::vector<SurfaceSample>& samples, v1::SurfaceSampleReply* reply) {
  const uint32_t n = uint32_t(samples.size());
  std::vector<float> positions(3 * n), normals(3 * n), pdf(n), uv(2 * n);
  std::vector<uint32_t> primitives(n);
  for (uint32_t k = 0; k < n; ++k) {
    const SurfaceSample& s = samples[k];
    s.position.Store(&positions[3 * k]);
    s.normal.Store(&normals[3 * k]);
    pdf[k] = std::isfinite(s.pdf) ? s.pdf : 0.0f;
    uv[2 * k] = s.u, uv[2 * k + 1] = s.v;
    primitives[k] = s.primitive;
  }
  *reply->mutable_positions() = FloatArray(positions, {n, 3});
  *reply->mutable_normals() = FloatArray(normals, {n, 3});
  *reply->mutable_pdf() = FloatArray(pdf, {n});
  *reply->mutable_uv() = FloatArray(uv, {n, 2});
  *reply->mutable_primitive_ids() = Uint32Array(primitives, {n});
}

// Radiance of emitters toward local directions, one call per emitter.
void EmitterRadiance(const std::vector<const Emitter*>& emitters, const std::vector<float>& w,
                     const std::vector<float>& uv, std::vector<float>& radiance) {
  std::map<const Emitter*, std::vector<uint32_t>> groups;
  for (uint32_t i = 0; i < emitters.size(); ++i)
    if (emitters[i]) groups[emitters[i]].push_back(i);
  for (const auto& [emitter, members] : groups) {
    const size_t m = members.size();
    std::vector<float> gw(3 * m), guv(2 * m), le(3 * m);
    for (size_t j = 0; j < m; ++j) {
      std::copy_n(&w[3 * members[j]], 3, &gw[3 * j]);
      std::copy_n(&uv[2 * members[j]], 2, &guv[2 * j]);
    }
    emitter->Radiance(gw, SurfacePoints{.uv = guv}, le);
    for (size_t j = 0; j < m; ++j) std::copy_n(&le[3 * j], 3, &radiance[3 * members[j]]);
  }
}

// Lights seen from points (SampleLightsFrom, LightPoint) as the wire has
// them: the radiance arriving unoccluded and, for a point light, the
// choice's probability as the pdf and the irradiance it gives as the
// radiance.
void FillLightDirections(const ServedScene& served, const std::vector<LightDirection>& lights,
                         v1::SampleLightsReply* reply) {
  const uint32_t n = uint32_t(lights.size());
  std::vector<float> directions(3 * n), distances(n), radiance(3 * n), pdf(n), w(3 * n), uv(2 * n),
      positions(3 * n), normals(3 * n);
  std::vector<uint32_t> delta(n), emitter_indices(n, kNoEmitter), shapes(n, kNoShape);
  std::vector<const Emitter*> emitters(n, nullptr);
  for (uint32_t i = 0; i < n; ++i) {
    const LightDirection& s = lights[i];
    if (!s.emitter || !(s.pdf > 0) || !std::isfinite(s.pdf)) continue;
    s.direction.Store(&directions[3 * i]);
    distances[i] = s.distance;
    pdf[i] = s.pdf;
    delta[i] = s.delta;
    emitters[i] = s.emitter;
    emitter_indices[i] = served.EmitterIndex(s.emitter);
    s.w.Store(&w[3 * i]);
    uv[2 * i] = s.u;
    uv[2 * i + 1] = s.v;
    shapes[i] = s.shape;
    if (!s.AtInfinity()) {
      s.position.Store(&positions[3 * i]);
      s.normal.Store(&normals[3 * i]);
    }
  }
  EmitterRadiance(emitters, w, uv, radiance);
  for (uint32_t i = 0; i < n; ++i)
    if (delta[i] && !lights[i].AtInfinity()) {
      const float d2 = distances[i] * distances[i];
      for (int c = 0; c < 3; ++c) radiance[3 * i + c] /= d2;
      pdf[i] /= d2;
    }
  *reply->mutable_directions() = FloatArray(directions, {n, 3});
  *reply->mutable_distances() = FloatArray(distances, {n});
  *reply->mutable_radiance() = FloatArray(radiance, {n, 3});
  *reply->mutable_pdf() = FloatArray(pdf, {n});
  *reply->mutable_delta() = Uint32Array(delta, {n});
  *reply->mutable_emitters() = Uint32Array(emitter_indices, {n});
  *reply->mutable_positions() = FloatArray(positions, {n, 3});
  *reply->mutable_normals() = FloatArray(normals, {n, 3});
  *reply->mutable_shape_ids() = Uint32Array(shapes, {n});
  *reply->mutable_uv() = FloatArray(uv, {n, 2});
}

}  // namespace

grpc::Status IntersectServiceImpl::Intersect(grpc::ServerContext*, const v1::IntersectRequest* request,
                                             v1::IntersectReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const std::vector<Ray> rays = RaysOf(request->rays());
    std::vector<Hit> hits(rays.size());
    served.scene().Intersect(rays, hits);
    FillHits(hits, reply);
  });
}

grpc::Status IntersectServiceImpl::Occluded(grpc::ServerContext*, const v1::IntersectRequest* request,
                                            v1::OccludedReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const std::vector<Ray> rays = RaysOf(request->rays());
    std::vector<uint8_t> blocked(rays.size());
    served.scene().Occluded(rays, blocked);
    *reply->mutable_occluded() = Uint32Array(std::vector<uint32_t>(blocked.begin(), blocked.end()),
                                             {uint32_t(rays.size())});
  });
}

grpc::Status IntersectServiceImpl::CrossSection(grpc::ServerContext*, const v1::IntersectRequest* request,
                                                v1::CrossSectionReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    std::vector<Ray> rays = RaysOf(request->rays());
    const uint32_t n = uint32_t(rays.size());
    // Every crossing: trace on from just past each hit, in rounds.
    std::vector<std::vector<std::pair<float, uint32_t>>> crossings(n);
    std::vector<uint32_t> active(n);
    for (uint32_t i = 0; i < n; ++i) active[i] = i;
    for (uint32_t round = 0; round < kMaxCrossings && !active.empty(); ++round) {
      std::vector<Ray> batch;
      for (uint32_t i : active) batch.push_back(rays[i]);
      std::vector<Hit> hits(batch.size());
      served.scene().Intersect(batch, hits);
      std::vector<uint32_t> next;
      for (size_t k = 0; k < active.size(); ++k) {
        if (!hits[k].Found()) continue;
        Ray& ray = rays[active[k]];
        crossings[active[k]].push_back({hits[k].t, hits[k].shape});
        const Vec3 p = ray.origin + ray.direction * hits[k].t;
        ray.tnear = hits[k].t + SurfaceOffset(p);
        if (ray.tnear < ray.tfar) next.push_back(active[k]);
      }
      active = std::move(next);
    }
    std::vector<uint32_t> offsets{0}, shapes;
    std::vector<float> t;
    for (const auto& list : crossings) {
      for (const auto& [distance, shape] : list) {
        t.push_back(distance);
        shapes.push_back(shape);
      }
      offsets.push_back(uint32_t(t.size()));
    }
    v1::Array offsets_array = Uint32Array(offsets, {n + 1});
    offsets_array.set_dtype(v1::Array::INT32);
    *reply->mutable_offsets() = offsets_array;
    *reply->mutable_t() = FloatArray(t, {uint32_t(t.size())});
    *reply->mutable_shape_ids() = Uint32Array(shapes, {uint32_t(shapes.size())});
  });
}

grpc::Status ShapeServiceImpl::Bounds(grpc::ServerContext*, const v1::ShapeRequest* request,
                                      v1::BoundsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    Vec3 lower, upper;
    served.Surface(request->shape()).Bounds(lower, upper);
    for (auto [to, from] : {std::pair{reply->mutable_lower(), lower}, std::pair{reply->mutable_upper(), upper}}) {
      to->set_x(from.x);
      to->set_y(from.y);
      to->set_z(from.z);
    }
  });
}

grpc::Status ShapeServiceImpl::Area(grpc::ServerContext*, const v1::ShapeRequest* request, v1::AreaReply* reply) {
  return WithScene(scenes_, request->handle(),
                   [&](const ServedScene& served) { reply->set_area(served.Surface(request->shape()).Area()); });
}

grpc::Status SampleSurfaceAreaServiceImpl::Sample(grpc::ServerContext*, const v1::SurfaceSampleRequest* request,
                                                  v1::SurfaceSampleReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto u = batch.Floats(request->uniform(), {3}, "uniform");
    CheckRows(batch.rows());
    CheckUniform(u, 3, "uniform");
    std::vector<SurfaceSample> samples(batch.rows());
    SampledSurface(served, request->shape()).Sample(u, samples);
    FillSurfaceSamples(samples, reply);
  });
}

grpc::Status SampleSurfaceDirectionServiceImpl::Sample(grpc::ServerContext*, const v1::SurfaceSampleRequest* request,
                                                       v1::SurfaceSampleReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto u = batch.Floats(request->uniform(), {3}, "uniform");
    const auto from = PointsOf(batch.Floats(request->reference_points(), {3}, "reference_points"), "reference point");
    CheckRows(batch.rows());
    CheckUniform(u, 3, "uniform");
    std::vector<SurfaceSample> samples(batch.rows());
    SampledSurface(served, request->shape()).Sample(from, u, samples);
    FillSurfaceSamples(samples, reply);
  });
}

grpc::Status SampleSurfaceDirectionServiceImpl::Pdf(grpc::ServerContext*, const v1::SurfacePdfRequest* request,
                                                    v1::SurfacePdfReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto from = PointsOf(batch.Floats(request->reference_points(), {3}, "reference_points"), "reference point");
    const auto positions = PointsOf(batch.Floats(request->positions(), {3}, "positions"), "position");
    const auto primitives = batch.Uint32s(request->primitive_ids(), "primitive_ids");
    const uint32_t n = batch.rows();
    CheckRows(n);
    const ShapeSurface& surface = SampledSurface(served, request->shape());
    // The normal is the surface's own: the primitive gives it.
    std::vector<SurfaceSample> at(n);
    for (uint32_t k = 0; k < n; ++k) {
      at[k].position = positions[k];
      at[k].primitive = primitives[k];
    }
    std::vector<float> pdf(n);
    surface.Pdf(from, at, pdf);
    for (float& p : pdf)
      if (!std::isfinite(p)) p = 0;
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SceneViewServiceImpl::Layout(grpc::ServerContext*, const v1::SceneViewRequest* request,
                                          v1::SceneLayout* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const KernelScene& scene = served.scene();
    const ServedScene::Handles& handles = served.handles();
    reply->set_width(scene.FilmWidth());
    reply->set_height(scene.FilmHeight());
    for (uint32_t shape = 0; shape < scene.ShapeCount(); ++shape) {
      reply->add_material_handles(handles.materials[scene.MaterialOf(shape)]);
      reply->add_emits(scene.EmitterOf(shape) != nullptr);
      reply->add_shape_emitters(served.EmitterIndex(scene.EmitterOf(shape)));
      reply->add_primitive_counts(scene.PrimitiveCount(shape));
      const MediumInterface media = scene.MediaOf(shape);
      reply->add_media_boundaries(media.boundary);
      reply->add_interior_media(media.interior);
      reply->add_exterior_media(media.exterior);
    }
    reply->set_has_lights(scene.HasLights());
    reply->set_has_environment(scene.HasEnvironment());
    reply->set_light_count(scene.LightCount());
    for (uint64_t emitter : handles.emitters) reply->add_emitter_handles(emitter);
    reply->set_camera_has_lens(scene.CameraHasLens());
    reply->set_camera_unreachable_reason(std::string(scene.CameraUnreachableReason()));
    for (uint64_t medium : handles.media) reply->add_medium_handles(medium);
    reply->set_camera_medium(scene.CameraMedium());
  });
}

grpc::Status SceneViewServiceImpl::CameraRays(grpc::ServerContext*, const v1::CameraRaysRequest* request,
                                              v1::RayBatch* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    size_t rows = 0;
    const auto points = FloatsOf(request->points(), {5}, "points", rows);
    const uint32_t n = uint32_t(rows);
    CheckRows(n);
    CheckUniform(points, 5, "points");
    const KernelScene& scene = served.scene();
    std::vector<float> origins(3 * n), directions(3 * n), times(n);
    for (uint32_t i = 0; i < n; ++i) {
      const float* p = &points[5 * i];
      const float time = scene.ShutterTime(p[4]);
      const Ray ray = scene.CameraRay(p[0], p[1], p[2], p[3], time);
      ray.origin.Store(&origins[3 * i]);
      ray.direction.Store(&directions[3 * i]);
      times[i] = ray.time;
    }
    *reply->mutable_origins() = FloatArray(origins, {n, 3});
    *reply->mutable_directions() = FloatArray(directions, {n, 3});
    *reply->mutable_times() = FloatArray(times, {n});
  });
}

grpc::Status SceneViewServiceImpl::ShutterTimes(grpc::ServerContext*, const v1::ShutterTimesRequest* request,
                                                v1::ShutterTimesReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    size_t rows = 0;
    const auto u = FloatsOf(request->uniform(), {}, "uniform", rows);
    const uint32_t n = uint32_t(rows);
    CheckRows(n);
    CheckUniform(u, 1, "uniform");
    std::vector<float> times(n);
    for (uint32_t i = 0; i < n; ++i) times[i] = served.scene().ShutterTime(u[i]);
    *reply->mutable_times() = FloatArray(times, {n});
  });
}

grpc::Status SceneViewServiceImpl::SampleLights(grpc::ServerContext*, const v1::SampleLightsRequest* request,
                                                v1::SampleLightsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto u = batch.Floats(request->uniform(), {3}, "uniform");
    const auto from = PointsOf(batch.Floats(request->points(), {3}, "points"), "point");
    CheckRows(batch.rows());
    CheckUniform(u, 3, "uniform");
    std::vector<LightDirection> lights(batch.rows());
    if (served.scene().HasLights()) served.scene().SampleLightsFrom(from, u, lights);
    FillLightDirections(served, lights, reply);
  });
}

grpc::Status SceneViewServiceImpl::LightPoints(grpc::ServerContext*, const v1::LightPointsRequest* request,
                                               v1::SampleLightsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto lights = batch.Uint32s(request->lights(), "lights");
    const auto from = PointsOf(batch.Floats(request->points(), {3}, "points"), "point");
    CheckRows(batch.rows());
    const KernelScene& scene = served.scene();
    std::vector<LightDirection> gathered(batch.rows());
    for (uint32_t i = 0; i < gathered.size(); ++i) {
      if (lights[i] >= scene.LightCount())
        throw Error("light " + std::to_string(lights[i]) + " (row " + std::to_string(i) + ") is not one of the scene's " +
                    std::to_string(scene.LightCount()) + " lights");
      gathered[i] = scene.LightPoint(lights[i], from[i]);
    }
    FillLightDirections(served, gathered, reply);
  });
}

grpc::Status SceneViewServiceImpl::SampleLightPoints(grpc::ServerContext*, const v1::SampleLightPointsRequest* request,
                                                     v1::LightPointsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    size_t rows = 0;
    const auto u = FloatsOf(request->uniform(), {3}, "uniform", rows);
    const uint32_t n = uint32_t(rows);
    CheckRows(n);
    CheckUniform(u, 3, "uniform");
    const KernelScene& scene = served.scene();
    std::vector<float> positions(3 * n), normals(3 * n), pdf(n), frames(9 * n), uv(2 * n);
    std::vector<uint32_t> flags(n), emitters(n, kNoEmitter), shapes(n, kNoShape);
    for (uint32_t i = 0; i < n; ++i) {
      if (!scene.HasLights()) break;
      const LightSample l = scene.SampleLight(u[3 * i], u[3 * i + 1], u[3 * i + 2]);
      if (!l.emitter || !(l.pdf > 0) || !std::isfinite(l.pdf)) continue;
      if (!l.infinite) {
        l.position.Store(&positions[3 * i]);
        l.normal.Store(&normals[3 * i]);
      }
      pdf[i] = l.pdf;
      flags[i] = (l.delta_position ? 1u : 0u) | (l.infinite ? 2u : 0u) | (l.delta_direction ? 4u : 0u);
      const Frame frame = l.infinite ? l.frame : Frame(l.normal);
      frame.s.Store(&frames[9 * i]);
      frame.t.Store(&frames[9 * i + 3]);
      frame.n.Store(&frames[9 * i + 6]);
      emitters[i] = served.EmitterIndex(l.emitter);
      shapes[i] = l.shape;
      uv[2 * i] = l.u;
      uv[2 * i + 1] = l.v;
    }
    *reply->mutable_positions() = FloatArray(positions, {n, 3});
    *reply->mutable_normals() = FloatArray(normals, {n, 3});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
    *reply->mutable_flags() = Uint32Array(flags, {n});
    *reply->mutable_frames() = FloatArray(frames, {n, 3, 3});
    *reply->mutable_emitters() = Uint32Array(emitters, {n});
    *reply->mutable_shape_ids() = Uint32Array(shapes, {n});
    *reply->mutable_uv() = FloatArray(uv, {n, 2});
  });
}

grpc::Status SceneViewServiceImpl::LightPdfArea(grpc::ServerContext*, const v1::LightPdfAreaRequest* request,
                                                v1::LightPdfAreaReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto shapes = batch.Uint32s(request->shape_ids(), "shape_ids");
    const uint32_t n = batch.rows();
    CheckRows(n);
    std::vector<float> pdf(n);
    for (uint32_t i = 0; i < n; ++i) pdf[i] = served.scene().LightPdfArea(CheckedShape(served, shapes[i], i));
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SceneViewServiceImpl::InfiniteLightOrigins(grpc::ServerContext*,
                                                        const v1::InfiniteLightOriginsRequest* request,
                                                        v1::InfiniteLightOriginsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto directions = UnitVectorsOf(batch.Floats(request->directions(), {3}, "directions"), "direction");
    const auto u = batch.Floats(request->uniform(), {2}, "uniform");
    const uint32_t n = batch.rows();
    CheckRows(n);
    CheckUniform(u, 2, "uniform");
    std::vector<float> origins(3 * n), pdf(n);
    for (uint32_t i = 0; i < n; ++i)
      served.scene().InfiniteLightOrigin(directions[i], u[2 * i], u[2 * i + 1], pdf[i]).Store(&origins[3 * i]);
    *reply->mutable_origins() = FloatArray(origins, {n, 3});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SceneViewServiceImpl::Emission(grpc::ServerContext*, const v1::EmissionRequest* request,
                                            v1::EmissionReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const std::vector<Ray> rays = RaysOf(request->rays());
    const uint32_t n = uint32_t(rays.size());
    size_t rows = 0;
    const auto t = FloatsOf(request->hits().t(), {}, "hits.t", rows);
    if (rows != n) throw Error("hits.t has " + std::to_string(rows) + " rows for " + std::to_string(n) + " rays");
    const auto normals = FloatsOf(request->hits().normals(), {3}, "hits.normals", rows);
    if (rows != n) throw Error("hits.normals has " + std::to_string(rows) + " rows for " + std::to_string(n) + " rays");
    const auto uv = FloatsOf(request->hits().uv(), {2}, "hits.uv", rows);
    if (rows != n) throw Error("hits.uv has " + std::to_string(rows) + " rows for " + std::to_string(n) + " rays");
    const v1::Array& ids = request->hits().shape_ids();
    if (ids.dtype() != v1::Array::UINT32 || ids.data().size() != 4 * size_t(n))
      throw Error("hits.shape_ids must be UINT32 [" + std::to_string(n) + "]");
    const auto* shape_ids = reinterpret_cast<const uint32_t*>(ids.data().data());
    const KernelScene& scene = served.scene();
    std::vector<float> w(3 * n), radiance(3 * n), pdf(n);
    std::vector<const Emitter*> emitters(n, nullptr);
    std::vector<Vec3> escaped;
    std::vector<uint32_t> escaped_rays;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t shape = shape_ids[i];
      if (shape == kNoShape) {
        escaped.push_back(rays[i].direction);
        escaped_rays.push_back(i);
        continue;
      }
      CheckedShape(served, shape, i);
      emitters[i] = scene.EmitterOf(shape);
      if (!emitters[i]) continue;
      Hit hit;
      hit.shape = shape;
      hit.t = t[i];
      hit.normal = Vec3::Load(&normals[3 * i]);
      Frame(hit.normal).ToLocal(-rays[i].direction).Store(&w[3 * i]);
      pdf[i] = scene.LightPdfFrom(rays[i], hit);
    }
    EmitterRadiance(emitters, w, uv, radiance);
    // Rays that left the scene: the environment and its density.
    std::vector<Vec3> environment(escaped.size());
    std::vector<float> environment_pdf(escaped.size());
    scene.Escaped(escaped, environment, environment_pdf);
    for (size_t k = 0; k < escaped.size(); ++k) {
      environment[k].Store(&radiance[3 * escaped_rays[k]]);
      pdf[escaped_rays[k]] = environment_pdf[k];
    }
    *reply->mutable_radiance() = FloatArray(radiance, {n, 3});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SceneViewServiceImpl::ConnectToCamera(grpc::ServerContext*, const v1::ConnectToCameraRequest* request,
                                                   v1::ConnectToCameraReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto points = PointsOf(batch.Floats(request->points(), {3}, "points"), "point");
    const auto lens = batch.Floats(request->lens(), {2}, "lens");
    const uint32_t n = batch.rows();
    CheckRows(n);
    CheckUniform(lens, 2, "lens");
    std::vector<uint32_t> connected(n);
    std::vector<float> lens_points(3 * n), raster(2 * n), importance(n);
    for (uint32_t i = 0; i < n; ++i) {
      CameraConnection c;
      if (!served.scene().ConnectToCamera(points[i], lens[2 * i], lens[2 * i + 1], c)) continue;
      connected[i] = 1;
      c.lens_point.Store(&lens_points[3 * i]);
      raster[2 * i] = c.raster_x;
      raster[2 * i + 1] = c.raster_y;
      importance[i] = c.importance;
    }
    *reply->mutable_connected() = Uint32Array(connected, {n});
    *reply->mutable_lens_points() = FloatArray(lens_points, {n, 3});
    *reply->mutable_raster() = FloatArray(raster, {n, 2});
    *reply->mutable_importance() = FloatArray(importance, {n});
  });
}

grpc::Status SceneViewServiceImpl::CameraDirectionPdf(grpc::ServerContext*,
                                                      const v1::CameraDirectionPdfRequest* request,
                                                      v1::CameraDirectionPdfReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto directions = UnitVectorsOf(batch.Floats(request->directions(), {3}, "directions"), "direction");
    const uint32_t n = batch.rows();
    CheckRows(n);
    std::vector<float> pdf(n);
    for (uint32_t i = 0; i < n; ++i) pdf[i] = served.scene().CameraDirectionPdf(directions[i]);
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SceneViewServiceImpl::SampleSpacing(grpc::ServerContext*, const v1::SampleSpacingRequest* request,
                                                 v1::SampleSpacingReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto points = PointsOf(batch.Floats(request->points(), {3}, "points"), "point");
    const auto normals = UnitVectorsOf(batch.Floats(request->normals(), {3}, "normals"), "normal");
    const uint32_t n = batch.rows();
    CheckRows(n);
    std::vector<float> dpdx(3 * n), dpdy(3 * n);
    for (uint32_t i = 0; i < n; ++i) {
      Vec3 dx, dy;
      served.scene().SampleSpacing(points[i], normals[i], dx, dy);
      dx.Store(&dpdx[3 * i]);
      dy.Store(&dpdy[3 * i]);
    }
    *reply->mutable_dpdx() = FloatArray(dpdx, {n, 3});
    *reply->mutable_dpdy() = FloatArray(dpdy, {n, 3});
  });
}

grpc::Status SceneViewServiceImpl::Triangles(grpc::ServerContext*, const v1::TrianglesRequest* request,
                                             v1::TrianglesReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const KernelScene& scene = served.scene();
    const uint32_t shape = CheckedShape(served, request->shape(), 0);
    const uint32_t count = scene.PrimitiveCount(shape);
    CheckRows(count);
    std::vector<float> corners;
    Vec3 triangle[3];
    for (uint32_t p = 0; p < count; ++p) {
      if (!scene.Triangle(shape, p, triangle)) {
        corners.clear();
        break;
      }
      for (const Vec3& corner : triangle) {
        corners.push_back(corner.x);
        corners.push_back(corner.y);
        corners.push_back(corner.z);
      }
    }
    *reply->mutable_corners() = FloatArray(corners, {uint32_t(corners.size() / 9), 3, 3});
  });
}

}  // namespace yarf
