package component

import (
	"context"
	"errors"
	"fmt"
	"io"
	"log"
	"net"
	"os"
	"os/signal"
	"path/filepath"
	"runtime/debug"
	"syscall"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// maxMessageBytes bounds messages both ways, as yarfd does.
const maxMessageBytes = 256 << 20

// gracefulStopTimeout is how long stopping waits for calls in flight.
const gracefulStopTimeout = 5 * time.Second

// Options configure a component server.
type Options struct {
	// Listen is where to serve: "host:port" (port 0 picks a free one) or
	// "unix:/path".
	Listen string
	// Register, when set, is the address of a yarfd to register with.
	Register string
	// Lease is the registration lease asked of yarfd (whole seconds);
	// 0 takes yarfd's default.
	Lease time.Duration
	// Classes served.
	Classes []Class
	// Origin is what Describe reports as the classes' origin; by default
	// "go <binary name>".
	Origin string
	// Stdout receives the one line announcing the address (default
	// os.Stdout); Stderr the diagnostics (default os.Stderr).
	Stdout, Stderr io.Writer
}

// Server is a component server bound to its address, not yet serving.
type Server struct {
	options  Options
	listener net.Listener
	address  string
	grpc     *grpc.Server
	host     *host
	log      *log.Logger
}

// Listen checks the classes and binds the address.
func Listen(options Options) (*Server, error) {
	program := filepath.Base(os.Args[0])
	if options.Origin == "" {
		options.Origin = "go " + program
	}
	if options.Stdout == nil {
		options.Stdout = os.Stdout
	}
	if options.Stderr == nil {
		options.Stderr = os.Stderr
	}
	host, err := newHost(options.Classes, options.Origin)
	if err != nil {
		return nil, err
	}
	listener, address, err := listen(options.Listen)
	if err != nil {
		return nil, err
	}
	s := &Server{
		options:  options,
		listener: listener,
		address:  address,
		host:     host,
		log:      log.New(options.Stderr, program+": ", log.LstdFlags|log.Lmsgprefix),
	}
	s.grpc = grpc.NewServer(
		grpc.MaxRecvMsgSize(maxMessageBytes),
		grpc.MaxSendMsgSize(maxMessageBytes),
		grpc.ChainUnaryInterceptor(s.recoverPanics),
	)
	yarfv1.RegisterComponentServer(s.grpc, &componentService{host: host})
	yarfv1.RegisterFactoryServer(s.grpc, &factoryService{host: host})
	yarfv1.RegisterRegistryServer(s.grpc, &registryService{host: host})
	yarfv1.RegisterSurfaceModelServer(s.grpc, &surfaceService{host: host})
	yarfv1.RegisterSamplerServer(s.grpc, &samplerService{host: host})
	return s, nil
}

// Address is where the server listens, as others should dial it.
func (s *Server) Address() string { return s.address }

// Serve announces the address on Stdout, registers with yarfd if asked,
// and serves until ctx ends; then it unregisters, finishes the calls in
// flight and releases every instance.
func (s *Server) Serve(ctx context.Context) error {
	served := make(chan error, 1)
	go func() { served <- s.grpc.Serve(s.listener) }()
	fmt.Fprintf(s.options.Stdout, "yarf-component listening on %s\n", s.address)

	var registered *registration
	registering := make(chan struct{})
	registrationCtx, stopRegistering := context.WithCancel(ctx)
	defer stopRegistering()
	if s.options.Register != "" {
		registered = &registration{yarfd: s.options.Register, address: s.address, lease: s.options.Lease, log: s.log}
		go func() {
			defer close(registering)
			registered.run(registrationCtx)
		}()
	} else {
		close(registering)
	}

	var err error
	select {
	case <-ctx.Done():
	case err = <-served:
	}
	stopRegistering()
	<-registering
	if registered != nil {
		registered.unregister()
	}
	s.stop()
	s.host.releaseAll()
	if errors.Is(err, grpc.ErrServerStopped) {
		err = nil
	}
	return err
}

// stop finishes the calls in flight, or cuts them after a while.
func (s *Server) stop() {
	stopped := make(chan struct{})
	go func() {
		s.grpc.GracefulStop()
		close(stopped)
	}()
	select {
	case <-stopped:
	case <-time.After(gracefulStopTimeout):
		s.grpc.Stop()
		<-stopped
	}
}

// recoverPanics turns a panic in a call (a bug in a class) into an
// INTERNAL error for that call, instead of ending the process.
func (s *Server) recoverPanics(ctx context.Context, request any, info *grpc.UnaryServerInfo,
	handler grpc.UnaryHandler) (reply any, err error) {
	defer func() {
		if r := recover(); r != nil {
			s.log.Printf("panic in %s: %v\n%s", info.FullMethod, r, debug.Stack())
			err = status.Errorf(codes.Internal, "%s: panic: %v", info.FullMethod, r)
		}
	}()
	return handler(ctx, request)
}

// Serve listens and serves until SIGINT or SIGTERM: the whole life of a
// component process.
func Serve(options Options) error {
	server, err := Listen(options)
	if err != nil {
		return err
	}
	ctx, stop := signal.NotifyContext(context.Background(), os.Interrupt, syscall.SIGTERM)
	defer stop()
	go func() {
		// A second signal ends the process at once.
		<-ctx.Done()
		stop()
	}()
	return server.Serve(ctx)
}
