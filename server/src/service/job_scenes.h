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

// The index of an emitter the scene does not have (a shape that does not
// emit, nothing sampled): 0xFFFFFFFF, as a missed ray's shape.
inline constexpr uint32_t kNoEmitter = 0xFFFFFFFFu;

class ServedScene {
 public:
  // The instances of the scene's materials, emitters (KernelScene's
  // Emitters() order) and media, in the table.
  struct Handles {
    std::vector<uint64_t> materials, emitters, media;
  };
  ServedScene(std::shared_ptr<const KernelScene> scene, Handles handles);

  const KernelScene& scene() const { return *scene_; }
  const Handles& handles() const { return handles_; }
  // The index of `emitter` among the scene's emitters; kNoEmitter for
  // nullptr.
  uint32_t EmitterIndex(const Emitter* emitter) const;
  // Shape `shape`'s surface (Shape and its samplers), made at the first
  // call; throws Error for a shape the scene does not have.
  const ShapeSurface& Surface(uint32_t shape) const;

 private:
  std::shared_ptr<const KernelScene> scene_;
  Handles handles_;
  std::map<const Emitter*, uint32_t> emitter_index_;
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
  std::unique_ptr<Lease> Serve(const std::shared_ptr<KernelScene>& scene);
  // nullptr for an unknown or withdrawn handle.
  std::shared_ptr<const ServedScene> Find(uint64_t handle) const;

 private:
  void Withdraw(uint64_t handle);

  InstanceTable& instances_;
  mutable std::mutex mutex_;
  std::map<uint64_t, std::shared_ptr<ServedScene>> scenes_;
};

}  // namespace yarf
