#include "yarf/support/per_thread.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <vector>

namespace yarf {
namespace {

struct Buffers {
  std::vector<int> values;
  int holders = 0;  // leases using these buffers at once
};

TEST(PerThread, AThreadGetsItsBuffersBackWithWhatTheyHeld) {
  PerThread<Buffers> per_thread;
  const Buffers* first = nullptr;
  {
    const PerThread<Buffers>::Lease lease(per_thread);
    (*lease).values.assign(100, 7);
    first = &*lease;
  }
  const PerThread<Buffers>::Lease again(per_thread);
  EXPECT_EQ(&*again, first);
  EXPECT_EQ((*again).values.size(), 100u);
}

TEST(PerThread, ALeaseTakenInsideAnotherOnTheSameThreadGetsBuffersOfItsOwn) {
  PerThread<Buffers> per_thread;
  const PerThread<Buffers>::Lease outer(per_thread);
  {
    const PerThread<Buffers>::Lease inner(per_thread);
    EXPECT_NE(&*inner, &*outer);
  }
  // The inner lease's end leaves the outer's buffers held.
  const PerThread<Buffers>::Lease another(per_thread);
  EXPECT_NE(&*another, &*outer);
}

TEST(PerThread, NestedParallelLoopsNeverShareBuffers) {
  // A thread waiting in the inner loop may run other outer iterations:
  // no two leases alive at once may use the same buffers.
  PerThread<Buffers> per_thread;
  std::atomic<int> shared{0};
  tbb::parallel_for(0, 64, [&](int) {
    const PerThread<Buffers>::Lease outer(per_thread);
    if (++(*outer).holders != 1) ++shared;
    tbb::parallel_for(0, 64, [&](int) {
      const PerThread<Buffers>::Lease inner(per_thread);
      if (++(*inner).holders != 1) ++shared;
      --(*inner).holders;
    });
    --(*outer).holders;
  });
  EXPECT_EQ(shared.load(), 0);
}

}  // namespace
}  // namespace yarf
