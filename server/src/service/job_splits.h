// Which components a job runs, how it may be divided and what its
// submitter is warned of: read from the capabilities their classes
// declare, never from their names.
#pragma once

#include <string>
#include <vector>

#include "yarf/component.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

// The classes a job runs when neither its options nor its scene name one.
inline constexpr char kDefaultIntegrator[] = "mean_sample";
inline constexpr char kDefaultTransport[] = "path";
inline constexpr char kDefaultSampler[] = "sobol";

// The job's choice, else the scene's, else the default class.
v1::ComponentSpec Chosen(const v1::ComponentSpec& job, const v1::ComponentSpec& scene, const char* fallback);

// How `request`'s job may be divided (proto JobSplits), its classes looked
// up in `known`; a class not there (or named with an address) declares
// nothing, so its job is not divided.
v1::JobSplits SplitsOf(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known);

// Throws Error when `request` asks for a share of its job (first_sample,
// crop) that its integrator cannot render alone.
void CheckShare(const v1::SubmitRequest& request, const v1::JobSplits& splits);

// What the accepted `request` runs as asked but not at its best, for
// Submit's reply: a sample count that is not a power of two for a sampler
// whose points want one (kPowerOfTwoSamplesCapability).
std::vector<std::string> SubmitWarnings(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known);

}  // namespace yarf
