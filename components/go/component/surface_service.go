package component

import (
	"context"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

var surfaceModelName = yarfv1.SurfaceModel_ServiceDesc.ServiceName

// surfaceService answers yarf.v1.SurfaceModel for instances implementing
// SurfaceModel: it decodes and checks the batch, calls the model, and
// encodes its outputs.
type surfaceService struct {
	yarfv1.UnimplementedSurfaceModelServer
	host *host
}

func (s *surfaceService) Evaluate(_ context.Context, request *yarfv1.SurfaceQuery) (*yarfv1.EvaluateSurfaceReply, error) {
	model, err := instanceAs[SurfaceModel](s.host, request.GetHandle(), surfaceModelName)
	if err != nil {
		return nil, err
	}
	var batch Batch
	wi := batch.Float32(request.GetWi(), "wi", 3)
	wo := batch.Float32(request.GetWo(), "wo", 3)
	uv := batch.Float32(request.GetUv(), "uv", 2)
	if err := batch.Err(); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	n := batch.Rows()
	value := make([]float32, 3*n)
	if err := model.Evaluate(request.GetMode(), wi, wo, uv, value); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	return &yarfv1.EvaluateSurfaceReply{Value: EncodeFloat32(value, uint32(n), 3)}, nil
}

func (s *surfaceService) Sample(_ context.Context, request *yarfv1.SampleSurfaceRequest) (*yarfv1.SampleSurfaceReply, error) {
	model, err := instanceAs[SurfaceModel](s.host, request.GetHandle(), surfaceModelName)
	if err != nil {
		return nil, err
	}
	var batch Batch
	wi := batch.Float32(request.GetWi(), "wi", 3)
	uv := batch.Float32(request.GetUv(), "uv", 2)
	uniform := batch.Float32(request.GetUniform(), "uniform", 3)
	if err := batch.Err(); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	n := batch.Rows()
	out := SampleRows{
		Wo:     make([]float32, 3*n),
		Weight: make([]float32, 3*n),
		Pdf:    make([]float32, n),
		Flags:  make([]uint32, n),
	}
	if err := model.Sample(request.GetMode(), wi, uv, uniform, request.GetAllowed(), out); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	rows := uint32(n)
	return &yarfv1.SampleSurfaceReply{
		Wo:     EncodeFloat32(out.Wo, rows, 3),
		Weight: EncodeFloat32(out.Weight, rows, 3),
		Pdf:    EncodeFloat32(out.Pdf, rows),
		Flags:  EncodeUint32(out.Flags, rows),
	}, nil
}

func (s *surfaceService) Pdf(_ context.Context, request *yarfv1.SurfaceQuery) (*yarfv1.PdfSurfaceReply, error) {
	model, err := instanceAs[SurfaceModel](s.host, request.GetHandle(), surfaceModelName)
	if err != nil {
		return nil, err
	}
	var batch Batch
	wi := batch.Float32(request.GetWi(), "wi", 3)
	wo := batch.Float32(request.GetWo(), "wo", 3)
	uv := batch.Float32(request.GetUv(), "uv", 2)
	if err := batch.Err(); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	n := batch.Rows()
	pdf := make([]float32, n)
	if err := model.Pdf(wi, wo, uv, pdf); err != nil {
		return nil, callError(surfaceModelName, err)
	}
	return &yarfv1.PdfSurfaceReply{Pdf: EncodeFloat32(pdf, uint32(n))}, nil
}

func (s *surfaceService) Lobes(_ context.Context, request *yarfv1.LobesRequest) (*yarfv1.LobesReply, error) {
	model, err := instanceAs[SurfaceModel](s.host, request.GetHandle(), surfaceModelName)
	if err != nil {
		return nil, err
	}
	return &yarfv1.LobesReply{Flags: model.Lobes()}, nil
}
