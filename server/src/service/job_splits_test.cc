#include "service/job_splits.h"

#include <gtest/gtest.h>

#include "components/parameter_checks.h"
#include "yarf/error.h"

namespace yarf {
namespace {

ComponentInfo Class(const std::string& name, std::vector<std::string> capabilities) {
  ComponentInfo info;
  info.class_name = name;
  info.capabilities = std::move(capabilities);
  return info;
}

// Classes named as the shipped ones, with the capabilities they declare.
const std::vector<ComponentInfo> kKnown = {
    Class("mean_sample", {kSamplePassesCapability}), Class("vegas", {}),
    Class("path", {kPixelLocalCapability}), Class("light", {}),
    Class("py_path", {kPixelLocalCapability}), Class("sobol", {kPowerOfTwoSamplesCapability}),
    Class("independent", {})};

v1::SubmitRequest Request(const std::string& integrator, const std::string& transport) {
  v1::SubmitRequest request;
  request.mutable_scene()->mutable_film()->set_width(64);
  request.mutable_scene()->mutable_film()->set_height(64);
  request.mutable_options()->set_spp(16);
  if (!integrator.empty()) request.mutable_scene()->mutable_integrator()->set_class_name(integrator);
  if (!transport.empty()) request.mutable_options()->mutable_transport()->set_class_name(transport);
  return request;
}

TEST(JobSplits, ComeFromTheCapabilitiesOfTheChosenClasses) {
  // The defaults (mean_sample, path) split both ways.
  EXPECT_TRUE(SplitsOf(Request("", ""), kKnown).sample_ranges());
  EXPECT_TRUE(SplitsOf(Request("", ""), kKnown).tiles());
  // A transport that splats: sample shares, no tiles.
  EXPECT_TRUE(SplitsOf(Request("", "light"), kKnown).sample_ranges());
  EXPECT_FALSE(SplitsOf(Request("", "light"), kKnown).tiles());
  // A component process's class that declares pixel_local is tiled too.
  EXPECT_TRUE(SplitsOf(Request("", "py_path"), kKnown).tiles());
  // An integrator that does not declare sample_passes: neither.
  const v1::JobSplits vegas = SplitsOf(Request("vegas", ""), kKnown);
  EXPECT_FALSE(vegas.sample_ranges());
  EXPECT_FALSE(vegas.tiles());
  // A class unknown here, or named by address, declares nothing.
  EXPECT_FALSE(SplitsOf(Request("", "unknown_transport"), kKnown).tiles());
  v1::SubmitRequest by_address = Request("", "path");
  by_address.mutable_options()->mutable_transport()->set_address("127.0.0.1:1");
  EXPECT_FALSE(SplitsOf(by_address, kKnown).tiles());
}

TEST(JobSplits, ARequestsOwnChoiceComesBeforeItsScenes) {
  v1::SubmitRequest request = Request("vegas", "");
  request.mutable_options()->mutable_integrator()->set_class_name("mean_sample");
  EXPECT_TRUE(SplitsOf(request, kKnown).sample_ranges());
}

TEST(JobSplits, AFilterWiderThanAPixelKeepsTheFilmWhole) {
  v1::SubmitRequest request = Request("", "");
  v1::ReconstructionFilter& filter = *request.mutable_scene()->mutable_film()->mutable_filter();
  filter.set_kind(v1::ReconstructionFilter::BOX);
  filter.set_radius(1.5);
  EXPECT_TRUE(SplitsOf(request, kKnown).sample_ranges());
  EXPECT_FALSE(SplitsOf(request, kKnown).tiles());
  filter.set_kind(v1::ReconstructionFilter::GAUSSIAN);
  filter.set_radius(0);
  EXPECT_FALSE(SplitsOf(request, kKnown).tiles());
}

TEST(JobSplits, AShareNeedsAnIntegratorThatRendersSamplePasses) {
  v1::SubmitRequest request = Request("vegas", "");
  EXPECT_NO_THROW(CheckShare(request, SplitsOf(request, kKnown)));
  request.mutable_options()->set_first_sample(4);
  try {
    CheckShare(request, SplitsOf(request, kKnown));
    FAIL() << "a share of a vegas job was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("first_sample needs an integrator"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'vegas' does not"), std::string::npos) << e.what();
  }
  request.mutable_scene()->mutable_integrator()->set_class_name("mean_sample");
  EXPECT_NO_THROW(CheckShare(request, SplitsOf(request, kKnown)));
}

TEST(JobSplits, AnUnknownCapabilityIsRefusedWithTheKnownOnes) {
  try {
    CheckSchema(Class("odd", {"sample_pases"}));
    FAIL() << "an unknown capability was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown capability 'sample_pases'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sample_passes, pixel_local"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(CheckSchema(Class("fine", {kPixelLocalCapability})));
}

// A request at `spp` whose sampler is named by the options, the scene or
// neither (the default, sobol).
v1::SubmitRequest AtSampleCount(uint32_t spp, const std::string& job_sampler, const std::string& scene_sampler) {
  v1::SubmitRequest request = Request("", "");
  request.mutable_options()->set_spp(spp);
  if (!job_sampler.empty()) request.mutable_options()->mutable_sampler()->set_class_name(job_sampler);
  if (!scene_sampler.empty()) request.mutable_scene()->mutable_sampler()->set_class_name(scene_sampler);
  return request;
}

TEST(SubmitWarnings, ASamplerBestAtPowersOfTwoWarnsOfAnyOtherCount) {
  // The default sampler, at 61: the counts on either side are named.
  const std::vector<std::string> warnings = SubmitWarnings(AtSampleCount(61, "", ""), kKnown);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("'sobol'"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("use 32 or 64"), std::string::npos) << warnings[0];
  for (const uint32_t spp : {1u, 2u, 64u, 1u << 20})
    EXPECT_TRUE(SubmitWarnings(AtSampleCount(spp, "", ""), kKnown).empty()) << spp;
  for (const uint32_t spp : {3u, 100u, (1u << 20) - 1})
    EXPECT_EQ(SubmitWarnings(AtSampleCount(spp, "", ""), kKnown).size(), 1u) << spp;
  // The scene's sampler, and the job's over the scene's.
  EXPECT_TRUE(SubmitWarnings(AtSampleCount(100, "", "independent"), kKnown).empty());
  EXPECT_EQ(SubmitWarnings(AtSampleCount(100, "sobol", "independent"), kKnown).size(), 1u);
  EXPECT_TRUE(SubmitWarnings(AtSampleCount(100, "independent", "sobol"), kKnown).empty());
  // A sampler that does not declare it, or one by address, warns of nothing.
  EXPECT_TRUE(SubmitWarnings(AtSampleCount(100, "unknown_sampler", ""), kKnown).empty());
  v1::SubmitRequest by_address = AtSampleCount(100, "sobol", "");
  by_address.mutable_options()->mutable_sampler()->set_address("127.0.0.1:1");
  EXPECT_TRUE(SubmitWarnings(by_address, kKnown).empty());
}

}  // namespace
}  // namespace yarf
