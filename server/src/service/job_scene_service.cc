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

// Points in [0,1)³, as a sampler's uniform numbers must be.
void CheckUniform(const std::vector<float>& u) {
  for (size_t i = 0; i < u.size(); ++i)
    if (!(u[i] >= 0 && u[i] < 1)) throw Error("uniform " + std::to_string(i / 3) + " is not in [0, 1)");
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
    CheckUniform(u);
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
    CheckUniform(u);
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

grpc::Status JobSceneServiceImpl::Layout(grpc::ServerContext*, const v1::JobSceneRequest* request,
                                         v1::SceneLayout* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    const KernelScene& scene = served.scene();
    reply->set_width(scene.FilmWidth());
    reply->set_height(scene.FilmHeight());
    for (uint32_t shape = 0; shape < scene.ShapeCount(); ++shape) {
      reply->add_material_handles(served.material_handles()[scene.MaterialOf(shape)]);
      reply->add_emits(scene.EmitterOf(shape) != nullptr);
    }
    reply->set_has_lights(scene.HasLights());
  });
}

grpc::Status JobSceneServiceImpl::CameraRays(grpc::ServerContext*, const v1::CameraRaysRequest* request,
                                             v1::RayBatch* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    size_t rows = 0;
    const auto points = FloatsOf(request->points(), {5}, "points", rows);
    const uint32_t n = uint32_t(rows);
    CheckRows(n);
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

grpc::Status JobSceneServiceImpl::SampleLights(grpc::ServerContext*, const v1::SampleLightsRequest* request,
                                               v1::SampleLightsReply* reply) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    BatchDecoder batch;
    const auto u = batch.Floats(request->uniform(), {3}, "uniform");
    const auto points = batch.Floats(request->points(), {3}, "points");
    const uint32_t n = batch.rows();
    CheckRows(n);
    const KernelScene& scene = served.scene();
    std::vector<float> directions(3 * n), distances(n), radiance(3 * n), pdf(n), w(3 * n), uv(2 * n);
    std::vector<uint32_t> delta(n);
    std::vector<const Emitter*> emitters(n, nullptr);
    std::vector<Vec3> from(n);
    for (uint32_t i = 0; i < n; ++i) from[i] = Vec3::Load(&points[3 * i]);
    std::vector<LightDirection> lights(n);
    if (scene.HasLights()) scene.SampleLightsFrom(from, u, lights);
    for (uint32_t i = 0; i < n; ++i) {
      const LightDirection& s = lights[i];
      if (!s.emitter || !(s.pdf > 0)) continue;
      s.direction.Store(&directions[3 * i]);
      distances[i] = s.distance;
      pdf[i] = s.pdf;
      delta[i] = s.delta;
      emitters[i] = s.emitter;
      s.w.Store(&w[3 * i]);
      uv[2 * i] = s.u;
      uv[2 * i + 1] = s.v;
    }
    EmitterRadiance(emitters, w, uv, radiance);
    // On the wire a point light's pdf is the choice's probability and its
    // radiance the irradiance it gives at the point.
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
  });
}

grpc::Status JobSceneServiceImpl::Emission(grpc::ServerContext*, const v1::EmissionRequest* request,
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
      if (shape >= scene.ShapeCount()) throw Error("hit " + std::to_string(i) + " names no shape of the scene");
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

grpc::Status JobSceneServiceImpl::Splat(grpc::ServerContext*, const v1::SplatRequest* request, v1::SplatReply*) {
  return WithScene(scenes_, request->handle(), [&](const ServedScene& served) {
    size_t rows = 0;
    const auto values = FloatsOf(request->contributions(), {5}, "contributions", rows);
    FilmSamples samples;
    samples.splats = true;
    const float width = float(served.scene().FilmWidth()), height = float(served.scene().FilmHeight());
    for (size_t k = 0; k < rows; ++k) {
      const float* row = &values[5 * k];
      for (int c = 0; c < 5; ++c)
        if (!std::isfinite(row[c])) throw Error("contribution " + std::to_string(k) + " is not finite");
      if (row[0] < 0 || row[0] > width || row[1] < 0 || row[1] > height)
        throw Error("contribution " + std::to_string(k) + " lies off the film");
      if (row[2] < 0 || row[3] < 0 || row[4] < 0) throw Error("contribution " + std::to_string(k) + " is negative");
      samples.Add(0, row[0], row[1], Vec3(row[2], row[3], row[4]));
    }
    if (!served.Splat(samples)) throw Error("the job has ended");
  });
}

}  // namespace yarf
