#include "components/registry.h"

#include <gtest/gtest.h>

#include <fstream>

#include "yarf/surface.h"

namespace yarf {
namespace {

std::filesystem::path WriteBogusPlugin() {
  auto dir = std::filesystem::temp_directory_path() / ("yarf_registry_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "libbroken.so") << "this is not an ELF file";
  return dir;
}

TEST(Registry, PluginThatFailsToLoadIsNamed) {
  const auto dir = WriteBogusPlugin();
  Registry registry;
  try {
    registry.LoadPlugin(dir / "libbroken.so");
    FAIL() << "loading a bogus plugin succeeded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("libbroken.so"), std::string::npos) << e.what();
  }
  registry.LoadDirectory(dir);
  ASSERT_EQ(registry.Failures().size(), 1u);
  EXPECT_NE(registry.Failures()[0].path.find("libbroken.so"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Registry, LoadsShippedPluginsAndDescribesThem) {
  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  EXPECT_TRUE(registry.Failures().empty());
  for (const char* name : {"lambertian", "phong", "mirror", "dielectric", "diffuse_area", "independent",
                           "sobol", "mean_sample", "path"})
    EXPECT_TRUE(registry.Has(name)) << name;
  auto lambertian = registry.CreateAs<SurfaceModel>("lambertian", Properties{});
  EXPECT_EQ(lambertian->Describe().class_name, "lambertian");
  EXPECT_EQ(lambertian->Describe().interfaces, std::vector<std::string>{"yarf.v1.SurfaceModel"});
}

TEST(Registry, RejectsUnknownClassesAndProperties) {
  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  EXPECT_THROW(registry.Create("no_such_class", Properties{}), Error);
  Properties misspelt;
  misspelt.Set("reflectanse", 0.5);
  try {
    registry.Create("lambertian", misspelt);
    FAIL() << "a misspelt property was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("reflectanse"), std::string::npos) << e.what();
  }
  EXPECT_THROW(registry.CreateAs<SurfaceModel>("sobol", Properties{}), Error);
}

}  // namespace
}  // namespace yarf
