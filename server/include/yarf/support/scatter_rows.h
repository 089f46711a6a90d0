// Reading and writing the rows of SurfaceModel's batch calls (surface.h),
// so each model in bsdfs/*.cc states only what one row computes. Row k
// holds floats 3k..3k+2 of a direction array, entry k of pdf and flags,
// and the values of textured properties at uv row k (TexturedValue::At).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "yarf/surface.h"
#include "yarf/vecmath.h"

namespace yarf {

// value[k] = value_of(k, wi[k], wo[k]) for each row: Evaluate's loop.
template <typename ValueOf>
void EvaluateEach(std::span<const float> wi, std::span<const float> wo, std::span<float> value,
                  ValueOf value_of) {
  const size_t count = wi.size() / 3;
  for (size_t k = 0; k < count; ++k)
    value_of(k, Vec3::Load(&wi[3 * k]), Vec3::Load(&wo[3 * k])).Store(&value[3 * k]);
}

// pdf[k] = pdf_of(k, wi[k], wo[k]) for each row: Pdf's loop.
template <typename PdfOf>
void PdfEach(std::span<const float> wi, std::span<const float> wo, std::span<float> pdf,
             PdfOf pdf_of) {
  const size_t count = wi.size() / 3;
  for (size_t k = 0; k < count; ++k)
    pdf[k] = pdf_of(k, Vec3::Load(&wi[3 * k]), Vec3::Load(&wo[3 * k]));
}

// Sample's four outputs, written a row at a time.
struct SampleRows {
  std::span<float> wo, weight, pdf;
  std::span<uint32_t> flags;

  void Store(size_t k, Vec3 direction, Vec3 w, float density, uint32_t lobe) const {
    direction.Store(&wo[3 * k]);
    w.Store(&weight[3 * k]);
    pdf[k] = density;
    flags[k] = lobe;
  }

  // What every model writes when it draws nothing: callers test pdf or
  // flags, and the zero weight keeps a path that ignores both dark.
  void StoreNoSample(size_t k) const { Store(k, Vec3(), Vec3(), 0.0f, kScatterNone); }
};

}  // namespace yarf
