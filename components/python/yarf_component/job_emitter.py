"""A light of a running job: yarfd's Emitter instance, as numpy calls.

Directions are in the emitter's local frame (+z its surface's normal or a point
light's axis; SceneView's light replies give the frame in the world), float32
[N,3]; uv [N,2] the emitting point's surface parameters.
"""

from __future__ import annotations

import numpy as np

from yarf.client import array_to_numpy
from yarf.v1 import surface_pb2, surface_pb2_grpc
from yarf_component.channels import channel
from yarf_component.job_calls import Caller, float_array


class EmitterClient:
    """Emitter instance ``handle`` on the yarfd of a job."""

    def __init__(self, caller: Caller, handle: int) -> None:
        self._call = caller
        self._stub = surface_pb2_grpc.EmitterStub(channel(caller.address))
        self.handle = handle

    def radiance(self, w: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """[N,3]: radiance leaving toward local directions w (a point light: intensity)."""
        n = len(w)
        request = surface_pb2.RadianceRequest(
            handle=self.handle, w=float_array(w, n, 3), uv=float_array(uv, n, 2)
        )
        return array_to_numpy(self._call("Emitter.Radiance", self._stub.Radiance, request).radiance)

    def sample_direction(self, uniform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Local directions of emission [N,3] drawn with uniform [N,2], and their
        solid-angle densities [N] (0: nothing sampled)."""
        request = surface_pb2.SampleDirectionRequest(
            handle=self.handle, uniform=float_array(uniform, len(uniform), 2)
        )
        reply = self._call("Emitter.SampleDirection", self._stub.SampleDirection, request)
        return array_to_numpy(reply.w), array_to_numpy(reply.pdf)

    def pdf_direction(self, w: np.ndarray) -> np.ndarray:
        """[N]: the density ``sample_direction`` has for local directions w [N,3]."""
        request = surface_pb2.PdfDirectionRequest(handle=self.handle, w=float_array(w, len(w), 3))
        reply = self._call("Emitter.PdfDirection", self._stub.PdfDirection, request)
        return array_to_numpy(reply.pdf)
