// ServedFunction over real gRPC: a Remote<Function> at the served address
// (as a component process's integrator reaches it) gets the function's
// values, its errors and nothing for another handle.
#include "components/served_function.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "components/remote_function.h"

namespace yarf {
namespace {

// (x, y) -> (x·y, x + y); throws for a point with x < 0.
class Product final : public Function {
 public:
  uint32_t InputDimensions() const override { return 2; }
  uint32_t OutputDimensions() const override { return 2; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size() / 2; ++i) {
      if (points[2 * i] < 0) throw Error("x is negative");
      values[2 * i] = points[2 * i] * points[2 * i + 1];
      values[2 * i + 1] = points[2 * i] + points[2 * i + 1];
    }
  }
};

Remote<Function> Caller(const std::string& address, uint64_t handle) {
  return Remote<Function>(std::make_unique<RemoteInstance>(address, handle, Function::kInterface, RemoteOptions{}));
}

std::string ErrorOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ServedFunction, AComponentOnThisMachineCallsItBackOverTcp) {
  Product product;
  const ServedFunction served(product, "127.0.0.1:50999");
  ASSERT_EQ(served.address().rfind("127.0.0.1:", 0), 0u) << served.address();
  Remote<Function> remote = Caller(served.address(), 0);
  EXPECT_EQ(remote.InputDimensions(), 2u);
  EXPECT_EQ(remote.OutputDimensions(), 2u);
  const std::vector<float> points = {2, 3, 0.5f, 4};
  std::vector<float> values(4);
  remote.Evaluate(points, values);
  EXPECT_EQ(values, (std::vector<float>{6, 5, 2, 4.5f}));
  // The function's own error reaches the caller.
  std::vector<float> one(2);
  EXPECT_NE(ErrorOf([&] { remote.Evaluate(std::vector<float>{-1, 1}, one); }).find("x is negative"),
            std::string::npos);
}

TEST(ServedFunction, AUnixComponentGetsAPrivateSocketRemovedAfterwards) {
  Product product;
  std::filesystem::path folder;
  {
    const ServedFunction served(product, "unix:/tmp/component.sock");
    ASSERT_EQ(served.address().rfind("unix:", 0), 0u) << served.address();
    folder = std::filesystem::path(served.address().substr(5)).parent_path();
    EXPECT_EQ(std::filesystem::status(folder).permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_all);
    std::vector<float> values(2);
    Caller(served.address(), 0).Evaluate(std::vector<float>{1, 1}, values);
    EXPECT_EQ(values, (std::vector<float>{1, 2}));
  }
  EXPECT_FALSE(std::filesystem::exists(folder));
}

TEST(ServedFunction, ServesOnlyHandleZero) {
  Product product;
  const ServedFunction served(product, "localhost:50999");
  const std::string error = ErrorOf([&] { Caller(served.address(), 7); });
  EXPECT_NE(error.find("NOT_FOUND"), std::string::npos) << error;
}

}  // namespace
}  // namespace yarf
