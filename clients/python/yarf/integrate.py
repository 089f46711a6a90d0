"""Numerical integration of a Python function by the server's integrators.

``integrate(f, lower, upper, method="vegas", evaluations=N)`` serves ``f``
— a numpy-vectorised function of points [N, d] returning [N] or [N, k] —
as an out-of-process yarf.v1.Function on 127.0.0.1, and asks a yarfd to
integrate it with the named Integrator class, which calls ``f`` back in
batches.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from concurrent import futures
from contextlib import contextmanager
from dataclasses import dataclass

import grpc
import numpy as np

from yarf.client import Client, array_to_numpy, numpy_to_array
from yarf.scene import PropertyValue, properties
from yarf.server import LocalServer
from yarf.v1 import math_pb2, math_pb2_grpc

VectorFunction = Callable[[np.ndarray], np.ndarray]
# Method names as people write them, for classes whose names cannot hold them.
METHOD_CLASSES = {"vegas+": "vegas_plus"}
# The sampler a method takes when none is named: rqmc's error bars come from
# independent scramblings of one net, so it takes the Owen-scrambled Sobol
# sequence; the others make their own points adaptive or stratified, and
# take independent numbers.
DEFAULT_SAMPLERS = {"rqmc": "sobol_nd"}


@dataclass(frozen=True)
class Integral:
    """An integrator's answer: one estimate and standard error per output."""

    estimate: np.ndarray
    standard_error: np.ndarray
    evaluations: int


class FunctionService(math_pb2_grpc.FunctionServicer):
    """Serves one numpy-vectorised function as yarf.v1.Function (handle 0)."""

    def __init__(self, f: VectorFunction, input_dimensions: int) -> None:
        self.f = f
        self.input_dimensions = input_dimensions
        probe = self._call(np.full((1, input_dimensions), 0.5, np.float32))
        self.output_dimensions = probe.shape[1]

    def _call(self, points: np.ndarray) -> np.ndarray:
        values = np.asarray(self.f(points), dtype=np.float32)
        if values.ndim == 1:
            values = values[:, None]
        if values.ndim != 2 or values.shape[0] != points.shape[0]:
            raise ValueError(
                f"the function returned shape {values.shape} for {points.shape[0]} points"
            )
        return values

    def Signature(
        self, request: math_pb2.FunctionSignatureRequest, context: grpc.ServicerContext
    ) -> math_pb2.FunctionSignature:
        return math_pb2.FunctionSignature(
            input_dimensions=self.input_dimensions, output_dimensions=self.output_dimensions
        )

    def Evaluate(
        self, request: math_pb2.EvaluateRequest, context: grpc.ServicerContext
    ) -> math_pb2.EvaluateReply:
        try:
            points = array_to_numpy(request.points)
            values = self._call(points)
        except Exception as error:  # the caller sees the function's own message
            context.abort(grpc.StatusCode.INVALID_ARGUMENT, f"{type(error).__name__}: {error}")
        return math_pb2.EvaluateReply(values=numpy_to_array(values), sequence=request.sequence)


@contextmanager
def serve_function(f: VectorFunction, input_dimensions: int) -> Iterator[str]:
    """Serves ``f`` on a free loopback port for the block; yields its address."""
    service = FunctionService(f, input_dimensions)
    server = grpc.server(
        futures.ThreadPoolExecutor(max_workers=2),
        options=[
            ("grpc.max_receive_message_length", 256 << 20),
            ("grpc.max_send_message_length", 256 << 20),
        ],
    )
    math_pb2_grpc.add_FunctionServicer_to_server(service, server)
    port = server.add_insecure_port("127.0.0.1:0")
    server.start()
    try:
        yield f"127.0.0.1:{port}"
    finally:
        server.stop(grace=None)


@contextmanager
def _connect(server: str | Client | None) -> Iterator[Client]:
    if isinstance(server, Client):
        yield server
    elif server:
        with Client(server) as client:
            yield client
    else:
        with LocalServer() as local, local.client() as client:
            yield client


def integrate(
    f: VectorFunction,
    lower: Sequence[float],
    upper: Sequence[float],
    *,
    method: str = "vegas",
    evaluations: int = 100_000,
    seed: int = 0,
    sampler: str | None = None,
    server: str | Client | None = None,
    **options: PropertyValue,
) -> Integral:
    """∫ f over the box [lower, upper] by the server's Integrator ``method``.

    ``options`` configure the integrator (e.g. ``iterations=10``);
    ``sampler`` names the point set (None: "sobol_nd" for rqmc, else
    "independent"); ``server`` is an address or a Client, else a local
    yarfd is started.
    """
    if len(lower) != len(upper) or not lower:
        raise ValueError("lower and upper need one bound per dimension")
    with _connect(server) as client, serve_function(f, len(lower)) as address:
        integrator = client.create(METHOD_CLASSES.get(method, method), properties(**options)).handle
        sampler_handle = client.create(
            sampler or DEFAULT_SAMPLERS.get(method, "independent")
        ).handle
        try:
            reply = math_pb2_grpc.IntegratorStub(client.channel).Integrate(
                math_pb2.IntegrateRequest(
                    handle=integrator,
                    function_address=address,
                    lower=list(lower),
                    upper=list(upper),
                    evaluations=evaluations,
                    seed=seed,
                    sampler_handle=sampler_handle,
                )
            )
        finally:
            client.release(integrator)
            client.release(sampler_handle)
    return Integral(
        estimate=np.array(reply.estimate),
        standard_error=np.array(reply.standard_error),
        evaluations=reply.evaluations,
    )
