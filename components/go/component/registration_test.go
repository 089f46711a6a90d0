package component_test

import (
	"context"
	"net"
	"path/filepath"
	"strings"
	"sync"
	"sync/atomic"
	"testing"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/credentials/insecure"
	"yarf.dev/components/go/component"
	"yarf.dev/components/go/component/componenttest"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// fakeYarfd takes registrations as yarfd does: it lists the classes at
// the address registered before answering.
type fakeYarfd struct {
	yarfv1.UnimplementedRegistryServer
	registered   chan *yarfv1.RegisterRequest
	unregistered chan *yarfv1.UnregisterRequest
}

func (f *fakeYarfd) Register(ctx context.Context, request *yarfv1.RegisterRequest) (*yarfv1.RegisterReply, error) {
	conn, err := grpc.NewClient(request.GetAddress(), grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		return nil, err
	}
	defer conn.Close()
	classes, err := yarfv1.NewRegistryClient(conn).ListClasses(ctx, &yarfv1.ListClassesRequest{})
	if err != nil {
		return nil, err
	}
	f.registered <- request
	return &yarfv1.RegisterReply{LeaseSeconds: request.GetLeaseSeconds(), Classes: classes.GetClasses()}, nil
}

func (f *fakeYarfd) Unregister(_ context.Context, request *yarfv1.UnregisterRequest) (*yarfv1.UnregisterReply, error) {
	f.unregistered <- request
	return &yarfv1.UnregisterReply{}, nil
}

// lockedBuffer collects a server's log lines.
type lockedBuffer struct {
	mu   sync.Mutex
	text strings.Builder
}

func (b *lockedBuffer) Write(p []byte) (int, error) {
	b.mu.Lock()
	defer b.mu.Unlock()
	return b.text.Write(p)
}

func (b *lockedBuffer) String() string {
	b.mu.Lock()
	defer b.mu.Unlock()
	return b.text.String()
}

// waitFor polls until condition holds, or fails the test after a while.
func waitFor(t *testing.T, what string, condition func() bool) {
	t.Helper()
	for deadline := time.Now().Add(10 * time.Second); !condition(); time.Sleep(20 * time.Millisecond) {
		if time.Now().After(deadline) {
			t.Fatalf("timed out waiting for %s", what)
		}
	}
}

func receive[T any](t *testing.T, what string, from <-chan T) T {
	t.Helper()
	select {
	case v := <-from:
		return v
	case <-time.After(10 * time.Second):
		t.Fatalf("timed out waiting for %s", what)
		panic("unreachable")
	}
}

func TestRegistrationLifecycle(t *testing.T) {
	dir := componenttest.SocketDir(t)
	yarfdAddress := "unix:" + filepath.Join(dir, "yarfd.sock")
	var log lockedBuffer
	server, err := component.Listen(component.Options{
		Listen:   "unix:" + filepath.Join(dir, "component.sock"),
		Register: yarfdAddress,
		Lease:    time.Second,
		Classes:  testClasses(&atomic.Int32{}),
		Stderr:   &log,
		Stdout:   chanWriter(make(chan string, 1)),
	})
	if err != nil {
		t.Fatal(err)
	}
	ctx, cancel := context.WithCancel(context.Background())
	defer cancel()
	served := make(chan error, 1)
	go func() { served <- server.Serve(ctx) }()

	// yarfd is not up yet: each attempt fails with one line.
	waitFor(t, "two failures logged", func() bool { return strings.Count(log.String(), "failed") >= 2 })
	for _, line := range strings.Split(strings.TrimSpace(log.String()), "\n") {
		if !strings.Contains(line, "registering with "+yarfdAddress+" failed: ") || !strings.Contains(line, "retrying in") {
			t.Errorf("unexpected log line %q", line)
		}
	}

	yarfd := &fakeYarfd{
		registered:   make(chan *yarfv1.RegisterRequest, 100),
		unregistered: make(chan *yarfv1.UnregisterRequest, 1),
	}
	listener, err := net.Listen("unix", strings.TrimPrefix(yarfdAddress, "unix:"))
	if err != nil {
		t.Fatal(err)
	}
	yarfdServer := grpc.NewServer()
	yarfv1.RegisterRegistryServer(yarfdServer, yarfd)
	go yarfdServer.Serve(listener)
	defer yarfdServer.Stop()

	// Registered, then renewed within a lease.
	first := receive(t, "Register", yarfd.registered)
	if first.GetAddress() != server.Address() || first.GetLeaseSeconds() != 1 {
		t.Errorf("Register(%v), want address %s, lease 1", first, server.Address())
	}
	start := time.Now()
	receive(t, "a renewal", yarfd.registered)
	if elapsed := time.Since(start); elapsed > time.Second {
		t.Errorf("renewed after %s, past the lease", elapsed)
	}
	if !strings.Contains(log.String(), "registered with "+yarfdAddress) {
		t.Errorf("no registration logged:\n%s", log.String())
	}

	// Stopping unregisters.
	cancel()
	if err := receive(t, "Serve to return", served); err != nil {
		t.Errorf("Serve: %v", err)
	}
	select {
	case request := <-yarfd.unregistered:
		if request.GetAddress() != server.Address() {
			t.Errorf("Unregister(%v)", request)
		}
	default:
		t.Error("stopped without unregistering")
	}
	if !strings.Contains(log.String(), "unregistered from "+yarfdAddress) {
		t.Errorf("no unregistration logged:\n%s", log.String())
	}
}

func TestNoUnregisterWithoutRegistration(t *testing.T) {
	dir := componenttest.SocketDir(t)
	var log lockedBuffer
	server, err := component.Listen(component.Options{
		Listen:   "unix:" + filepath.Join(dir, "component.sock"),
		Register: "unix:" + filepath.Join(dir, "nobody.sock"),
		Classes:  testClasses(&atomic.Int32{}),
		Stderr:   &log,
		Stdout:   chanWriter(make(chan string, 1)),
	})
	if err != nil {
		t.Fatal(err)
	}
	ctx, cancel := context.WithCancel(context.Background())
	served := make(chan error, 1)
	go func() { served <- server.Serve(ctx) }()
	waitFor(t, "a failure logged", func() bool { return strings.Contains(log.String(), "failed") })
	cancel()
	if err := receive(t, "Serve to return", served); err != nil {
		t.Errorf("Serve: %v", err)
	}
	if strings.Contains(log.String(), "unregister") {
		t.Errorf("unregistered without a registration:\n%s", log.String())
	}
}
