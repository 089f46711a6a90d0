#include "service/job_scenes.h"

#include "yarf/error.h"

namespace yarf {
namespace {

// A material of a served scene as an instance of the table: it forwards to
// the scene's model and keeps the scene alive while a call is in flight.
class ServedMaterial final : public SurfaceModel {
 public:
  ServedMaterial(std::shared_ptr<const KernelScene> scene, uint32_t material)
      : scene_(std::move(scene)), model_(scene_->Material(material)) {
    SetInfo(model_.Describe());
  }
  void Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const SurfacePoints& at, std::span<float> value) const override {
    model_.Evaluate(mode, wi, wo, at, value);
  }
  void Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    model_.Sample(mode, wi, at, uniform, allowed, wo, weight, pdf, flags);
  }
  void Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
           std::span<float> pdf) const override {
    model_.Pdf(wi, wo, at, pdf);
  }
  uint32_t Lobes() const override { return model_.Lobes(); }

 private:
  std::shared_ptr<const KernelScene> scene_;
  const SurfaceModel& model_;
};

// An emitter of a served scene, likewise.
class ServedEmitter final : public Emitter {
 public:
  ServedEmitter(std::shared_ptr<const KernelScene> scene, const Emitter& emitter)
      : scene_(std::move(scene)), emitter_(emitter) {
    SetInfo(emitter_.Describe());
  }
  void Radiance(std::span<const float> w, const SurfacePoints& at, std::span<float> radiance) const override {
    emitter_.Radiance(w, at, radiance);
  }
  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override {
    emitter_.SampleDirection(uniform, w, pdf);
  }
  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    emitter_.PdfDirection(w, pdf);
  }

 private:
  std::shared_ptr<const KernelScene> scene_;
  const Emitter& emitter_;
};

// A medium of a served scene, likewise.
class ServedMedium final : public Medium {
 public:
  ServedMedium(std::shared_ptr<const KernelScene> scene, uint32_t medium)
      : scene_(std::move(scene)), medium_(scene_->MediumAt(medium)) {
    SetInfo(medium_.Describe());
  }
  void Majorants(std::span<const float> origin, std::span<const float> direction, std::span<const float> tmax,
                 MajorantSegments& out) const override {
    medium_.Majorants(origin, direction, tmax, out);
  }
  void Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                    std::span<float> emission) const override {
    medium_.Coefficients(position, sigma_a, sigma_s, emission);
  }
  bool Emits() const override { return medium_.Emits(); }
  void EvaluatePhase(std::span<const float> wi, std::span<const float> wo, std::span<const float> position,
                     std::span<float> value, std::span<float> pdf) const override {
    medium_.EvaluatePhase(wi, wo, position, value, pdf);
  }
  void SamplePhase(std::span<const float> wi, std::span<const float> position, std::span<const float> uniform,
                   std::span<float> wo, std::span<float> weight, std::span<float> pdf) const override {
    medium_.SamplePhase(wi, position, uniform, wo, weight, pdf);
  }

 private:
  std::shared_ptr<const KernelScene> scene_;
  const Medium& medium_;
};

}  // namespace

JobScenes::JobScenes(InstanceTable& instances) : instances_(instances) {}

ServedScene::ServedScene(std::shared_ptr<const KernelScene> scene, Handles handles)
    : scene_(std::move(scene)), handles_(std::move(handles)) {
  const std::vector<const Emitter*> emitters = scene_->Emitters();
  for (uint32_t i = 0; i < emitters.size(); ++i) emitter_index_[emitters[i]] = i;
}

uint32_t ServedScene::EmitterIndex(const Emitter* emitter) const {
  auto it = emitter_index_.find(emitter);
  return it == emitter_index_.end() ? kNoEmitter : it->second;
}

const ShapeSurface& ServedScene::Surface(uint32_t shape) const {
  if (shape >= scene_->ShapeCount())
    throw Error("shape " + std::to_string(shape) + " is not one of the scene's " +
                std::to_string(scene_->ShapeCount()) + " shapes");
  std::lock_guard lock(surfaces_mutex_);
  auto& surface = surfaces_[shape];
  if (!surface) surface = scene_->MakeSurface(shape);
  return *surface;
}

std::unique_ptr<JobScenes::Lease> JobScenes::Serve(const std::shared_ptr<KernelScene>& scene) {
  ServedScene::Handles handles;
  for (uint32_t m = 0; m < scene->MaterialCount(); ++m)
    handles.materials.push_back(instances_.Add(std::make_unique<ServedMaterial>(scene, m)));
  for (const Emitter* emitter : scene->Emitters())
    handles.emitters.push_back(instances_.Add(std::make_unique<ServedEmitter>(scene, *emitter)));
  for (uint32_t m = 0; m < scene->MediumCount(); ++m)
    handles.media.push_back(instances_.Add(std::make_unique<ServedMedium>(scene, m)));
  std::lock_guard lock(mutex_);
  uint64_t handle = RandomHandle();
  while (scenes_.contains(handle)) handle = RandomHandle();
  scene->SetServiceHandle(handle);
  scenes_[handle] = std::make_shared<ServedScene>(scene, std::move(handles));
  return std::make_unique<Lease>(*this, handle);
}

std::shared_ptr<const ServedScene> JobScenes::Find(uint64_t handle) const {
  std::lock_guard lock(mutex_);
  auto it = scenes_.find(handle);
  return it == scenes_.end() ? nullptr : it->second;
}

void JobScenes::Withdraw(uint64_t handle) {
  std::shared_ptr<ServedScene> served;
  {
    std::lock_guard lock(mutex_);
    auto it = scenes_.find(handle);
    if (it == scenes_.end()) return;
    served = std::move(it->second);
    scenes_.erase(it);
  }
  const ServedScene::Handles& handles = served->handles();
  for (const auto* kind : {&handles.materials, &handles.emitters, &handles.media})
    for (uint64_t instance : *kind) instances_.Release(instance);
}

}  // namespace yarf
