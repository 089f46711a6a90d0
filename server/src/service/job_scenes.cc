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

}  // namespace

JobScenes::JobScenes(InstanceTable& instances) : instances_(instances) {}

bool ServedScene::Splat(const FilmSamples& samples) const {
  std::lock_guard lock(mutex_);
  if (!target_) return false;
  target_->Accumulate(samples);
  return true;
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

void ServedScene::End() {
  std::lock_guard lock(mutex_);
  target_ = nullptr;
}

std::unique_ptr<JobScenes::Lease> JobScenes::Serve(const std::shared_ptr<KernelScene>& scene, RenderTarget& target) {
  std::vector<uint64_t> materials;
  for (uint32_t m = 0; m < scene->MaterialCount(); ++m)
    materials.push_back(instances_.Add(std::make_unique<ServedMaterial>(scene, m)));
  std::lock_guard lock(mutex_);
  uint64_t handle = RandomHandle();
  while (scenes_.contains(handle)) handle = RandomHandle();
  scene->SetServiceHandle(handle);
  scenes_[handle] = std::make_shared<ServedScene>(scene, target, std::move(materials));
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
  served->End();
  for (uint64_t material : served->material_handles()) instances_.Release(material);
}

}  // namespace yarf
