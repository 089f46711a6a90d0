"""Calls from a transport to the yarfd running its job: deadlines, errors that name the
call, replies awaited later (so that independent calls overlap), and the arrays sent."""

from __future__ import annotations

import typing
from collections.abc import Callable
from typing import Generic, TypeVar

import grpc
import numpy as np
from google.protobuf.message import Message

from yarf.client import numpy_to_array
from yarf.v1 import component_pb2, geometry_pb2

Reply = TypeVar("Reply", bound=Message)
Result = TypeVar("Result")


class SceneViewError(RuntimeError):
    """A call to the job's scene failed (the job ended, yarfd went away...)."""


def _error(name: str, address: str, error: grpc.RpcError) -> SceneViewError:
    call = typing.cast(grpc.Call, error)
    return SceneViewError(f"{name} at {address}: {call.code().name}: {call.details()}")


class Pending(Generic[Result]):
    """A call in flight; ``result()`` waits for its reply, decoded."""

    def __init__(
        self, name: str, address: str, future: grpc.Future, decode: Callable[[typing.Any], Result]
    ) -> None:
        self._name = name
        self._address = address
        self._future = future
        self._decode = decode

    def result(self) -> Result:
        try:
            reply = self._future.result()
        except grpc.RpcError as error:
            raise _error(self._name, self._address, error) from None
        return self._decode(reply)


class Caller:
    """Unary calls to one address with a deadline; failures become SceneViewError."""

    def __init__(self, address: str, timeout: float) -> None:
        self.address = address
        self.timeout = timeout

    def __call__(self, name: str, method: Callable[..., Reply], request: Message) -> Reply:
        try:
            return method(request, timeout=self.timeout)
        except grpc.RpcError as error:
            raise _error(name, self.address, error) from None

    def start(
        self,
        name: str,
        method: grpc.UnaryUnaryMultiCallable,
        request: Message,
        decode: Callable[[typing.Any], Result],
    ) -> Pending[Result]:
        """Sends the call now; its reply is awaited by the Pending's ``result()``."""
        future = method.future(request, timeout=self.timeout)
        return Pending(name, self.address, future, decode)


def floats(values: np.ndarray | float, rows: int, columns: tuple[int, ...] = ()) -> np.ndarray:
    """``values`` as contiguous float32 [rows, *columns], broadcast from a scalar or a row."""
    return np.ascontiguousarray(
        np.broadcast_to(np.asarray(values, dtype=np.float32), (rows, *columns))
    )


def float_array(values: np.ndarray | float, rows: int, *columns: int) -> component_pb2.Array:
    return numpy_to_array(floats(values, rows, columns))


def ray_batch(
    origins: np.ndarray,
    directions: np.ndarray,
    tnear: np.ndarray | float | None = None,
    tfar: np.ndarray | float | None = None,
    times: np.ndarray | float | None = None,
) -> geometry_pb2.RayBatch:
    """The RayBatch of N rays; intervals default to [0, inf), times to 0."""
    n = len(origins)
    batch = geometry_pb2.RayBatch(
        origins=float_array(origins, n, 3), directions=float_array(directions, n, 3)
    )
    if tnear is not None or tfar is not None:
        intervals = np.empty((n, 2), np.float32)
        intervals[:, 0] = floats(0.0 if tnear is None else tnear, n)
        intervals[:, 1] = floats(np.inf if tfar is None else tfar, n)
        batch.intervals.CopyFrom(numpy_to_array(intervals))
    if times is not None:
        batch.times.CopyFrom(float_array(times, n))
    return batch
