"""What an Integrator receives: its integrand and its sampler as numpy callables.

The integrand is the Function a request names, in this process or at
another address; each call of the callable is one batch (split only when
it would exceed a message). Its values are checked, as yarfd checks a
remote function's, so an integrator never averages garbage.
"""

from __future__ import annotations

import threading
import typing
from collections.abc import Callable
from typing import TypeVar

import grpc
import numpy as np
from google.protobuf.message import Message

from yarf.client import array_to_numpy, numpy_to_array
from yarf.v1 import math_pb2, math_pb2_grpc
from yarf_component.calls import RpcFailure, user_code
from yarf_component.channels import channel
from yarf_component.host import Host
from yarf_component.numerical import Function, Sampler

# Values per Evaluate call, well under the message limit.
MAX_VALUES_PER_CALL = 1 << 24
DEFAULT_TIMEOUT = 60.0

Reply = TypeVar("Reply", bound=Message)


class CalleeError(RpcFailure):
    """The integrand or the sampler an integrator called failed."""

    def __init__(self, message: str) -> None:
        super().__init__(grpc.StatusCode.FAILED_PRECONDITION, message)


def _checked_values(values: np.ndarray, rows: int, outputs: int, name: str) -> np.ndarray:
    if values.shape != (rows, outputs):
        raise CalleeError(
            f"{name} returned shape {list(values.shape)} for {rows} points of {outputs} outputs"
        )
    if not np.all(np.isfinite(values)):
        raise CalleeError(f"{name} returned a non-finite value")
    return values.astype(np.float64)


class Integrand:
    """f: points [N, d] -> float64 values [N, k]; counts the points it was given."""

    def __init__(self, name: str, input_dimensions: int, output_dimensions: int) -> None:
        if input_dimensions < 1 or output_dimensions < 1:
            raise CalleeError(f"{name} has no dimensions")
        self.name = name
        self.input_dimensions = input_dimensions
        self.output_dimensions = output_dimensions
        self.evaluations = 0
        self._lock = threading.Lock()

    def __call__(self, points: np.ndarray) -> np.ndarray:
        points = np.ascontiguousarray(points, dtype=np.float32)
        if points.ndim != 2 or points.shape[1] != self.input_dimensions:
            raise ValueError(
                f"{self.name} takes points [N, {self.input_dimensions}], not {list(points.shape)}"
            )
        rows = max(1, MAX_VALUES_PER_CALL // self.input_dimensions)
        parts = [
            _checked_values(
                self._evaluate(points[start : start + rows]),
                len(points[start : start + rows]),
                self.output_dimensions,
                self.name,
            )
            for start in range(0, max(len(points), 1), rows)
        ]
        with self._lock:
            self.evaluations += len(points)
        return np.concatenate(parts) if len(parts) > 1 else parts[0]

    def _evaluate(self, points: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class LocalIntegrand(Integrand):
    """A Function instance of this process, called directly."""

    def __init__(self, function: Function) -> None:
        with user_code(function, "input_dimensions"):
            dimensions = int(function.input_dimensions), int(function.output_dimensions)
        super().__init__(f"function '{function.class_name}'", *dimensions)
        self._function = function

    def _evaluate(self, points: np.ndarray) -> np.ndarray:
        try:
            with user_code(self._function, "evaluate"):
                return np.asarray(self._function.evaluate(points), dtype=np.float32)
        except RpcFailure as failure:
            raise CalleeError(failure.message) from None


class RemoteIntegrand(Integrand):
    """Function ``handle`` at ``address``, one Evaluate call per batch."""

    def __init__(self, address: str, handle: int, timeout: float = DEFAULT_TIMEOUT) -> None:
        self._stub = math_pb2_grpc.FunctionStub(channel(address))
        self._handle = handle
        self._timeout = timeout
        self._sequence = 0
        name = f"remote function {handle} at {address}"
        request = math_pb2.FunctionSignatureRequest(handle=handle)
        signature = self._call(name, "Signature", self._stub.Signature, request)
        super().__init__(name, signature.input_dimensions, signature.output_dimensions)

    @staticmethod
    def _call(
        name: str,
        method: str,
        stub_method: Callable[..., Reply],
        request: Message,
        timeout: float = DEFAULT_TIMEOUT,
    ) -> Reply:
        try:
            return stub_method(request, timeout=timeout)
        except grpc.RpcError as error:
            call = typing.cast(grpc.Call, error)
            raise CalleeError(
                f"{name}: {method} failed: {call.code().name}: {call.details()}"
            ) from None

    def _evaluate(self, points: np.ndarray) -> np.ndarray:
        self._sequence += 1
        request = math_pb2.EvaluateRequest(
            handle=self._handle, points=numpy_to_array(points), sequence=self._sequence
        )
        reply = self._call(self.name, "Evaluate", self._stub.Evaluate, request, self._timeout)
        try:
            return array_to_numpy(reply.values)
        except ValueError as error:
            raise CalleeError(f"{self.name}: Evaluate returned {error}") from None


def resolve_integrand(host: Host, address: str, handle: int) -> Integrand:
    """The integrand of an Integrate request: a Function here, or at ``address``."""
    if address:
        return RemoteIntegrand(address, handle)
    return LocalIntegrand(host.instance(handle, Function))


class SamplerPoints:
    """(first, count, d) -> float32 points of a Sampler instance of this process for one seed."""

    def __init__(self, sampler: Sampler, seed: int) -> None:
        self._sampler = sampler
        self._seed = seed

    def __call__(self, first_index: int, count: int, dimensions: int) -> np.ndarray:
        try:
            with user_code(self._sampler, "generate"):
                points = np.asarray(
                    self._sampler.generate(
                        int(first_index), int(count), int(dimensions), self._seed
                    ),
                    dtype=np.float32,
                )
        except RpcFailure as failure:
            raise CalleeError(failure.message) from None
        if points.shape != (count, dimensions):
            raise CalleeError(
                f"sampler '{self._sampler.class_name}' returned shape {list(points.shape)} "
                f"for {count} points of {dimensions} dimensions"
            )
        return points


def resolve_sampler(host: Host, handle: int, seed: int) -> SamplerPoints | None:
    """The points of an Integrate request's sampler; None (independent points) for handle 0."""
    if handle == 0:
        return None
    return SamplerPoints(host.instance(handle, Sampler), seed)
