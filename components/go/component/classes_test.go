package component_test

import (
	"errors"
	"strings"
	"sync/atomic"
	"testing"

	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	"yarf.dev/components/go/component"
)

// Classes the tests serve, each showing one behaviour of the server.

// echoSurface answers Evaluate with wi scaled by its gain, fails on
// request (a uv of -1, allowed 99), and panics in Pdf.
type echoSurface struct {
	gain   float32
	closed *atomic.Int32
}

func newEchoSurface(closed *atomic.Int32) func(*component.Properties) (*echoSurface, error) {
	return func(p *component.Properties) (*echoSurface, error) {
		gain := p.Float("gain", 1)
		if gain < 0 {
			return nil, errors.New("gain must not be negative")
		}
		return &echoSurface{gain: float32(gain), closed: closed}, nil
	}
}

func (s *echoSurface) Evaluate(_ component.TransportMode, wi, _, uv, value []float32) error {
	for i := range value {
		value[i] = s.gain * wi[i]
	}
	if len(uv) > 0 && uv[0] == -1 {
		return errors.New("uv -1 is refused")
	}
	return nil
}

func (s *echoSurface) Sample(_ component.TransportMode, wi, _, _ []float32, allowed uint32, out component.SampleRows) error {
	if allowed == 99 {
		return status.Error(codes.Unavailable, "try later")
	}
	for k := range len(wi) / 3 {
		out.Store(k, [3]float32{wi[3*k], wi[3*k+1], wi[3*k+2]}, [3]float32{1, 1, 1}, 1, component.ScatterReflect)
	}
	return nil
}

func (s *echoSurface) Pdf(_, _, _, _ []float32) error { panic("Pdf is broken") }

func (s *echoSurface) Lobes() uint32 { return component.ScatterReflect | component.ScatterGlossy }

func (s *echoSurface) Close() error {
	s.closed.Add(1)
	return nil
}

// indexSampler makes coordinate d of point i equal to (i + d) / 1000.
type indexSampler struct{}

func (indexSampler) Generate(first uint64, count, dimensions uint32, _ uint64, points []float32) error {
	for i := range count {
		for d := range dimensions {
			points[i*dimensions+d] = float32(first+uint64(i)+uint64(d)) / 1000
		}
	}
	return nil
}

func testClasses(closed *atomic.Int32) []component.Class {
	return []component.Class{
		component.NewClass("echo_surface", "1.2.3", "Echoes wi", newEchoSurface(closed)),
		component.NewClass("index_sampler", "0.1.0", "Points from indices",
			func(*component.Properties) (indexSampler, error) { return indexSampler{}, nil }),
	}
}

// wantStatus fails unless err is a status with this code whose message
// contains every one of the parts.
func wantStatus(t *testing.T, err error, code codes.Code, parts ...string) {
	t.Helper()
	s, ok := status.FromError(err)
	if err == nil || !ok || s.Code() != code {
		t.Errorf("got error %v, want code %v", err, code)
		return
	}
	for _, part := range parts {
		if !strings.Contains(s.Message(), part) {
			t.Errorf("message %q does not contain %q", s.Message(), part)
		}
	}
}
