"""The SurfaceModel and Emitter services (surface.proto) over a Host's instances.

Each call decodes its arrays (checked as yarfd checks them), runs the
instance's method on the whole batch and encodes what it returned as
float32 or uint32 without checking it: the caller validates replies.
"""

from __future__ import annotations

import grpc

from yarf.v1 import surface_pb2, surface_pb2_grpc
from yarf_component.arrays import Batch, float32, uint32
from yarf_component.calls import invalid, rpc, user_code
from yarf_component.host import Host
from yarf_component.surface import Emitter, ScatterFlags, SurfaceModel, TransportMode


def _mode(value: int) -> TransportMode:
    try:
        return TransportMode(value)
    except ValueError:
        raise invalid(f"mode: unknown TransportMode {value}") from None


class SurfaceModelService(surface_pb2_grpc.SurfaceModelServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Evaluate(
        self, request: surface_pb2.SurfaceQuery, context: grpc.ServicerContext
    ) -> surface_pb2.EvaluateSurfaceReply:
        model = self._host.instance(request.handle, SurfaceModel)
        batch = Batch()
        wi = batch.floats(request.wi, "wi", 3)
        wo = batch.floats(request.wo, "wo", 3)
        uv = batch.floats(request.uv, "uv", 2)
        mode = _mode(request.mode)
        with user_code(model, "evaluate"):
            return surface_pb2.EvaluateSurfaceReply(value=float32(model.evaluate(wi, wo, uv, mode)))

    @rpc
    def Sample(
        self, request: surface_pb2.SampleSurfaceRequest, context: grpc.ServicerContext
    ) -> surface_pb2.SampleSurfaceReply:
        model = self._host.instance(request.handle, SurfaceModel)
        batch = Batch()
        wi = batch.floats(request.wi, "wi", 3)
        uv = batch.floats(request.uv, "uv", 2)
        uniform = batch.floats(request.uniform, "uniform", 3)
        mode = _mode(request.mode)
        with user_code(model, "sample"):
            wo, weight, pdf, flags = model.sample(
                wi, uv, uniform, ScatterFlags(request.allowed), mode
            )
            return surface_pb2.SampleSurfaceReply(
                wo=float32(wo), weight=float32(weight), pdf=float32(pdf), flags=uint32(flags)
            )

    @rpc
    def Pdf(
        self, request: surface_pb2.SurfaceQuery, context: grpc.ServicerContext
    ) -> surface_pb2.PdfSurfaceReply:
        model = self._host.instance(request.handle, SurfaceModel)
        batch = Batch()
        wi = batch.floats(request.wi, "wi", 3)
        wo = batch.floats(request.wo, "wo", 3)
        uv = batch.floats(request.uv, "uv", 2)
        with user_code(model, "pdf"):
            return surface_pb2.PdfSurfaceReply(pdf=float32(model.pdf(wi, wo, uv)))

    @rpc
    def Lobes(
        self, request: surface_pb2.LobesRequest, context: grpc.ServicerContext
    ) -> surface_pb2.LobesReply:
        model = self._host.instance(request.handle, SurfaceModel)
        with user_code(model, "lobes"):
            return surface_pb2.LobesReply(flags=int(model.lobes()))


class EmitterService(surface_pb2_grpc.EmitterServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Radiance(
        self, request: surface_pb2.RadianceRequest, context: grpc.ServicerContext
    ) -> surface_pb2.RadianceReply:
        emitter = self._host.instance(request.handle, Emitter)
        batch = Batch()
        w = batch.floats(request.w, "w", 3)
        uv = batch.floats(request.uv, "uv", 2)
        with user_code(emitter, "radiance"):
            return surface_pb2.RadianceReply(radiance=float32(emitter.radiance(w, uv)))

    @rpc
    def SampleDirection(
        self, request: surface_pb2.SampleDirectionRequest, context: grpc.ServicerContext
    ) -> surface_pb2.SampleDirectionReply:
        emitter = self._host.instance(request.handle, Emitter)
        uniform = Batch().floats(request.uniform, "uniform", 2)
        with user_code(emitter, "sample_direction"):
            w, pdf = emitter.sample_direction(uniform)
            return surface_pb2.SampleDirectionReply(w=float32(w), pdf=float32(pdf))

    @rpc
    def PdfDirection(
        self, request: surface_pb2.PdfDirectionRequest, context: grpc.ServicerContext
    ) -> surface_pb2.PdfDirectionReply:
        emitter = self._host.instance(request.handle, Emitter)
        w = Batch().floats(request.w, "w", 3)
        with user_code(emitter, "pdf_direction"):
            return surface_pb2.PdfDirectionReply(pdf=float32(emitter.pdf_direction(w)))
