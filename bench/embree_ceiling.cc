// Embree's raw ray rate on a scene's own triangles: the ceiling a renderer
// built on it can approach. Builds the scene as yarfd does, makes a set of
// closest-hit rays (a quarter from the camera in pixel order, the rest
// diffuse bounces from their hits) and shadow rays (from those hits to
// emitters), then times every Embree kernel over them on all cores and
// prints JSON (with the seconds the scene took to build). A scene that
// names an aggregate class is traced through it, inside Embree's BVH, by
// the same kernels.
//
// usage: embree_ceiling SCENE.json [rays]

#include <google/protobuf/util/json_util.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>

#include "components/registry.h"
#include "components/scene_builder.h"
#include "yarf/support/hash.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

constexpr size_t kChunk = 4096;

float Uniform(uint64_t i, uint64_t d) { return ToUnitFloat(uint32_t(Hash(i, d))); }

RTCRayHit ToRayHit(const Ray& r) {
  RTCRayHit rh{};
  rh.ray.org_x = r.origin.x, rh.ray.org_y = r.origin.y, rh.ray.org_z = r.origin.z;
  rh.ray.dir_x = r.direction.x, rh.ray.dir_y = r.direction.y, rh.ray.dir_z = r.direction.z;
  rh.ray.tnear = r.tnear, rh.ray.tfar = r.tfar, rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

struct RaySets {
  std::vector<Ray> closest, shadow;
};

RaySets MakeRays(const KernelScene& scene, size_t count) {
  RaySets sets;
  // Camera rays in the order a renderer traces them: the film's pixels
  // row by row, one jittered sample each, over as many passes as it takes.
  // Neighbouring rays meet neighbouring triangles, and so do the bounce and
  // shadow rays that follow from their hits; random pixels would make the
  // ceiling lower than what a renderer reaches.
  std::vector<Ray> camera(count);
  const size_t width = scene.FilmWidth(), height = scene.FilmHeight();
  for (size_t i = 0; i < count; ++i) {
    const size_t pixel = i % (width * height);
    camera[i] = scene.CameraRay((float(pixel % width) + Uniform(i, 0)) / float(width),
                                (float(pixel / width) + Uniform(i, 1)) / float(height), 0.5f, 0.5f, 0.0f);
  }
  std::vector<Hit> hits(count);
  scene.Intersect(camera, hits);
  sets.closest.assign(camera.begin(), camera.begin() + count / 4);
  for (size_t i = 0; sets.closest.size() < count || sets.shadow.size() < count; ++i) {
    const size_t k = i % count;
    if (!hits[k].Found()) continue;
    const Vec3 p = camera[k].origin + camera[k].direction * hits[k].t;
    const Frame frame(hits[k].normal);
    const Vec3 d = frame.ToWorld(SampleCosineHemisphere(Uniform(i, 2), Uniform(i, 3)));
    if (sets.closest.size() < count) sets.closest.push_back({OffsetRayOrigin(p, hits[k].normal, d), 0, d, kInfinity});
    const LightSample s = scene.SampleLight(Uniform(i, 4), Uniform(i, 5), Uniform(i, 6));
    if (sets.shadow.size() < count && Length(s.position - p) > 0)
      sets.shadow.push_back(ShadowRay(p, hits[k].normal, s.position));
  }
  return sets;
}

// Rays per second of `trace` over all rays, best of three runs.
double Rate(size_t count, const std::function<void(size_t, size_t)>& trace) {
  double best = 0;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t(0), (count + kChunk - 1) / kChunk, [&](size_t chunk) {
      trace(chunk * kChunk, std::min(count, (chunk + 1) * kChunk));
    });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::max(best, count / s);
  }
  return best;
}

template <int N, typename Packet, typename Call>
void TracePackets(const std::vector<Ray>& rays, size_t begin, size_t end, bool shadow, Call call) {
  for (size_t i = begin; i < end; i += N) {
    alignas(64) Packet packet;
    alignas(64) int valid[N];
    for (int k = 0; k < N; ++k) {
      const size_t j = std::min(i + k, end - 1);
      valid[k] = i + k < end ? -1 : 0;
      const Ray& r = rays[j];
      auto& ray = [&]() -> auto& { if constexpr (requires { packet.ray; }) return packet.ray; else return packet; }();
      ray.org_x[k] = r.origin.x, ray.org_y[k] = r.origin.y, ray.org_z[k] = r.origin.z;
      ray.dir_x[k] = r.direction.x, ray.dir_y[k] = r.direction.y, ray.dir_z[k] = r.direction.z;
      ray.tnear[k] = r.tnear, ray.tfar[k] = r.tfar, ray.mask[k] = 0xFFFFFFFFu, ray.time[k] = 0, ray.flags[k] = 0;
      if constexpr (requires { packet.hit; }) packet.hit.geomID[k] = packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    call(valid, &packet);
  }
  (void)shadow;
}

int Main(int argc, char** argv) {
  if (argc < 2) throw Error("usage: embree_ceiling SCENE.json [rays]");
  const std::filesystem::path path = argv[1];
  const size_t count = argc > 2 ? std::stoul(argv[2]) : 1 << 20;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  v1::Scene proto;
  if (!google::protobuf::util::JsonStringToMessage(text.str(), &proto).ok()) throw Error("cannot parse " + path.string());
  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  EmbreeDevice device;
  const auto build_start = std::chrono::steady_clock::now();
  auto scene = BuildScene(proto, SceneSources{{registry}, device, path.parent_path()});
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  const RaySets rays = MakeRays(*scene, count);
  const RTCScene world = scene->embree_scene();

  auto context = [] {
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    c.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    return c;
  };
  const auto& c = rays.closest;
  const auto& s = rays.shadow;
  const double i1 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    for (size_t i = b; i < e; ++i) { RTCRayHit rh = ToRayHit(c[i]); rtcIntersect1(world, &ctx, &rh); }
  });
  const double i1m = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    std::vector<RTCRayHit> batch(e - b);
    for (size_t i = b; i < e; ++i) batch[i - b] = ToRayHit(c[i]);
    rtcIntersect1M(world, &ctx, batch.data(), unsigned(e - b), sizeof(RTCRayHit));
  });
  const double i8 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    TracePackets<8, RTCRayHit8>(c, b, e, false, [&](int* v, RTCRayHit8* p) { rtcIntersect8(v, world, &ctx, p); });
  });
  const double i16 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    TracePackets<16, RTCRayHit16>(c, b, e, false, [&](int* v, RTCRayHit16* p) { rtcIntersect16(v, world, &ctx, p); });
  });
  const double o1 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    for (size_t i = b; i < e; ++i) { RTCRay r = ToRayHit(s[i]).ray; rtcOccluded1(world, &ctx, &r); }
  });
  const double o1m = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    std::vector<RTCRay> batch(e - b);
    for (size_t i = b; i < e; ++i) batch[i - b] = ToRayHit(s[i]).ray;
    rtcOccluded1M(world, &ctx, batch.data(), unsigned(e - b), sizeof(RTCRay));
  });
  const double o8 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    TracePackets<8, RTCRay8>(s, b, e, true, [&](int* v, RTCRay8* p) { rtcOccluded8(v, world, &ctx, p); });
  });
  const double o16 = Rate(count, [&](size_t b, size_t e) {
    auto ctx = context();
    TracePackets<16, RTCRay16>(s, b, e, true, [&](int* v, RTCRay16* p) { rtcOccluded16(v, world, &ctx, p); });
  });
  std::cout << "{\"closest\": {\"single\": " << i1 << ", \"stream\": " << i1m << ", \"packet8\": " << i8
            << ", \"packet16\": " << i16 << ", \"best\": " << std::max({i1, i1m, i8, i16}) << "},\n"
            << " \"shadow\": {\"single\": " << o1 << ", \"stream\": " << o1m << ", \"packet8\": " << o8
            << ", \"packet16\": " << o16 << ", \"best\": " << std::max({o1, o1m, o8, o16}) << "},\n"
            << " \"build_seconds\": " << build_seconds << "}\n";
  return 0;
}

}  // namespace
}  // namespace yarf

int main(int argc, char** argv) {
  try {
    return yarf::Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "embree_ceiling: " << e.what() << "\n";
    return 1;
  }
}
