// Package bsdf holds surface models (yarf.v1.SurfaceModel) written in Go.
package bsdf

import (
	"math"

	"yarf.dev/components/go/component"
	"yarf.dev/components/go/warp"
)

// LambertianClass is go_lambertian, the ideal diffuse reflector.
var LambertianClass = component.NewClass("go_lambertian", "1.0.0",
	"Ideal diffuse (Lambertian) reflection, two-sided", NewLambertian).WithParameters(
	component.Parameter{Name: "reflectance", Type: "rgb", Default: "0.5", Min: component.Bound(0), Max: component.Bound(1),
		Doc: "fraction of the incident light reflected, per channel"},
)

const (
	lambertianLobe         = component.ScatterReflect | component.ScatterDiffuse
	invPi          float32 = 1 / math.Pi
)

var _ component.SurfaceModel = (*Lambertian)(nil)

// Lambertian scatters incident light equally in all directions of the
// side it arrives on: f(wi, wo) = reflectance / π when wi and wo lie on
// the same side of the surface, 0 otherwise. Both sides reflect alike (a
// two-sided material); there is no transmission. Sample draws wo from the
// cosine-weighted hemisphere on wi's side, so its weight is the
// reflectance itself; a grazing wi (z = 0), or an `allowed` that excludes
// reflection or diffuse lobes, draws nothing. The transport mode makes no
// difference.
type Lambertian struct {
	reflectance [3]float32
}

// NewLambertian reads the properties of a go_lambertian.
func NewLambertian(p *component.Properties) (*Lambertian, error) {
	rgb := p.Reflectance("reflectance", [3]float64{0.5, 0.5, 0.5})
	return &Lambertian{reflectance: [3]float32{float32(rgb[0]), float32(rgb[1]), float32(rgb[2])}}, nil
}

func (l *Lambertian) Evaluate(_ component.TransportMode, wi, wo, _, value []float32) error {
	f := l.reflectance
	for c := range f {
		f[c] *= invPi
	}
	for k := range len(wi) / 3 {
		if wi[3*k+2]*wo[3*k+2] > 0 {
			copy(value[3*k:3*k+3], f[:])
		} else {
			clear(value[3*k : 3*k+3])
		}
	}
	return nil
}

func (l *Lambertian) Sample(_ component.TransportMode, wi, _, uniform []float32, allowed uint32,
	out component.SampleRows) error {
	canReflect := component.LobeAllowed(lambertianLobe, allowed)
	for k := range len(wi) / 3 {
		wiZ := wi[3*k+2]
		wo := warp.SampleCosineHemisphere(uniform[3*k+1], uniform[3*k+2])
		// Mirror onto wi's side: the back face reflects like the front.
		if wiZ < 0 {
			wo[2] = -wo[2]
		}
		density := warp.CosineHemispherePdf(abs(wo[2]))
		if !canReflect || wiZ == 0 || density <= 0 {
			out.StoreNoSample(k)
			continue
		}
		// f·|cos θo| / pdf = (ρ/π)·cos θo / (cos θo/π) = ρ.
		out.Store(k, wo, l.reflectance, density, lambertianLobe)
	}
	return nil
}

func (l *Lambertian) Pdf(wi, wo, _, pdf []float32) error {
	for k := range len(wi) / 3 {
		if wi[3*k+2]*wo[3*k+2] > 0 {
			pdf[k] = warp.CosineHemispherePdf(abs(wo[3*k+2]))
		} else {
			pdf[k] = 0
		}
	}
	return nil
}

func (l *Lambertian) Lobes() uint32 { return lambertianLobe }

func abs(v float32) float32 { return float32(math.Abs(float64(v))) }
