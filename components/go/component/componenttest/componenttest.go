// Package componenttest runs a component server inside a test, on a unix
// socket in a temporary directory, so that a class can be tested over a
// real gRPC connection as yarfd will call it.
package componenttest

import (
	"context"
	"io"
	"os"
	"path/filepath"
	"strings"
	"testing"

	"google.golang.org/grpc"
	"google.golang.org/grpc/credentials/insecure"
	"yarf.dev/components/go/component"
)

// Start serves the classes and returns a connection to them; both end
// with the test.
func Start(t testing.TB, classes ...component.Class) *grpc.ClientConn {
	t.Helper()
	address := Serve(t, component.Options{Classes: classes})
	return Dial(t, address)
}

// Serve runs a server with these options until the test ends and returns
// its address. An empty Listen becomes a socket in a new temporary
// directory; Stderr, when nil, goes to the test log.
func Serve(t testing.TB, options component.Options) string {
	t.Helper()
	if options.Listen == "" {
		options.Listen = "unix:" + filepath.Join(SocketDir(t), "component.sock")
	}
	if options.Stdout == nil {
		options.Stdout = io.Discard
	}
	if options.Stderr == nil {
		options.Stderr = testLog{t}
	}
	server, err := component.Listen(options)
	if err != nil {
		t.Fatalf("component.Listen: %v", err)
	}
	ctx, cancel := context.WithCancel(context.Background())
	done := make(chan error, 1)
	go func() { done <- server.Serve(ctx) }()
	t.Cleanup(func() {
		cancel()
		if err := <-done; err != nil {
			t.Errorf("component server: %v", err)
		}
	})
	return server.Address()
}

// Dial connects to a component server; the connection is closed when
// the test ends.
func Dial(t testing.TB, address string) *grpc.ClientConn {
	t.Helper()
	conn, err := grpc.NewClient(address, grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		t.Fatalf("dialing %s: %v", address, err)
	}
	t.Cleanup(func() { conn.Close() })
	return conn
}

// SocketDir is a new temporary directory, removed when the test ends,
// with a path short enough for unix sockets (t.TempDir's can exceed
// their 108-byte limit).
func SocketDir(t testing.TB) string {
	t.Helper()
	dir, err := os.MkdirTemp("", "yarf-")
	if err != nil {
		t.Fatal(err)
	}
	t.Cleanup(func() { os.RemoveAll(dir) })
	return dir
}

// testLog writes a server's diagnostics to the test log, a line at a time.
type testLog struct{ t testing.TB }

func (l testLog) Write(p []byte) (int, error) {
	l.t.Log(strings.TrimRight(string(p), "\n"))
	return len(p), nil
}
