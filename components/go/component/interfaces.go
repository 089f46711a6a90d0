package component

import yarfv1 "yarf.dev/components/go/gen/yarfv1"

// The interfaces a class can implement, one per service of the IDL. Each
// method gets its batch decoded into flat row-major slices (row k of an
// [N,3] array is elements 3k..3k+2) and output slices of the right length,
// zeroed. An error returned reaches the caller as INVALID_ARGUMENT, unless
// it is a gRPC status error, which is passed on as it is.

// SurfaceModel is yarf.v1.SurfaceModel: surface scattering in the local
// shading frame (+z the normal). See surface.proto for the conventions.
type SurfaceModel interface {
	// Evaluate sets value[k] (RGB, 1/sr) to f(wi[k], wo[k]), no cosine.
	Evaluate(mode TransportMode, wi, wo, uv, value []float32) error
	// Sample draws wo given wi and uniform[k] (three numbers: one to
	// choose a lobe, two for the direction), among the lobes that
	// LobeAllowed(lobe, allowed) accepts.
	Sample(mode TransportMode, wi, uv, uniform []float32, allowed uint32, out SampleRows) error
	// Pdf sets pdf[k] to the solid-angle density of Sample drawing wo[k].
	Pdf(wi, wo, uv, pdf []float32) error
	// Lobes is the union of the ScatterFlags of every lobe.
	Lobes() uint32
}

// Sampler is yarf.v1.Sampler: deterministic point sets in [0,1)^d.
type Sampler interface {
	// Generate sets points[i*dimensions+d] to coordinate d of point
	// firstIndex+i of the sequence for seed, for i < count.
	Generate(firstIndex uint64, count, dimensions uint32, seed uint64, points []float32) error
}

// TransportMode says whether a path carries radiance or importance.
type TransportMode = yarfv1.TransportMode

const (
	Radiance   = yarfv1.TransportMode_RADIANCE
	Importance = yarfv1.TransportMode_IMPORTANCE
)

// Bits of SampleRows.Flags, of Lobes and of Sample's allowed.
const (
	ScatterNone    = uint32(yarfv1.ScatterFlags_SCATTER_NONE)
	ScatterReflect = uint32(yarfv1.ScatterFlags_SCATTER_REFLECT)
	ScatterRefract = uint32(yarfv1.ScatterFlags_SCATTER_REFRACT)
	ScatterDelta   = uint32(yarfv1.ScatterFlags_SCATTER_DELTA)
	ScatterDiffuse = uint32(yarfv1.ScatterFlags_SCATTER_DIFFUSE)
	ScatterGlossy  = uint32(yarfv1.ScatterFlags_SCATTER_GLOSSY)
)

// LobeAllowed reports whether a lobe with these flags may be drawn: every
// flag of the lobe must be allowed, and 0 allows everything.
func LobeAllowed(lobe, allowed uint32) bool {
	return allowed == 0 || lobe&^allowed == 0
}

// SampleRows holds Sample's four outputs: wo and weight [N,3], pdf and
// flags [N].
type SampleRows struct {
	Wo, Weight, Pdf []float32
	Flags           []uint32
}

// Store writes row k.
func (r SampleRows) Store(k int, wo, weight [3]float32, pdf float32, flags uint32) {
	copy(r.Wo[3*k:3*k+3], wo[:])
	copy(r.Weight[3*k:3*k+3], weight[:])
	r.Pdf[k] = pdf
	r.Flags[k] = flags
}

// StoreNoSample writes row k as "nothing drawn": callers test pdf or
// flags, and the zero weight keeps a path that ignores both dark.
func (r SampleRows) StoreNoSample(k int) {
	r.Store(k, [3]float32{}, [3]float32{}, 0, ScatterNone)
}

// interfaceNames lists the full service names of the interfaces v
// implements, in a fixed order.
func interfaceNames(v any) []string {
	var names []string
	if _, ok := v.(SurfaceModel); ok {
		names = append(names, yarfv1.SurfaceModel_ServiceDesc.ServiceName)
	}
	if _, ok := v.(Sampler); ok {
		names = append(names, yarfv1.Sampler_ServiceDesc.ServiceName)
	}
	return names
}
