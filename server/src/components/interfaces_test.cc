// The C++ interfaces and the proto services must stay in lock-step: each
// interface names a service of the IDL and mirrors its methods exactly.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "yarf/geometry.h"
#include "yarf/math.h"
#include "yarf/medium.h"
#include "yarf/shape.h"
#include "yarf/surface.h"
#include "yarf/transport.h"
#include "yarf/v1/geometry.pb.h"
#include "yarf/v1/math.pb.h"
#include "yarf/v1/medium.pb.h"
#include "yarf/v1/surface.pb.h"
#include "yarf/v1/transport.pb.h"

namespace yarf {
namespace {

const google::protobuf::ServiceDescriptor* FindService(const std::string& name) {
  // Referencing one message of each file links its descriptors in.
  for (const auto* file : {v1::EvaluateRequest::descriptor()->file(), v1::SurfaceQuery::descriptor()->file(),
                           v1::RayBatch::descriptor()->file(), v1::TransportRequest::descriptor()->file(),
                           v1::PhaseQuery::descriptor()->file()})
    for (int i = 0; i < file->service_count(); ++i)
      if (file->service(i)->full_name() == name) return file->service(i);
  return nullptr;
}

template <typename I>
void ExpectMirrorsService() {
  const auto* service = FindService(I::kInterface);
  ASSERT_NE(service, nullptr) << I::kInterface << " is not a service of the IDL";
  std::set<std::string> proto_methods, cpp_methods(std::begin(I::kMethods), std::end(I::kMethods));
  for (int i = 0; i < service->method_count(); ++i) proto_methods.insert(service->method(i)->name());
  EXPECT_EQ(proto_methods, cpp_methods) << I::kInterface;
}

TEST(Interfaces, MirrorTheirProtoServices) {
  ExpectMirrorsService<Function>();
  ExpectMirrorsService<Integrator>();
  ExpectMirrorsService<Sampler>();
  ExpectMirrorsService<Generator>();
  ExpectMirrorsService<RootFinder>();
  ExpectMirrorsService<Warp>();
  ExpectMirrorsService<SurfaceModel>();
  ExpectMirrorsService<Emitter>();
  ExpectMirrorsService<Intersector>();
  ExpectMirrorsService<Shape>();
  ExpectMirrorsService<SurfaceAreaSampler>();
  ExpectMirrorsService<SurfaceDirectionSampler>();
  ExpectMirrorsService<Transport>();
  ExpectMirrorsService<Medium>();
}

}  // namespace
}  // namespace yarf
