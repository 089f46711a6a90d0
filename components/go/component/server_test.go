package component_test

import (
	"context"
	"net"
	"path/filepath"
	"regexp"
	"slices"
	"strings"
	"sync/atomic"
	"testing"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/codes"
	"yarf.dev/components/go/component"
	"yarf.dev/components/go/component/componenttest"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

type clients struct {
	component yarfv1.ComponentClient
	factory   yarfv1.FactoryClient
	registry  yarfv1.RegistryClient
	surface   yarfv1.SurfaceModelClient
	sampler   yarfv1.SamplerClient
}

func startTestClasses(t *testing.T) (clients, *atomic.Int32) {
	closed := &atomic.Int32{}
	conn := componenttest.Start(t, testClasses(closed)...)
	return newClients(conn), closed
}

func newClients(conn *grpc.ClientConn) clients {
	return clients{
		component: yarfv1.NewComponentClient(conn),
		factory:   yarfv1.NewFactoryClient(conn),
		registry:  yarfv1.NewRegistryClient(conn),
		surface:   yarfv1.NewSurfaceModelClient(conn),
		sampler:   yarfv1.NewSamplerClient(conn),
	}
}

func create(t *testing.T, c clients, class string) uint64 {
	t.Helper()
	reply, err := c.factory.Create(context.Background(), &yarfv1.CreateRequest{ClassName: class})
	if err != nil {
		t.Fatalf("Create %s: %v", class, err)
	}
	return reply.GetHandle()
}

func TestDescribeClass(t *testing.T) {
	c, _ := startTestClasses(t)
	info, err := c.component.Describe(context.Background(), &yarfv1.DescribeRequest{ClassName: "echo_surface"})
	if err != nil {
		t.Fatal(err)
	}
	if info.GetClassName() != "echo_surface" || info.GetVersion() != "1.2.3" || info.GetSummary() != "Echoes wi" ||
		!slices.Equal(info.GetInterfaces(), []string{"yarf.v1.SurfaceModel"}) ||
		info.GetOrigin() != "go component.test" {
		t.Errorf("info %v", info)
	}
	_, err = c.component.Describe(context.Background(), &yarfv1.DescribeRequest{ClassName: "nothing"})
	wantStatus(t, err, codes.NotFound, "'nothing'")
}

func TestListClasses(t *testing.T) {
	c, _ := startTestClasses(t)
	reply, err := c.registry.ListClasses(context.Background(), &yarfv1.ListClassesRequest{})
	if err != nil {
		t.Fatal(err)
	}
	var names []string
	for _, info := range reply.GetClasses() {
		names = append(names, info.GetClassName()+" "+strings.Join(info.GetInterfaces(), ","))
	}
	want := []string{"echo_surface yarf.v1.SurfaceModel", "index_sampler yarf.v1.Sampler"}
	if !slices.Equal(names, want) || len(reply.GetPluginErrors()) != 0 {
		t.Errorf("classes %v, want %v", names, want)
	}
}

func TestRegistryLeavesPluginsAndRegistrationsToYarfd(t *testing.T) {
	c, _ := startTestClasses(t)
	ctx := context.Background()
	_, err := c.registry.LoadPlugin(ctx, &yarfv1.LoadPluginRequest{Path: "x.so"})
	wantStatus(t, err, codes.Unimplemented)
	_, err = c.registry.Register(ctx, &yarfv1.RegisterRequest{Address: "unix:/x"})
	wantStatus(t, err, codes.Unimplemented)
	_, err = c.registry.Unregister(ctx, &yarfv1.UnregisterRequest{Address: "unix:/x"})
	wantStatus(t, err, codes.Unimplemented)
}

func TestCreateDescribeRelease(t *testing.T) {
	c, closed := startTestClasses(t)
	ctx := context.Background()
	reply, err := c.factory.Create(ctx, &yarfv1.CreateRequest{
		ClassName:  "echo_surface",
		Properties: &yarfv1.Properties{Values: map[string]*yarfv1.Property{"gain": floatValue(2)}},
	})
	if err != nil {
		t.Fatal(err)
	}
	handle := reply.GetHandle()
	if handle == 0 || reply.GetInfo().GetClassName() != "echo_surface" {
		t.Fatalf("reply %v", reply)
	}
	if other := create(t, c, "echo_surface"); other == handle || other == 0 {
		t.Errorf("second handle %d, first %d", other, handle)
	}
	info, err := c.component.Describe(ctx, &yarfv1.DescribeRequest{Handle: handle})
	if err != nil || info.GetClassName() != "echo_surface" {
		t.Errorf("Describe(handle): %v, %v", info, err)
	}
	if _, err := c.factory.Release(ctx, &yarfv1.ReleaseRequest{Handle: handle}); err != nil {
		t.Fatal(err)
	}
	if closed.Load() != 1 {
		t.Errorf("Close called %d times on release", closed.Load())
	}
	_, err = c.factory.Release(ctx, &yarfv1.ReleaseRequest{Handle: handle})
	wantStatus(t, err, codes.NotFound)
	_, err = c.component.Describe(ctx, &yarfv1.DescribeRequest{Handle: handle})
	wantStatus(t, err, codes.NotFound)
}

func TestCreateErrors(t *testing.T) {
	c, _ := startTestClasses(t)
	tests := []struct {
		name       string
		class      string
		properties map[string]*yarfv1.Property
		code       codes.Code
		want       string
	}{
		{"unknown class", "nothing", nil, codes.NotFound, "unknown component class 'nothing'"},
		{"unknown key", "echo_surface", map[string]*yarfv1.Property{"gian": floatValue(1)},
			codes.InvalidArgument, "component 'echo_surface' does not understand property 'gian'"},
		{"wrong type", "echo_surface", map[string]*yarfv1.Property{"gain": stringValue("high")},
			codes.InvalidArgument, "component 'echo_surface': property 'gain' must be of type float, not string"},
		{"constructor error", "echo_surface", map[string]*yarfv1.Property{"gain": floatValue(-1)},
			codes.InvalidArgument, "component 'echo_surface': gain must not be negative"},
		{"class reading nothing", "index_sampler", map[string]*yarfv1.Property{"seed": intValue(1)},
			codes.InvalidArgument, "does not understand property 'seed'"},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			_, err := c.factory.Create(context.Background(), &yarfv1.CreateRequest{
				ClassName:  test.class,
				Properties: &yarfv1.Properties{Values: test.properties},
			})
			wantStatus(t, err, test.code, test.want)
		})
	}
}

func TestSurfaceModelCalls(t *testing.T) {
	c, _ := startTestClasses(t)
	ctx := context.Background()
	handle := create(t, c, "echo_surface")
	wi := []float32{1, 2, 3, 4, 5, 6}
	reply, err := c.surface.Evaluate(ctx, &yarfv1.SurfaceQuery{
		Handle: handle,
		Wi:     component.EncodeFloat32(wi, 2, 3),
		Wo:     component.EncodeFloat32(wi, 2, 3),
		Uv:     component.EncodeFloat32(make([]float32, 4), 2, 2),
	})
	if err != nil {
		t.Fatal(err)
	}
	value, rows, err := component.DecodeFloat32(reply.GetValue(), "value", 3)
	if err != nil || rows != 2 || !slices.Equal(value, wi) {
		t.Errorf("value %v (%d rows, %v), want %v", value, rows, err, wi)
	}
	sampled, err := c.surface.Sample(ctx, &yarfv1.SampleSurfaceRequest{
		Handle:  handle,
		Wi:      component.EncodeFloat32(wi, 2, 3),
		Uv:      component.EncodeFloat32(make([]float32, 4), 2, 2),
		Uniform: component.EncodeFloat32(make([]float32, 6), 2, 3),
	})
	if err != nil {
		t.Fatal(err)
	}
	flags, _, err := component.DecodeUint32(sampled.GetFlags(), "flags")
	if err != nil || !slices.Equal(flags, []uint32{component.ScatterReflect, component.ScatterReflect}) {
		t.Errorf("flags %v, %v", flags, err)
	}
	lobes, err := c.surface.Lobes(ctx, &yarfv1.LobesRequest{Handle: handle})
	if err != nil || lobes.GetFlags() != component.ScatterReflect|component.ScatterGlossy {
		t.Errorf("lobes %v, %v", lobes, err)
	}
}

func TestSurfaceModelCallErrors(t *testing.T) {
	c, _ := startTestClasses(t)
	ctx := context.Background()
	handle := create(t, c, "echo_surface")
	sampler := create(t, c, "index_sampler")
	three := component.EncodeFloat32(make([]float32, 3), 1, 3)
	two := component.EncodeFloat32(make([]float32, 2), 1, 2)
	query := func(handle uint64, uv *yarfv1.Array) *yarfv1.SurfaceQuery {
		return &yarfv1.SurfaceQuery{Handle: handle, Wi: three, Wo: three, Uv: uv}
	}

	_, err := c.surface.Evaluate(ctx, query(12345, two))
	wantStatus(t, err, codes.NotFound, "no instance 12345")
	_, err = c.surface.Evaluate(ctx, query(sampler, two))
	wantStatus(t, err, codes.FailedPrecondition, "('index_sampler') does not implement yarf.v1.SurfaceModel")
	_, err = c.surface.Evaluate(ctx, query(handle, nil))
	wantStatus(t, err, codes.InvalidArgument, "yarf.v1.SurfaceModel: uv: expected a FLOAT32 array")
	_, err = c.surface.Evaluate(ctx, query(handle, component.EncodeFloat32(make([]float32, 4), 2, 2)))
	wantStatus(t, err, codes.InvalidArgument, "uv has 2 rows, the batch 1")
	_, err = c.surface.Evaluate(ctx, query(handle, component.EncodeFloat32([]float32{-1, 0}, 1, 2)))
	wantStatus(t, err, codes.InvalidArgument, "yarf.v1.SurfaceModel: uv -1 is refused")
	_, err = c.surface.Sample(ctx, &yarfv1.SampleSurfaceRequest{Handle: handle, Wi: three, Uv: two, Uniform: three, Allowed: 99})
	wantStatus(t, err, codes.Unavailable, "try later")
	_, err = c.surface.Pdf(ctx, query(handle, two))
	wantStatus(t, err, codes.Internal, "panic: Pdf is broken")
	// The panic ended one call, not the server.
	if _, err := c.surface.Lobes(ctx, &yarfv1.LobesRequest{Handle: handle}); err != nil {
		t.Errorf("after a panic: %v", err)
	}
}

func TestSamplerGenerate(t *testing.T) {
	c, _ := startTestClasses(t)
	ctx := context.Background()
	handle := create(t, c, "index_sampler")
	reply, err := c.sampler.Generate(ctx, &yarfv1.GenerateSamplesRequest{Handle: handle, FirstIndex: 10, Count: 2, Dimensions: 3})
	if err != nil {
		t.Fatal(err)
	}
	points, rows, err := component.DecodeFloat32(reply.GetPoints(), "points", 3)
	want := []float32{0.010, 0.011, 0.012, 0.011, 0.012, 0.013}
	if err != nil || rows != 2 || !slices.Equal(points, want) {
		t.Errorf("points %v (%d rows, %v), want %v", points, rows, err, want)
	}
	_, err = c.sampler.Generate(ctx, &yarfv1.GenerateSamplesRequest{Handle: handle, Count: 1 << 20, Dimensions: 1 << 10})
	wantStatus(t, err, codes.InvalidArgument, "exceeds")
	_, err = c.sampler.Generate(ctx, &yarfv1.GenerateSamplesRequest{Handle: create(t, c, "echo_surface"), Count: 1, Dimensions: 1})
	wantStatus(t, err, codes.FailedPrecondition, "does not implement yarf.v1.Sampler")
}

func TestListenAnnouncesTheRealPort(t *testing.T) {
	stdout := make(chanWriter, 1)
	address := componenttest.Serve(t, component.Options{
		Listen:  "127.0.0.1:0",
		Classes: testClasses(&atomic.Int32{}),
		Stdout:  stdout,
	})
	var line string
	select {
	case line = <-stdout:
	case <-time.After(10 * time.Second):
		t.Fatal("nothing announced")
	}
	if !regexp.MustCompile(`^yarf-component listening on 127\.0\.0\.1:[1-9][0-9]*\n$`).MatchString(line) ||
		line != "yarf-component listening on "+address+"\n" {
		t.Fatalf("announced %q, address %q", line, address)
	}
	c := newClients(componenttest.Dial(t, address))
	if _, err := c.registry.ListClasses(context.Background(), &yarfv1.ListClassesRequest{}); err != nil {
		t.Error(err)
	}
}

// chanWriter passes on each write, e.g. a line printed by a server.
type chanWriter chan string

func (w chanWriter) Write(p []byte) (int, error) {
	w <- string(p)
	return len(p), nil
}

func TestListenRejectsBadClasses(t *testing.T) {
	echo := testClasses(&atomic.Int32{})[0]
	notAnInterface := func(*component.Properties) (*strings.Builder, error) { return nil, nil }
	tests := []struct {
		name    string
		classes []component.Class
		want    string
	}{
		{"none", nil, "no class to serve"},
		{"twice", []component.Class{echo, echo}, "class echo_surface is given twice"},
		{"name", []component.Class{component.NewClass("Echo", "1.0.0", "", notAnInterface)}, "not lower_snake_case"},
		{"version", []component.Class{component.NewClass("echo", "1.0", "", notAnInterface)}, "not MAJOR.MINOR.PATCH"},
		{"no interface", []component.Class{component.NewClass("echo", "1.0.0", "", notAnInterface)},
			"implements no interface"},
		{"parameter type", []component.Class{echo.WithParameters(component.Parameter{Name: "gain", Type: "number"})},
			`parameter "gain": unknown type "number"`},
		{"parameter twice", []component.Class{echo.WithParameters(
			component.Parameter{Name: "gain", Type: "float"}, component.Parameter{Name: "gain", Type: "float"})},
			`declares parameter "gain" twice`},
		{"parameter bounds", []component.Class{echo.WithParameters(
			component.Parameter{Name: "gain", Type: "float", Min: component.Bound(1), Max: component.Bound(0)})},
			"least value is above its most"},
		{"capability", []component.Class{echo.WithCapabilities("pixel_locale")},
			`declares an unknown capability "pixel_locale"`},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			dir := componenttest.SocketDir(t)
			_, err := component.Listen(component.Options{Listen: "unix:" + dir + "/s", Classes: test.classes})
			if err == nil || !strings.Contains(err.Error(), test.want) {
				t.Errorf("error %v, want %q", err, test.want)
			}
		})
	}
}

func TestListenReplacesAStaleSocket(t *testing.T) {
	path := filepath.Join(componenttest.SocketDir(t), "component.sock")
	// A socket file left by a process that ended without removing it.
	stale, err := net.ListenUnix("unix", &net.UnixAddr{Name: path, Net: "unix"})
	if err != nil {
		t.Fatal(err)
	}
	stale.SetUnlinkOnClose(false)
	stale.Close()

	address := componenttest.Serve(t, component.Options{Listen: "unix:" + path, Classes: testClasses(&atomic.Int32{})})
	if address != "unix:"+path {
		t.Errorf("address %q", address)
	}
	// A socket in use is not taken over.
	_, err = component.Listen(component.Options{Listen: "unix:" + path, Classes: testClasses(&atomic.Int32{})})
	if err == nil || !strings.Contains(err.Error(), "in use") {
		t.Errorf("second listener: %v", err)
	}
}
