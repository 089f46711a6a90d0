// "sample_count", the parameter of the samplers whose points come in
// blocks of a fixed size (stratified, latin_hypercube, hammersley): its
// declaration and its reading, written once.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"

namespace yarf {

// A float can resolve at most 2^24 strata of [0, 1).
inline constexpr int64_t kMaxSampleCount = int64_t(1) << 24;
inline constexpr int64_t kDefaultSampleCount = 16;

// The declaration; `doc` says what the points of a block form.
inline Parameter SampleCountParameter(std::string doc) {
  return Parameter::Int("sample_count").Default(kDefaultSampleCount).Range(1, kMaxSampleCount).Doc(std::move(doc));
}

// The value, checked; `sampler` names the class in the message.
inline uint32_t ReadSampleCount(const Properties& props, const std::string& sampler) {
  const int64_t count = props.Int("sample_count", kDefaultSampleCount);
  if (count < 1 || count > kMaxSampleCount)
    throw Error(sampler + ": property 'sample_count' must lie in [1, " + std::to_string(kMaxSampleCount) +
                "], got " + std::to_string(count));
  return uint32_t(count);
}

}  // namespace yarf
