"""The Medium service (medium.proto) over a Host's instances.

Each call decodes its arrays (checked as yarfd checks them), runs the
instance's method on the whole batch and encodes what it returned as
float32 or uint32 without checking it: yarfd validates replies.
"""

from __future__ import annotations

import grpc

from yarf.v1 import medium_pb2, medium_pb2_grpc
from yarf_component.arrays import Batch, float32, uint32
from yarf_component.calls import rpc, user_code
from yarf_component.host import Host
from yarf_component.medium import Medium


class MediumService(medium_pb2_grpc.MediumServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Majorants(
        self, request: medium_pb2.MajorantsRequest, context: grpc.ServicerContext
    ) -> medium_pb2.MajorantsReply:
        medium = self._host.instance(request.handle, Medium)
        batch = Batch()
        origin = batch.floats(request.origin, "origin", 3)
        direction = batch.floats(request.direction, "direction", 3)
        tmax = batch.floats(request.tmax, "tmax")
        with user_code(medium, "majorants"):
            segments, offsets = medium.majorants(origin, direction, tmax)
            return medium_pb2.MajorantsReply(segments=float32(segments), offsets=uint32(offsets))

    @rpc
    def Coefficients(
        self, request: medium_pb2.CoefficientsRequest, context: grpc.ServicerContext
    ) -> medium_pb2.CoefficientsReply:
        medium = self._host.instance(request.handle, Medium)
        position = Batch().floats(request.position, "position", 3)
        with user_code(medium, "coefficients"):
            sigma_a, sigma_s, emission = medium.coefficients(position)
            return medium_pb2.CoefficientsReply(
                sigma_a=float32(sigma_a), sigma_s=float32(sigma_s), emission=float32(emission)
            )

    @rpc
    def Emits(
        self, request: medium_pb2.EmitsRequest, context: grpc.ServicerContext
    ) -> medium_pb2.EmitsReply:
        medium = self._host.instance(request.handle, Medium)
        with user_code(medium, "emits"):
            return medium_pb2.EmitsReply(emits=bool(medium.emits()))

    @rpc
    def EvaluatePhase(
        self, request: medium_pb2.PhaseQuery, context: grpc.ServicerContext
    ) -> medium_pb2.EvaluatePhaseReply:
        medium = self._host.instance(request.handle, Medium)
        batch = Batch()
        wi = batch.floats(request.wi, "wi", 3)
        wo = batch.floats(request.wo, "wo", 3)
        position = batch.floats(request.position, "position", 3)
        with user_code(medium, "evaluate_phase"):
            value, pdf = medium.evaluate_phase(wi, wo, position)
            return medium_pb2.EvaluatePhaseReply(value=float32(value), pdf=float32(pdf))

    @rpc
    def SamplePhase(
        self, request: medium_pb2.SamplePhaseRequest, context: grpc.ServicerContext
    ) -> medium_pb2.SamplePhaseReply:
        medium = self._host.instance(request.handle, Medium)
        batch = Batch()
        wi = batch.floats(request.wi, "wi", 3)
        position = batch.floats(request.position, "position", 3)
        uniform = batch.floats(request.uniform, "uniform", 2)
        with user_code(medium, "sample_phase"):
            wo, weight, pdf = medium.sample_phase(wi, position, uniform)
            return medium_pb2.SamplePhaseReply(
                wo=float32(wo), weight=float32(weight), pdf=float32(pdf)
            )
