package bsdf_test

import (
	"context"
	"math"
	"math/rand/v2"
	"slices"
	"strings"
	"testing"

	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	"yarf.dev/components/go/bsdf"
	"yarf.dev/components/go/component"
	"yarf.dev/components/go/component/componenttest"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// The tests call go_lambertian over gRPC on a unix socket, as yarfd does.

var reflectance = [3]float32{0.2, 0.5, 0.8}

const lobe = component.ScatterReflect | component.ScatterDiffuse

type lambertian struct {
	t       *testing.T
	factory yarfv1.FactoryClient
	surface yarfv1.SurfaceModelClient
	handle  uint64
}

// startLambertian serves go_lambertian and makes one with `reflectance`.
func startLambertian(t *testing.T) *lambertian {
	conn := componenttest.Start(t, bsdf.LambertianClass)
	l := &lambertian{t: t, factory: yarfv1.NewFactoryClient(conn), surface: yarfv1.NewSurfaceModelClient(conn)}
	reply, err := l.factory.Create(context.Background(), &yarfv1.CreateRequest{
		ClassName: "go_lambertian",
		Properties: &yarfv1.Properties{Values: map[string]*yarfv1.Property{
			"reflectance": {Value: &yarfv1.Property_RgbValue{RgbValue: &yarfv1.Rgb{R: 0.2, G: 0.5, B: 0.8}}},
		}},
	})
	if err != nil {
		t.Fatal(err)
	}
	l.handle = reply.GetHandle()
	return l
}

type sampled struct {
	wo, weight, pdf []float32
	flags           []uint32
}

func (l *lambertian) sample(wi, uniform []float32, allowed uint32, mode component.TransportMode) sampled {
	l.t.Helper()
	n := uint32(len(wi) / 3)
	reply, err := l.surface.Sample(context.Background(), &yarfv1.SampleSurfaceRequest{
		Handle:  l.handle,
		Wi:      component.EncodeFloat32(wi, n, 3),
		Uv:      component.EncodeFloat32(make([]float32, 2*n), n, 2),
		Uniform: component.EncodeFloat32(uniform, n, 3),
		Allowed: allowed,
		Mode:    mode,
	})
	if err != nil {
		l.t.Fatal(err)
	}
	var s sampled
	var errs [4]error
	s.wo, _, errs[0] = component.DecodeFloat32(reply.GetWo(), "wo", 3)
	s.weight, _, errs[1] = component.DecodeFloat32(reply.GetWeight(), "weight", 3)
	s.pdf, _, errs[2] = component.DecodeFloat32(reply.GetPdf(), "pdf")
	s.flags, _, errs[3] = component.DecodeUint32(reply.GetFlags(), "flags")
	for _, err := range errs {
		if err != nil {
			l.t.Fatal(err)
		}
	}
	return s
}

func (l *lambertian) query(wi, wo []float32) *yarfv1.SurfaceQuery {
	n := uint32(len(wi) / 3)
	return &yarfv1.SurfaceQuery{
		Handle: l.handle,
		Wi:     component.EncodeFloat32(wi, n, 3),
		Wo:     component.EncodeFloat32(wo, n, 3),
		Uv:     component.EncodeFloat32(make([]float32, 2*n), n, 2),
	}
}

func (l *lambertian) evaluate(wi, wo []float32) []float32 {
	l.t.Helper()
	reply, err := l.surface.Evaluate(context.Background(), l.query(wi, wo))
	if err != nil {
		l.t.Fatal(err)
	}
	value, _, err := component.DecodeFloat32(reply.GetValue(), "value", 3)
	if err != nil {
		l.t.Fatal(err)
	}
	return value
}

func (l *lambertian) pdf(wi, wo []float32) []float32 {
	l.t.Helper()
	reply, err := l.surface.Pdf(context.Background(), l.query(wi, wo))
	if err != nil {
		l.t.Fatal(err)
	}
	pdf, _, err := component.DecodeFloat32(reply.GetPdf(), "pdf")
	if err != nil {
		l.t.Fatal(err)
	}
	return pdf
}

// randomDirections draws n unit vectors uniform on the sphere, so half of
// them arrive from the back side.
func randomDirections(random *rand.Rand, n int) []float32 {
	w := make([]float32, 0, 3*n)
	for range n {
		z := 1 - 2*random.Float64()
		r := math.Sqrt(max(0, 1-z*z))
		phi := 2 * math.Pi * random.Float64()
		w = append(w, float32(r*math.Cos(phi)), float32(r*math.Sin(phi)), float32(z))
	}
	return w
}

func uniformNumbers(random *rand.Rand, n int) []float32 {
	u := make([]float32, n)
	for i := range u {
		u[i] = random.Float32()
	}
	return u
}

func near(a, b, relative float32) bool {
	return math.Abs(float64(a-b)) <= float64(relative)*math.Max(math.Abs(float64(a)), math.Abs(float64(b)))
}

func TestSampleAgreesWithPdfAndEvaluate(t *testing.T) {
	l := startLambertian(t)
	random := rand.New(rand.NewPCG(1, 2))
	const n = 4096
	wi := randomDirections(random, n)
	s := l.sample(wi, uniformNumbers(random, 3*n), 0, component.Radiance)
	pdf := l.pdf(wi, s.wo)
	value := l.evaluate(wi, s.wo)
	for k := range n {
		if s.flags[k] != lobe {
			t.Fatalf("row %d: flags %d, want %d", k, s.flags[k], lobe)
		}
		wo := s.wo[3*k : 3*k+3]
		if wi[3*k+2]*wo[2] <= 0 {
			t.Errorf("row %d: wo %v not on the side of wi %v", k, wo, wi[3*k:3*k+3])
		}
		if length := wo[0]*wo[0] + wo[1]*wo[1] + wo[2]*wo[2]; !near(length, 1, 1e-5) {
			t.Errorf("row %d: |wo|² = %v", k, length)
		}
		if !near(s.pdf[k], pdf[k], 1e-6) || !near(s.pdf[k], float32(math.Abs(float64(wo[2]))/math.Pi), 1e-5) {
			t.Errorf("row %d: Sample's pdf %v, Pdf %v, cos θ/π %v", k, s.pdf[k], pdf[k], math.Abs(float64(wo[2]))/math.Pi)
		}
		cos := float32(math.Abs(float64(wo[2])))
		for c := range 3 {
			if want := value[3*k+c] * cos / s.pdf[k]; !near(s.weight[3*k+c], want, 1e-5) {
				t.Errorf("row %d: weight %v, f·cos θ/pdf %v", k, s.weight[3*k+c], want)
			}
			if s.weight[3*k+c] != reflectance[c] {
				t.Errorf("row %d: weight %v, want the reflectance %v", k, s.weight[3*k+c], reflectance[c])
			}
		}
	}
}

func TestSampledCosinesAreCosineWeighted(t *testing.T) {
	l := startLambertian(t)
	random := rand.New(rand.NewPCG(3, 4))
	const n = 100000
	s := l.sample(randomDirections(random, n), uniformNumbers(random, 3*n), 0, component.Radiance)
	sum := 0.0
	for k := range n {
		sum += math.Abs(float64(s.wo[3*k+2]))
	}
	// Under the density cos θ/π, E[cos θ] = 2/3 and Var[cos θ] = 1/2 - 4/9.
	mean := sum / n
	standardError := math.Sqrt((1.0/2 - 4.0/9) / n)
	if math.Abs(mean-2.0/3) > 4*standardError {
		t.Errorf("mean cos θ = %.5f, want 2/3 within %.5f", mean, 4*standardError)
	}
}

// TestWhiteFurnace integrates f·|cos θo| over wi's hemisphere by uniform
// sampling: it equals the reflectance (energy is conserved and none lost),
// for light arriving on either side; over the other hemisphere it is 0.
func TestWhiteFurnace(t *testing.T) {
	l := startLambertian(t)
	random := rand.New(rand.NewPCG(5, 6))
	const n = 100000
	for _, side := range []float32{1, -1} {
		wi := make([]float32, 0, 3*n)
		for range n {
			wi = append(wi, 0, 0.6, 0.8*side)
		}
		wo := randomDirections(random, n)
		value := l.evaluate(wi, wo)
		for c := range 3 {
			// Directions uniform on the sphere have density 1/4π.
			var sum, sumOfSquares float64
			for k := range n {
				estimate := float64(value[3*k+c]) * math.Abs(float64(wo[3*k+2])) * 4 * math.Pi
				sum += estimate
				sumOfSquares += estimate * estimate
				if wo[3*k+2]*side < 0 && value[3*k+c] != 0 {
					t.Fatalf("light transmitted: f(%v, %v) = %v", wi[3*k:3*k+3], wo[3*k:3*k+3], value[3*k+c])
				}
			}
			mean := sum / n
			standardError := math.Sqrt((sumOfSquares/n - mean*mean) / n)
			if math.Abs(mean-float64(reflectance[c])) > 4*standardError {
				t.Errorf("side %v, channel %d: ∫ f cos θ = %.4f ± %.4f, want %v", side, c, mean, standardError, reflectance[c])
			}
		}
	}
}

func TestEvaluateIsReflectanceOverPi(t *testing.T) {
	l := startLambertian(t)
	wi := []float32{0, 0, 1, 0, 0, -1, 0.6, 0, 0.8, 1, 0, 0}
	wo := []float32{0.8, 0, 0.6, 0, 0.6, -0.8, 0, 0, -1, 0, 0, 1}
	value := l.evaluate(wi, wo)
	pdf := l.pdf(wi, wo)
	for c := range 3 {
		f := reflectance[c] * float32(1/math.Pi)
		if want := []float32{f, f, 0, 0}; !slices.Equal([]float32{value[c], value[3+c], value[6+c], value[9+c]}, want) {
			t.Errorf("channel %d: values %v, want %v", c, value, want)
		}
	}
	if want := []float32{0.6 / math.Pi, 0.8 / math.Pi, 0, 0}; !slices.EqualFunc(pdf, want, func(a, b float32) bool {
		return near(a, b, 1e-6) || a == b
	}) {
		t.Errorf("pdf %v, want %v", pdf, want)
	}
}

func TestNoSample(t *testing.T) {
	l := startLambertian(t)
	tests := []struct {
		name    string
		wi      []float32
		allowed uint32
	}{
		{"grazing wi", []float32{1, 0, 0}, 0},
		{"refraction only", []float32{0, 0, 1}, component.ScatterRefract},
		{"not diffuse", []float32{0, 0, 1}, component.ScatterReflect},
		{"glossy only", []float32{0, 0, 1}, component.ScatterReflect | component.ScatterGlossy},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			s := l.sample(test.wi, []float32{0.5, 0.3, 0.7}, test.allowed, component.Radiance)
			if s.flags[0] != 0 || s.pdf[0] != 0 || slices.ContainsFunc(append(s.wo, s.weight...), func(v float32) bool { return v != 0 }) {
				t.Errorf("got %+v, want no sample", s)
			}
		})
	}
	for _, allowed := range []uint32{0, lobe, component.ScatterReflect | component.ScatterDiffuse | component.ScatterGlossy} {
		if s := l.sample([]float32{0, 0, 1}, []float32{0.5, 0.3, 0.7}, allowed, component.Radiance); s.flags[0] != lobe {
			t.Errorf("allowed %d: flags %d, want %d", allowed, s.flags[0], lobe)
		}
	}
}

func TestTransportModeMakesNoDifference(t *testing.T) {
	l := startLambertian(t)
	random := rand.New(rand.NewPCG(7, 8))
	wi := randomDirections(random, 64)
	u := uniformNumbers(random, 3*64)
	radiance := l.sample(wi, u, 0, component.Radiance)
	importance := l.sample(wi, u, 0, component.Importance)
	if !slices.Equal(radiance.wo, importance.wo) || !slices.Equal(radiance.weight, importance.weight) ||
		!slices.Equal(radiance.pdf, importance.pdf) {
		t.Error("Sample differs between radiance and importance")
	}
}

func TestSampledDirectionsMatchTheCppWarp(t *testing.T) {
	l := startLambertian(t)
	// SampleCosineHemisphere of server/include/yarf/support/warps.h at these numbers.
	want := []float32{
		0, 0, 1,
		-0x1.7a6bccp-1, 0x1.397e88p-2, 0x1.333332p-1,
		0x1.7a6bc8p-1, -0x1.397e88p-2, 0x1.333336p-1,
		-0x1.857c2cp-2, 0x1.a1a06ap-1, 0x1.be59ecp-2,
	}
	u := []float32{0, 0.5, 0.5, 0, 0x1.99999ap-4, 0x1.666666p-1, 0, 0x1.ccccccp-1, 0x1.333334p-2, 0, 0.25, 0x1.e66666p-1}
	wi := []float32{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}
	s := l.sample(wi, u, 0, component.Radiance)
	for i := range want {
		if math.Abs(float64(s.wo[i]-want[i])) > 1e-6 {
			t.Errorf("wo %v, want %v", s.wo, want)
			break
		}
	}
}

func TestLobesAndDefaults(t *testing.T) {
	conn := componenttest.Start(t, bsdf.LambertianClass)
	factory := yarfv1.NewFactoryClient(conn)
	surface := yarfv1.NewSurfaceModelClient(conn)
	ctx := context.Background()
	created, err := factory.Create(ctx, &yarfv1.CreateRequest{ClassName: "go_lambertian"})
	if err != nil {
		t.Fatal(err)
	}
	info := created.GetInfo()
	if !slices.Equal(info.GetInterfaces(), []string{"yarf.v1.SurfaceModel"}) || !strings.HasPrefix(info.GetOrigin(), "go ") {
		t.Errorf("info %v", info)
	}
	// The declared default is the one the class takes (the weight below).
	if params := info.GetParameters(); !info.GetDeclaresParameters() || len(params) != 1 ||
		params[0].GetName() != "reflectance" || params[0].GetType() != "rgb" || params[0].GetDefaultValue() != "0.5" {
		t.Errorf("declared parameters %v", params)
	}
	lobes, err := surface.Lobes(ctx, &yarfv1.LobesRequest{Handle: created.GetHandle()})
	if err != nil || lobes.GetFlags() != lobe {
		t.Errorf("lobes %v, %v", lobes, err)
	}
	l := &lambertian{t: t, surface: surface, handle: created.GetHandle()}
	if s := l.sample([]float32{0, 0, 1}, []float32{0, 0.3, 0.6}, 0, component.Radiance); !slices.Equal(s.weight, []float32{0.5, 0.5, 0.5}) {
		t.Errorf("default weight %v, want 0.5", s.weight)
	}
	if _, err := factory.Release(ctx, &yarfv1.ReleaseRequest{Handle: created.GetHandle()}); err != nil {
		t.Fatal(err)
	}
	_, err = factory.Release(ctx, &yarfv1.ReleaseRequest{Handle: created.GetHandle()})
	if status.Code(err) != codes.NotFound {
		t.Errorf("second Release: %v, want NOT_FOUND", err)
	}
}

func TestBadProperties(t *testing.T) {
	conn := componenttest.Start(t, bsdf.LambertianClass)
	factory := yarfv1.NewFactoryClient(conn)
	tests := []struct {
		name     string
		key      string
		property *yarfv1.Property
		want     string
	}{
		{"wrong type", "reflectance", &yarfv1.Property{Value: &yarfv1.Property_StringValue{StringValue: "red"}},
			"property 'reflectance' must be of type rgb or float, not string"},
		{"out of range", "reflectance", &yarfv1.Property{Value: &yarfv1.Property_FloatValue{FloatValue: 1.5}},
			"property 'reflectance' must lie in [0, 1] in every channel"},
		{"unknown key", "roughness", &yarfv1.Property{Value: &yarfv1.Property_FloatValue{FloatValue: 0.1}},
			"does not understand property 'roughness'"},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			_, err := factory.Create(context.Background(), &yarfv1.CreateRequest{
				ClassName:  "go_lambertian",
				Properties: &yarfv1.Properties{Values: map[string]*yarfv1.Property{test.key: test.property}},
			})
			if status.Code(err) != codes.InvalidArgument || !strings.Contains(status.Convert(err).Message(), test.want) {
				t.Errorf("error %v, want INVALID_ARGUMENT %q", err, test.want)
			}
		})
	}
}
