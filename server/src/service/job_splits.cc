#include "service/job_splits.h"

#include <algorithm>
#include <bit>
#include <string>

#include "yarf/error.h"

namespace yarf {
namespace {

// Whether the component's class declares `capability`. A component named
// by address has no class description here, so it declares nothing.
bool Declares(const v1::ComponentSpec& spec, const std::vector<ComponentInfo>& known, const char* capability) {
  if (!spec.address().empty()) return false;
  const auto info = std::find_if(known.begin(), known.end(),
                                 [&](const ComponentInfo& c) { return c.class_name == spec.class_name(); });
  return info != known.end() && HasCapability(*info, capability);
}

// A box filter no wider than a pixel: each sample lands in its own pixel.
bool PixelWideFilter(const v1::Film& film) {
  return film.filter().kind() == v1::ReconstructionFilter::BOX && film.filter().radius() <= 0.5f;
}

}  // namespace

v1::ComponentSpec Chosen(const v1::ComponentSpec& job, const v1::ComponentSpec& scene, const char* fallback) {
  if (!job.class_name().empty()) return job;
  if (!scene.class_name().empty()) return scene;
  v1::ComponentSpec spec;
  spec.set_class_name(fallback);
  return spec;
}

v1::JobSplits SplitsOf(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known) {
  const v1::RenderOptions& options = request.options();
  const v1::Scene& scene = request.scene();
  v1::JobSplits splits;
  splits.set_sample_ranges(
      Declares(Chosen(options.integrator(), scene.integrator(), kDefaultIntegrator), known, kSamplePassesCapability));
  splits.set_tiles(splits.sample_ranges() && PixelWideFilter(scene.film()) &&
                   Declares(Chosen(options.transport(), scene.transport(), kDefaultTransport), known,
                            kPixelLocalCapability));
  return splits;
}

void CheckShare(const v1::SubmitRequest& request, const v1::JobSplits& splits) {
  const v1::RenderOptions& options = request.options();
  if ((options.first_sample() == 0 && !options.has_crop()) || splits.sample_ranges()) return;
  const v1::ComponentSpec integrator = Chosen(options.integrator(), request.scene().integrator(), kDefaultIntegrator);
  throw Error(std::string(options.has_crop() ? "crop" : "first_sample") +
              " needs an integrator that renders any range of sample passes (capability '" +
              kSamplePassesCapability + "', as mean_sample), and the job's '" + integrator.class_name() +
              "' does not");
}

std::vector<std::string> SubmitWarnings(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known) {
  std::vector<std::string> warnings;
  const uint32_t spp = request.options().spp();
  const v1::ComponentSpec sampler = Chosen(request.options().sampler(), request.scene().sampler(), kDefaultSampler);
  if (spp > 0 && !std::has_single_bit(spp) && Declares(sampler, known, kPowerOfTwoSamplesCapability)) {
    const std::string below = std::to_string(std::bit_floor(spp)), above = std::to_string(std::bit_ceil(spp));
    warnings.push_back("sampler '" + sampler.class_name() + "' works best with a power of two samples per pixel: at " +
                       std::to_string(spp) + " its " + above +
                       "-point pattern is left incomplete, and the image is noisier than " + std::to_string(spp) +
                       " samples should make it; use " + below + " or " + above);
  }
  return warnings;
}

}  // namespace yarf
