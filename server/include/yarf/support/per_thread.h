// Buffers a component keeps per thread, so that the batches a thread
// evaluates one after another reuse them instead of allocating their own.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <optional>

namespace yarf {

template <typename Buffers>
class PerThread {
  struct Slot {
    Buffers buffers;
    bool busy = false;
  };

 public:
  // The calling thread's buffers for the length of one batch. A thread
  // that waits inside a component's own parallel loop may be handed
  // another batch meanwhile: that batch, finding the slot busy, gets
  // buffers of its own.
  class Lease {
   public:
    explicit Lease(PerThread& owner) : slot_(owner.slots_.local()) {
      if (slot_.busy) {
        used_ = &own_.emplace();
        return;
      }
      slot_.busy = true;
      used_ = &slot_.buffers;
    }
    ~Lease() {
      if (used_ == &slot_.buffers) slot_.busy = false;
    }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Buffers& operator*() const { return *used_; }

   private:
    Slot& slot_;
    std::optional<Buffers> own_;
    Buffers* used_ = nullptr;
  };

 private:
  tbb::enumerable_thread_specific<Slot> slots_;
};

}  // namespace yarf
