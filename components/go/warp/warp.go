// Package warp maps uniform numbers in [0,1)^2 to points of the disk and
// the hemisphere, with the densities they produce, in float32 as yarf's
// C++ warps compute them (Shirley, "Nonuniform random point sets via
// warping", 1992). Directions are unit vectors whose +z is the axis.
package warp

import "math"

const (
	pi    float32 = math.Pi
	invPi float32 = 1 / math.Pi
)

// SampleConcentricDisk maps the square onto the unit disk (Shirley & Chiu
// 1997): concentric squares go to concentric circles, so strata of the
// square stay compact on the disk.
func SampleConcentricDisk(u0, u1 float32) (x, y float32) {
	a := 2*u0 - 1
	b := 2*u1 - 1
	if a == 0 && b == 0 {
		return 0, 0
	}
	var r, phi float32
	if abs(a) > abs(b) {
		r = a
		phi = (pi / 4) * (b / a)
	} else {
		r = b
		phi = pi/2 - (pi/4)*(a/b)
	}
	return r * cos(phi), r * sin(phi)
}

// SampleCosineHemisphere draws a direction of the hemisphere z ≥ 0 with
// density cos θ / π (Malley's method: uniform points of the disk lifted
// onto the hemisphere).
func SampleCosineHemisphere(u0, u1 float32) [3]float32 {
	x, y := SampleConcentricDisk(u0, u1)
	return [3]float32{x, y, float32(math.Sqrt(float64(max(0, 1-x*x-y*y))))}
}

// CosineHemispherePdf is the density of SampleCosineHemisphere at a
// direction with this cos θ; 0 below the horizon.
func CosineHemispherePdf(cosTheta float32) float32 {
	if cosTheta > 0 {
		return cosTheta * invPi
	}
	return 0
}

func abs(v float32) float32 { return float32(math.Abs(float64(v))) }
func cos(v float32) float32 { return float32(math.Cos(float64(v))) }
func sin(v float32) float32 { return float32(math.Sin(float64(v))) }
