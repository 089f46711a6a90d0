#include "components/parameter_checks.h"

#include <gtest/gtest.h>

#include "components/properties_proto.h"
#include "components/registry.h"
#include "yarf/error.h"

namespace yarf {
namespace {

ComponentInfo Metal() {
  ComponentInfo info;
  info.class_name = "metal";
  info.version = "1.0.0";
  info.interfaces = {"yarf.v1.SurfaceModel"};
  info.declares_parameters = true;
  info.parameters = {
      Parameter::FloatTexture("alpha").Default(0.1).Min(0).Doc("roughness"),
      Parameter::String("distribution").Default("ggx").Choices({"ggx", "beckmann"}),
      Parameter::RgbTexture("specular_reflectance").Default(1.0).Range(0, 1),
      Parameter::Int("samples").Default(4).Range(1, 64),
      Parameter::Material("nested").Required(),
  };
  return info;
}

std::string Refusal(const ComponentInfo& info, const v1::Properties& properties) {
  try {
    CheckProperties(info, properties, "scene.materials[0] ('m').properties");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

v1::Properties WithNested() {
  v1::Properties properties;
  (*properties.mutable_values())["nested"].set_reference("inner");
  return properties;
}

TEST(ParameterChecks, AcceptWhatTheSchemaDeclares) {
  v1::Properties properties = WithNested();
  auto& values = *properties.mutable_values();
  values["alpha"].set_reference("roughness_map");
  values["distribution"].set_string_value("beckmann");
  values["specular_reflectance"].mutable_rgb_value()->set_r(0.5);
  values["samples"].set_int_value(16);
  EXPECT_EQ(Refusal(Metal(), properties), "");
  // An int where a float is asked is a float.
  values["alpha"].set_int_value(1);
  EXPECT_EQ(Refusal(Metal(), properties), "");
}

TEST(ParameterChecks, RefuseWithThePathAndTheNearestName) {
  v1::Properties properties = WithNested();
  (*properties.mutable_values())["alpah"].set_float_value(0.2);
  EXPECT_EQ(Refusal(Metal(), properties),
            "scene.materials[0] ('m').properties.alpah: 'metal' has no parameter 'alpah'; did you mean "
            "'alpha'? (`yarf classes -v metal` lists its parameters)");
}

TEST(ParameterChecks, RefuseIllTypedOutOfRangeAndUnlistedValues) {
  const auto refusal = [](const char* key, auto set) {
    v1::Properties properties = WithNested();
    set((*properties.mutable_values())[key]);
    return Refusal(Metal(), properties);
  };
  EXPECT_EQ(refusal("distribution", [](v1::Property& p) { p.set_float_value(3); }),
            "scene.materials[0] ('m').properties.distribution: must be string, not a float");
  EXPECT_EQ(refusal("samples", [](v1::Property& p) { p.set_float_value(3); }),
            "scene.materials[0] ('m').properties.samples: must be int, not a float");
  EXPECT_EQ(refusal("samples", [](v1::Property& p) { p.set_int_value(65); }),
            "scene.materials[0] ('m').properties.samples: 65 is above 64, the most it may be");
  EXPECT_EQ(refusal("alpha", [](v1::Property& p) { p.set_float_value(-1); }),
            "scene.materials[0] ('m').properties.alpha: -1 is below 0, the least it may be");
  EXPECT_NE(refusal("specular_reflectance", [](v1::Property& p) { p.mutable_rgb_value()->set_g(2); })
                .find("2 is above 1"),
            std::string::npos);
  EXPECT_EQ(refusal("distribution", [](v1::Property& p) { p.set_string_value("gxx"); }),
            "scene.materials[0] ('m').properties.distribution: 'gxx' is not one of 'ggx', 'beckmann'; did you "
            "mean 'ggx'?");
  EXPECT_NE(refusal("nested", [](v1::Property& p) { p.set_string_value("inner"); }).find("must be material"),
            std::string::npos);
  EXPECT_NE(Refusal(Metal(), v1::Properties()).find("'metal' needs parameter 'nested'"), std::string::npos);
}

TEST(ParameterChecks, AnUploadedAssetStandsInForARequiredFile) {
  ComponentInfo info = Metal();
  info.parameters = {Parameter::File("filename").Required(), Parameter::String("asset"),
                     Parameter::File("density_filename").Required(), Parameter::String("density_asset")};
  v1::Properties properties;
  (*properties.mutable_values())["asset"].set_string_value(std::string(64, 'a'));
  (*properties.mutable_values())["density_filename"].set_string_value("smoke.vol");
  EXPECT_EQ(Refusal(info, properties), "");
  properties.mutable_values()->erase("asset");
  EXPECT_NE(Refusal(info, properties).find("needs parameter 'filename'"), std::string::npos);
}

TEST(ParameterChecks, AClassWithoutASchemaIsNotChecked) {
  ComponentInfo info = Metal();
  info.declares_parameters = false;
  info.parameters.clear();
  v1::Properties properties;
  (*properties.mutable_values())["anything"].set_bool_value(true);
  EXPECT_EQ(Refusal(info, properties), "");
}

TEST(ParameterChecks, MalformedSchemasAreRefused) {
  const auto refusal = [](Parameter parameter) -> std::string {
    ComponentInfo info = Metal();
    info.parameters.push_back(std::move(parameter));
    try {
      CheckSchema(info);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(refusal(Parameter::Float("extra").Default(0.5)), "");
  EXPECT_NE(refusal(Parameter::Float("alpha")).find("declared twice"), std::string::npos);
  EXPECT_NE(refusal(Parameter::Float("")).find("without a name"), std::string::npos);
  EXPECT_NE(refusal(Parameter::Float("extra").Default("text")).find("default is not float"), std::string::npos);
  EXPECT_NE(refusal(Parameter::Float("extra").Range(1, 0)).find("least value is above its most"),
            std::string::npos);
  EXPECT_NE(refusal(Parameter::Float("extra").Default(2.0).Range(0, 1)).find("2 is above 1"), std::string::npos);
  EXPECT_NE(refusal(Parameter::String("extra").Default("c").Choices({"a", "b"})).find("'c' is not one of"),
            std::string::npos);
  EXPECT_NE(refusal(Parameter::Float("extra").Choices({"a"})).find("only a string has choices"), std::string::npos);
}

TEST(ParameterChecks, DefaultsTravelAsTextAndBack) {
  const ComponentInfo info = Metal();
  const ComponentInfo back = FromProto(ToProto(info), "remote x");
  ASSERT_EQ(back.parameters.size(), info.parameters.size());
  for (size_t i = 0; i < info.parameters.size(); ++i) {
    const Parameter &a = info.parameters[i], &b = back.parameters[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.required, b.required);
    EXPECT_EQ(a.min, b.min);
    EXPECT_EQ(a.max, b.max);
    EXPECT_EQ(a.choices, b.choices);
    EXPECT_EQ(a.default_value.has_value(), b.default_value.has_value()) << a.name;
    if (a.default_value) {
      EXPECT_EQ(DefaultText(*a.default_value), DefaultText(*b.default_value)) << a.name;
    }
  }
  EXPECT_EQ(DefaultText(*ParseDefault(ParameterType::kRgb, "0.25, 0.5, 1")), "0.25, 0.5, 1");
  EXPECT_THROW(ParseDefault(ParameterType::kRgb, "0.25, 0.5"), Error);
  EXPECT_THROW(ParseDefault(ParameterType::kInt, "1.5"), Error);
  EXPECT_THROW(ParseDefault(ParameterType::kBool, "yes"), Error);
  EXPECT_THROW(ParseDefault(ParameterType::kMaterial, "a"), Error);
}

TEST(ParameterChecks, MisspellingsFindTheirWord) {
  const std::vector<std::string> words = {"bdpt", "path", "lambertian", "roughconductor", "vegas", "vegas_plus"};
  EXPECT_EQ(DidYouMean("bpdt", words), "bdpt");
  EXPECT_EQ(DidYouMean("lambertain", words), "lambertian");
  EXPECT_EQ(DidYouMean("roughconducter", words), "roughconductor");
  EXPECT_EQ(DidYouMean("vegass", words), "vegas");
  EXPECT_EQ(DidYouMean("xyz", words), "");
  EXPECT_EQ(DidYouMean("quasirandom_halton", words), "");
}

// Every shipped class that declares its parameters can be made from its
// declared defaults alone (required ones aside): a default the class
// itself refuses, or that conflicts with another key, is a schema error.
TEST(ParameterChecks, EveryShippedSchemaMakesItsClassFromItsDefaults) {
  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  ASSERT_TRUE(registry.Failures().empty()) << registry.Failures()[0].message;
  int declared = 0;
  for (const ComponentInfo& info : registry.Classes()) {
    if (!info.declares_parameters) continue;
    ++declared;
    // grid needs one of its quantities as a grid, whichever: no one
    // parameter is required.
    bool needs_scene = info.class_name == "grid";
    for (const Parameter& parameter : info.parameters) needs_scene |= parameter.required;
    if (needs_scene) continue;  // a required material or file comes from a scene
    EXPECT_NO_THROW(registry.Create(info.class_name, Properties{})) << info.class_name;
  }
  EXPECT_GT(declared, 0);
}

}  // namespace
}  // namespace yarf
