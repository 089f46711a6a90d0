"""A participating medium of a running job: yarfd's Medium instance, as numpy calls.

Points and directions are in world space, float32 [N,3]; coefficients per unit
length of the scene, RGB.
"""

from __future__ import annotations

import functools

import numpy as np

from yarf.client import array_to_numpy
from yarf.v1 import medium_pb2, medium_pb2_grpc
from yarf_component.channels import channel
from yarf_component.job_calls import Caller, float_array


class MediumClient:
    """Medium instance ``handle`` on the yarfd of a job (``layout.medium_handles``)."""

    def __init__(self, caller: Caller, handle: int) -> None:
        self._call = caller
        self._stub = medium_pb2_grpc.MediumStub(channel(caller.address))
        self.handle = handle

    @functools.cached_property
    def emits(self) -> bool:
        """Whether the medium may ever emit (asked once)."""
        request = medium_pb2.EmitsRequest(handle=self.handle)
        return self._call("Medium.Emits", self._stub.Emits, request).emits

    def coefficients(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """σ_a, σ_s and the emitted radiance [N,3] at points [N,3]."""
        request = medium_pb2.CoefficientsRequest(
            handle=self.handle, position=float_array(positions, len(positions), 3)
        )
        reply = self._call("Medium.Coefficients", self._stub.Coefficients, request)
        return (
            array_to_numpy(reply.sigma_a),
            array_to_numpy(reply.sigma_s),
            array_to_numpy(reply.emission),
        )

    def majorants(
        self, origins: np.ndarray, directions: np.ndarray, tmax: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Segments [M,5] (t0, t1, σ_maj RGB) over which σ_t stays below σ_maj along each
        ray within [0, tmax), and offsets [N+1]: ray i owns rows offsets[i]..offsets[i+1]-1."""
        n = len(origins)
        request = medium_pb2.MajorantsRequest(
            handle=self.handle,
            origin=float_array(origins, n, 3),
            direction=float_array(directions, n, 3),
            tmax=float_array(tmax, n),
        )
        reply = self._call("Medium.Majorants", self._stub.Majorants, request)
        return array_to_numpy(reply.segments).reshape(-1, 5), array_to_numpy(reply.offsets)

    def evaluate_phase(
        self, wi: np.ndarray, wo: np.ndarray, positions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The phase function p(wi, wo) [N] and SamplePhase's density [N] for wo; wi points
        back toward where the path came from, wo toward where light comes from."""
        n = len(wi)
        request = medium_pb2.PhaseQuery(
            handle=self.handle,
            wi=float_array(wi, n, 3),
            wo=float_array(wo, n, 3),
            position=float_array(positions, n, 3),
        )
        reply = self._call("Medium.EvaluatePhase", self._stub.EvaluatePhase, request)
        return array_to_numpy(reply.value), array_to_numpy(reply.pdf)

    def sample_phase(
        self, wi: np.ndarray, positions: np.ndarray, uniform: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """wo [N,3] drawn with uniform [N,2], its weight p/pdf [N] and its density [N]."""
        n = len(wi)
        request = medium_pb2.SamplePhaseRequest(
            handle=self.handle,
            wi=float_array(wi, n, 3),
            position=float_array(positions, n, 3),
            uniform=float_array(uniform, n, 2),
        )
        reply = self._call("Medium.SamplePhase", self._stub.SamplePhase, request)
        return array_to_numpy(reply.wo), array_to_numpy(reply.weight), array_to_numpy(reply.pdf)
