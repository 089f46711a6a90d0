// The scenes of running jobs, served by handle to transports that live in
// other processes (the JobScene and Intersect services): while a job
// renders, its scene, its materials (as SurfaceModel instances of the
// instance table) and its film are reachable under one handle.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "kernel/scene.h"
#include "service/component_service.h"
#include "yarf/transport.h"

namespace yarf {

class ServedScene {
 public:
  ServedScene(std::shared_ptr<const KernelScene> scene, RenderTarget& target, std::vector<uint64_t> materials)
      : scene_(std::move(scene)), target_(&target), material_handles_(std::move(materials)) {}

  const KernelScene& scene() const { return *scene_; }
  // The instance handle of material m of the scene.
  const std::vector<uint64_t>& material_handles() const { return material_handles_; }
  // Adds splats to the job's film; false once the job has ended.
  bool Splat(const FilmSamples& samples) const;
  // Shape `shape`'s surface (Shape and its samplers), made at the first
  // call; throws Error for a shape the scene does not have.
  const ShapeSurface& Surface(uint32_t shape) const;
  void End();

 private:
  std::shared_ptr<const KernelScene> scene_;
  mutable std::mutex mutex_;
  RenderTarget* target_;
  std::vector<uint64_t> material_handles_;
  mutable std::mutex surfaces_mutex_;
  mutable std::map<uint32_t, std::unique_ptr<ShapeSurface>> surfaces_;
};

class JobScenes {
 public:
  explicit JobScenes(InstanceTable& instances);

  // Withdraws the scene (and its material instances) when it ends.
  class Lease {
   public:
    Lease(JobScenes& table, uint64_t handle) : table_(table), handle_(handle) {}
    ~Lease() { table_.Withdraw(handle_); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;

   private:
    JobScenes& table_;
    uint64_t handle_;
  };

  // Serves `scene` (whose ServiceHandle is set) while the lease lives.
  std::unique_ptr<Lease> Serve(const std::shared_ptr<KernelScene>& scene, RenderTarget& target);
  // nullptr for an unknown or withdrawn handle.
  std::shared_ptr<const ServedScene> Find(uint64_t handle) const;

 private:
  void Withdraw(uint64_t handle);

  InstanceTable& instances_;
  mutable std::mutex mutex_;
  std::map<uint64_t, std::shared_ptr<ServedScene>> scenes_;
};

}  // namespace yarf
