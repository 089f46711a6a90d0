package component

import (
	"io"
	"math/rand/v2"
	"sync"
)

// instance is a live object made by Factory.Create.
type instance struct {
	class *Class
	value any
}

// close ends the instance's resources, if it holds any.
func (i *instance) close() {
	if closer, ok := i.value.(io.Closer); ok {
		closer.Close()
	}
}

// instanceTable maps handles to instances. Handles start at a random
// number and are never reused, so a stale handle cannot name a newer
// instance, not even one of a restarted process.
type instanceTable struct {
	mu       sync.Mutex
	last     uint64
	byHandle map[uint64]*instance
}

func (t *instanceTable) add(i *instance) uint64 {
	t.mu.Lock()
	defer t.mu.Unlock()
	if t.byHandle == nil {
		t.byHandle = map[uint64]*instance{}
		t.last = rand.Uint64N(1 << 62)
	}
	t.last++
	t.byHandle[t.last] = i
	return t.last
}

func (t *instanceTable) find(handle uint64) (*instance, bool) {
	t.mu.Lock()
	defer t.mu.Unlock()
	i, ok := t.byHandle[handle]
	return i, ok
}

func (t *instanceTable) remove(handle uint64) (*instance, bool) {
	t.mu.Lock()
	defer t.mu.Unlock()
	i, ok := t.byHandle[handle]
	delete(t.byHandle, handle)
	return i, ok
}

// removeAll empties the table and returns what it held.
func (t *instanceTable) removeAll() []*instance {
	t.mu.Lock()
	defer t.mu.Unlock()
	all := make([]*instance, 0, len(t.byHandle))
	for _, i := range t.byHandle {
		all = append(all, i)
	}
	t.byHandle = nil
	return all
}
