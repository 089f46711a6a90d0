package sampler_test

import (
	"context"
	"slices"
	"testing"

	"yarf.dev/components/go/component"
	"yarf.dev/components/go/component/componenttest"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
	"yarf.dev/components/go/sampler"
)

func TestIndependentMatchesYarfd(t *testing.T) {
	// yarfd's "independent" sampler: ToUnitFloat(Hash(seed, index, dimension) >> 32).
	tests := []struct {
		seed, index uint64
		dimension   uint32
		want        float32
	}{
		{0, 0, 0, 0x1.d44688p-1},
		{0, 1, 1, 0x1.314e5cp-1},
		{7, 1, 1, 0x1.3c55dep-1},
		{123456789, 0, 0, 0x1.416b34p-2},
		{123456789, 1000, 5, 0x1.9b70f6p-1},
	}
	for _, test := range tests {
		points := make([]float32, test.dimension+1)
		(&sampler.Independent{}).Generate(test.index, 1, test.dimension+1, test.seed, points)
		if got := points[test.dimension]; got != test.want {
			t.Errorf("seed %d, point %d, dimension %d: %v, want %v", test.seed, test.index, test.dimension, got, test.want)
		}
	}
}

func TestGenerateOverGrpc(t *testing.T) {
	conn := componenttest.Start(t, sampler.IndependentClass)
	ctx := context.Background()
	created, err := yarfv1.NewFactoryClient(conn).Create(ctx, &yarfv1.CreateRequest{ClassName: "go_independent"})
	if err != nil {
		t.Fatal(err)
	}
	client := yarfv1.NewSamplerClient(conn)
	generate := func(first uint64, count uint32) []float32 {
		reply, err := client.Generate(ctx, &yarfv1.GenerateSamplesRequest{
			Handle: created.GetHandle(), FirstIndex: first, Count: count, Dimensions: 4, Seed: 42,
		})
		if err != nil {
			t.Fatal(err)
		}
		points, rows, err := component.DecodeFloat32(reply.GetPoints(), "points", 4)
		if err != nil || rows != int(count) {
			t.Fatalf("%d rows, %v", rows, err)
		}
		return points
	}
	all := generate(0, 1000)
	for _, v := range all {
		if v < 0 || v >= 1 {
			t.Fatalf("coordinate %v outside [0, 1)", v)
		}
	}
	// Points are addressed by index: a later piece is the same points.
	if piece := generate(500, 10); !slices.Equal(piece, all[4*500:4*510]) {
		t.Errorf("points 500..509 differ when asked alone")
	}
}
