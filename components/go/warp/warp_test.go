package warp_test

import (
	"math"
	"testing"

	"yarf.dev/components/go/warp"
)

func TestCosineHemisphereMatchesTheCppWarp(t *testing.T) {
	// SampleCosineHemisphere of server/include/yarf/support/warps.h at these numbers.
	tests := []struct {
		u0, u1 float32
		want   [3]float32
	}{
		{0x1p-1, 0x1p-1, [3]float32{0, 0, 1}},
		{0x1.99999ap-4, 0x1.666666p-1, [3]float32{-0x1.7a6bccp-1, 0x1.397e88p-2, 0x1.333332p-1}},
		{0x1.ccccccp-1, 0x1.333334p-2, [3]float32{0x1.7a6bc8p-1, -0x1.397e88p-2, 0x1.333336p-1}},
		{0x1p-2, 0x1.e66666p-1, [3]float32{-0x1.857c2cp-2, 0x1.a1a06ap-1, 0x1.be59ecp-2}},
		{0, 0, [3]float32{-0x1.6a09e6p-1, -0x1.6a09e6p-1, 0x1.6a09e6p-13}},
	}
	for _, test := range tests {
		got := warp.SampleCosineHemisphere(test.u0, test.u1)
		for i := range got {
			if math.Abs(float64(got[i]-test.want[i])) > 1e-6 {
				t.Errorf("SampleCosineHemisphere(%v, %v) = %v, want %v", test.u0, test.u1, got, test.want)
				break
			}
		}
	}
}

func TestConcentricDiskStaysInTheDisk(t *testing.T) {
	for i := range 64 {
		for j := range 64 {
			x, y := warp.SampleConcentricDisk(float32(i)/64, float32(j)/64)
			if x*x+y*y > 1+1e-6 {
				t.Fatalf("(%d, %d)/64 maps outside the disk: (%v, %v)", i, j, x, y)
			}
		}
	}
}

func TestCosineHemispherePdf(t *testing.T) {
	if got := warp.CosineHemispherePdf(0.5); math.Abs(float64(got)-0.5/math.Pi) > 1e-7 {
		t.Errorf("pdf(0.5) = %v", got)
	}
	for _, cos := range []float32{0, -0.5} {
		if got := warp.CosineHemispherePdf(cos); got != 0 {
			t.Errorf("pdf(%v) = %v, want 0 at and below the horizon", cos, got)
		}
	}
}
