"""A material of a running job: yarfd's SurfaceModel instance, as numpy calls.

Each call has a ``*_async`` twin that sends it at once and returns a
Pending, so that a transport can have every material's call of a bounce
in flight together and wait once.
"""

from __future__ import annotations

import functools

import numpy as np

from yarf.client import array_to_numpy
from yarf.v1 import surface_pb2, surface_pb2_grpc
from yarf_component.channels import channel
from yarf_component.job_calls import Caller, Pending, float_array
from yarf_component.surface import ScatterFlags, TransportMode

Sampled = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _value(reply: surface_pb2.EvaluateSurfaceReply) -> np.ndarray:
    return array_to_numpy(reply.value)


def _pdf(reply: surface_pb2.PdfSurfaceReply) -> np.ndarray:
    return array_to_numpy(reply.pdf)


def _sampled(reply: surface_pb2.SampleSurfaceReply) -> Sampled:
    return (
        array_to_numpy(reply.wo),
        array_to_numpy(reply.weight),
        array_to_numpy(reply.pdf),
        array_to_numpy(reply.flags),
    )


class SurfaceClient:
    """SurfaceModel instance ``handle`` on the yarfd of a job. Directions are local
    (+z the normal), float32 [N,3]; uv [N,2]."""

    def __init__(self, caller: Caller, handle: int) -> None:
        self._call = caller
        self._stub = surface_pb2_grpc.SurfaceModelStub(channel(caller.address))
        self.handle = handle

    @functools.cached_property
    def _lobes(self) -> ScatterFlags:
        request = surface_pb2.LobesRequest(handle=self.handle)
        return ScatterFlags(self._call("SurfaceModel.Lobes", self._stub.Lobes, request).flags)

    def lobes(self) -> ScatterFlags:
        """Union of the flags of the model's lobes (asked once)."""
        return self._lobes

    def _query(
        self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray, mode: TransportMode
    ) -> surface_pb2.SurfaceQuery:
        n = len(wi)
        return surface_pb2.SurfaceQuery(
            handle=self.handle,
            wi=float_array(wi, n, 3),
            wo=float_array(wo, n, 3),
            uv=float_array(uv, n, 2),
            mode=int(mode),  # type: ignore[arg-type]
        )

    def evaluate_async(
        self,
        wi: np.ndarray,
        wo: np.ndarray,
        uv: np.ndarray,
        mode: TransportMode = TransportMode.RADIANCE,
    ) -> Pending[np.ndarray]:
        request = self._query(wi, wo, uv, mode)
        return self._call.start("SurfaceModel.Evaluate", self._stub.Evaluate, request, _value)

    def evaluate(
        self,
        wi: np.ndarray,
        wo: np.ndarray,
        uv: np.ndarray,
        mode: TransportMode = TransportMode.RADIANCE,
    ) -> np.ndarray:
        """f(wi, wo) [N,3], 1/sr, no cosine factor."""
        return self.evaluate_async(wi, wo, uv, mode).result()

    def pdf_async(self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> Pending[np.ndarray]:
        request = self._query(wi, wo, uv, TransportMode.RADIANCE)
        return self._call.start("SurfaceModel.Pdf", self._stub.Pdf, request, _pdf)

    def pdf(self, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """[N]: the solid-angle density of sampling wo given wi."""
        return self.pdf_async(wi, wo, uv).result()

    def sample_async(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: int = 0,
        mode: TransportMode = TransportMode.RADIANCE,
    ) -> Pending[Sampled]:
        n = len(wi)
        request = surface_pb2.SampleSurfaceRequest(
            handle=self.handle,
            wi=float_array(wi, n, 3),
            uv=float_array(uv, n, 2),
            uniform=float_array(uniform, n, 3),
            allowed=int(allowed),
            mode=int(mode),  # type: ignore[arg-type]
        )
        return self._call.start("SurfaceModel.Sample", self._stub.Sample, request, _sampled)

    def sample(
        self,
        wi: np.ndarray,
        uv: np.ndarray,
        uniform: np.ndarray,
        allowed: int = 0,
        mode: TransportMode = TransportMode.RADIANCE,
    ) -> Sampled:
        """(wo [N,3], weight [N,3], pdf [N], flags [N] uint32) drawn with uniform [N,3]
        (lobe choice, then the direction's two numbers); 0 ``allowed`` accepts every lobe."""
        return self.sample_async(wi, uv, uniform, allowed, mode).result()
