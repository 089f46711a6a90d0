package component

import (
	"context"
	"log"
	"sync/atomic"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/credentials/insecure"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

const (
	// leaseWhenUnknown stands for the lease before yarfd has granted one,
	// when none was asked for (and if yarfd ever grants 0).
	leaseWhenUnknown  = 30 * time.Second
	firstRetry        = time.Second
	registerTimeout   = 10 * time.Second
	unregisterTimeout = 2 * time.Second
)

// registration keeps a component process registered with a yarfd: it
// calls Registry.Register at once and again every third of the lease, and
// retries (sooner, backing off) while yarfd cannot be reached or refuses.
type registration struct {
	yarfd   string // where yarfd listens
	address string // where this process listens
	lease   time.Duration
	log     *log.Logger

	// registered is set once any Register succeeded.
	registered atomic.Bool
}

// run registers until ctx ends.
func (r *registration) run(ctx context.Context) {
	retry := firstRetry
	failing := false
	for {
		granted, err := r.register(ctx)
		if ctx.Err() != nil {
			return
		}
		var wait time.Duration
		if err != nil {
			wait = min(retry, r.renewal(r.lease))
			retry *= 2
			failing = true
			r.log.Printf("registering with %s failed: %v; retrying in %s", r.yarfd, err, wait)
		} else {
			if failing || !r.registered.Load() {
				r.log.Printf("registered with %s as %s (lease %s)", r.yarfd, r.address, granted)
			}
			r.registered.Store(true)
			wait = r.renewal(granted)
			retry = firstRetry
			failing = false
		}
		select {
		case <-ctx.Done():
			return
		case <-time.After(wait):
		}
	}
}

// renewal is how long to wait before registering again under a lease.
func (r *registration) renewal(lease time.Duration) time.Duration {
	if lease <= 0 {
		lease = leaseWhenUnknown
	}
	return max(lease/3, 100*time.Millisecond)
}

// register makes one Register call and returns the lease granted.
func (r *registration) register(ctx context.Context) (time.Duration, error) {
	ctx, cancel := context.WithTimeout(ctx, registerTimeout)
	defer cancel()
	var granted time.Duration
	err := r.call(func(client yarfv1.RegistryClient) error {
		reply, err := client.Register(ctx, &yarfv1.RegisterRequest{
			Address:      r.address,
			LeaseSeconds: leaseSeconds(r.lease),
		})
		granted = time.Duration(reply.GetLeaseSeconds()) * time.Second
		return err
	})
	return granted, err
}

// unregister ends the registration, best effort, if there is one.
func (r *registration) unregister() {
	if !r.registered.Load() {
		return
	}
	ctx, cancel := context.WithTimeout(context.Background(), unregisterTimeout)
	defer cancel()
	err := r.call(func(client yarfv1.RegistryClient) error {
		_, err := client.Unregister(ctx, &yarfv1.UnregisterRequest{Address: r.address})
		return err
	})
	if err != nil {
		r.log.Printf("unregistering from %s failed: %v", r.yarfd, err)
		return
	}
	r.log.Printf("unregistered from %s", r.yarfd)
}

// call runs one RPC on a fresh connection: calls are a lease period apart,
// and a fresh connection fails fast with the real cause while yarfd is
// down, then succeeds as soon as it is up, with no reconnection backoff
// in between.
func (r *registration) call(rpc func(yarfv1.RegistryClient) error) error {
	conn, err := grpc.NewClient(r.yarfd, grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		return err
	}
	defer conn.Close()
	return rpc(yarfv1.NewRegistryClient(conn))
}

// leaseSeconds rounds a lease up to whole seconds, as Register takes it.
func leaseSeconds(lease time.Duration) uint32 {
	if lease <= 0 {
		return 0
	}
	return uint32((lease + time.Second - 1) / time.Second)
}
