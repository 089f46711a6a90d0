// Evaluations per second of yarf's integrators on an in-process C++
// integrand against a hand-written loop doing the same work (the same
// sampler's points, the same function, a running sum): the cost of going
// through the component interfaces in batches. Prints JSON.
//
// usage: integrator_throughput [evaluations]

#include <chrono>
#include <cmath>
#include <iostream>

#include "components/registry.h"
#include "yarf/math.h"

namespace yarf {
namespace {

constexpr uint32_t kDimensions = 4;

float Integrand(const float* x) {
  float s = 0;
  for (uint32_t j = 0; j < kDimensions; ++j) s += x[j] * x[j];
  return std::exp(-s);
}

class Gaussian final : public Function {
 public:
  uint32_t InputDimensions() const override { return kDimensions; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < values.size(); ++i) values[i] = Integrand(&points[i * kDimensions]);
  }
};

template <typename F>
double Seconds(F&& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int Main(int argc, char** argv) {
  const uint64_t n = argc > 1 ? std::stoull(argv[1]) : uint64_t(1) << 23;
  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  auto sampler = registry.CreateAs<Sampler>("independent", Properties{});
  const double lower[kDimensions] = {0, 0, 0, 0}, upper[kDimensions] = {1, 1, 1, 1};
  Gaussian f;

  double hand_sum = 0;
  const double hand = Seconds([&] {
    float x[kDimensions];
    for (uint64_t i = 0; i < n; ++i) {
      for (uint32_t j = 0; j < kDimensions; ++j) x[j] = sampler->Sample(i, j, 1);
      hand_sum += Integrand(x);
    }
  });
  std::cout << "{\"evaluations\": " << n << ", \"hand_loop_per_second\": " << n / hand;
  for (const char* name : {"mean_sample", "vegas", "vegas_plus"}) {
    auto integrator = registry.CreateAs<Integrator>(name, Properties{});
    IntegrationResult result;
    const double seconds = Seconds([&] { result = integrator->Integrate(f, lower, upper, n, 1, *sampler); });
    std::cout << ", \"" << name << "_per_second\": " << n / seconds << ", \"" << name
              << "_vs_hand_loop\": " << hand / seconds;
  }
  std::cout << ", \"hand_loop_estimate\": " << hand_sum / double(n) << "}\n";
  return 0;
}

}  // namespace
}  // namespace yarf

int main(int argc, char** argv) {
  try {
    return yarf::Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "integrator_throughput: " << e.what() << "\n";
    return 1;
  }
}
