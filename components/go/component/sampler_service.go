package component

import (
	"context"
	"fmt"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

var samplerName = yarfv1.Sampler_ServiceDesc.ServiceName

// maxGeneratedValues bounds one Generate reply (count × dimensions), as
// yarfd does for its own samplers.
const maxGeneratedValues = 1 << 26

// samplerService answers yarf.v1.Sampler for instances implementing Sampler.
type samplerService struct {
	yarfv1.UnimplementedSamplerServer
	host *host
}

func (s *samplerService) Generate(_ context.Context, request *yarfv1.GenerateSamplesRequest) (*yarfv1.GenerateSamplesReply, error) {
	sampler, err := instanceAs[Sampler](s.host, request.GetHandle(), samplerName)
	if err != nil {
		return nil, err
	}
	count, dimensions := request.GetCount(), request.GetDimensions()
	values := uint64(count) * uint64(dimensions)
	if values > maxGeneratedValues {
		return nil, callError(samplerName, fmt.Errorf("batch of %d values exceeds %d", values, maxGeneratedValues))
	}
	points := make([]float32, values)
	if err := sampler.Generate(request.GetFirstIndex(), count, dimensions, request.GetSeed(), points); err != nil {
		return nil, callError(samplerName, err)
	}
	return &yarfv1.GenerateSamplesReply{Points: EncodeFloat32(points, count, dimensions)}, nil
}
