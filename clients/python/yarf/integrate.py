"""Numerical integration of a Python function by the server's integrators.

``integrate(f, lower, upper, method="vegas", evaluations=N)`` serves ``f``
— a numpy-vectorised function of points [N, d] returning [N] or [N, k] —
as an out-of-process yarf.v1.Function on 127.0.0.1, and asks a yarfd to
integrate it with the named Integrator class, which calls ``f`` back in
batches.

The result says, for integrators that average iterations (vegas, vegas+),
how well the iterations agree: χ²/dof and Q as G. P. Lepage's ``vegas``
package reports them; Q < 0.05 raises an ``IntegrationWarning``, as the
error is then not to be trusted. Lepage's option names are accepted too
(``LEPAGE_OPTIONS``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
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
# Lepage's vegas option names and the yarf names they stand for. All but
# neval are integrator properties; neval is his evaluations per iteration,
# so it sets the budget: evaluations = neval · nitn (nitn, or the
# "iterations" given, else yarf's default of ITERATIONS).
LEPAGE_OPTIONS: Mapping[str, str] = {
    "nitn": "iterations",
    "neval": "evaluations",
    "alpha": "alpha",
    "beta": "beta",
}
ITERATIONS = 10
DEFAULT_EVALUATIONS = 100_000
# Below this Q the iterations disagree beyond their errors (Lepage's rule).
SMALL_Q = 0.05


class IntegrationWarning(UserWarning):
    """The iterations of an integral disagree beyond their errors (Q < 0.05)."""


def _nan_unless_given(values: Sequence[float], outputs: int) -> np.ndarray:
    return np.array(values, dtype=np.float64) if values else np.full(outputs, np.nan)


@dataclass(frozen=True)
class Integral:
    """An integrator's answer: one estimate and standard error per output.

    For integrators that average iterations, ``chi2_per_dof`` and ``q`` are,
    per output, χ² of the kept iterations about their weighted average over
    its degrees of freedom (iterations − 1) and the probability of a χ² at
    least as large (Lepage's Q); NaN for one-shot methods or one iteration.
    """

    estimate: np.ndarray
    standard_error: np.ndarray
    evaluations: int
    chi2_per_dof: np.ndarray
    q: np.ndarray

    @property
    def trustworthy(self) -> bool:
        """False when some output's Q is below 0.05."""
        return not bool(np.any(self.q < SMALL_Q))

    def __str__(self) -> str:
        lines = []
        for k, (mean, error) in enumerate(zip(self.estimate, self.standard_error, strict=True)):
            line = f"{mean:.8g} ± {error:.2g}"
            if not math.isnan(self.q[k]):
                line += f"  χ²/dof = {self.chi2_per_dof[k]:.2f}  Q = {self.q[k]:.2f}"
                if self.q[k] < SMALL_Q:
                    line += "  (Q < 0.05: iterations disagree, error not to be trusted)"
            lines.append(line if len(self.estimate) == 1 else f"[{k}] {line}")
        lines.append(f"{self.evaluations} evaluations")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (
            f"Integral(estimate={self.estimate.tolist()}, "
            f"standard_error={self.standard_error.tolist()}, evaluations={self.evaluations}, "
            f"chi2_per_dof={self.chi2_per_dof.tolist()}, q={self.q.tolist()})"
        )


def lepage_options(
    options: Mapping[str, PropertyValue], evaluations: int | None
) -> tuple[dict[str, PropertyValue], int]:
    """yarf's properties and budget from options that may use Lepage's names."""
    renamed: dict[str, PropertyValue] = {}
    neval: PropertyValue | None = None
    for key, value in options.items():
        name = LEPAGE_OPTIONS.get(key, key)
        if name == "evaluations":
            neval = value
            continue
        if name in renamed:
            raise ValueError(f"option {key!r} names {name!r}, which is given twice")
        renamed[name] = value
    if neval is None:
        return renamed, DEFAULT_EVALUATIONS if evaluations is None else evaluations
    if evaluations is not None:
        raise ValueError("give either neval (per iteration) or evaluations (in all), not both")
    if not isinstance(neval, int) or isinstance(neval, bool) or neval < 1:
        raise ValueError(f"neval must be a positive int, not {neval!r}")
    iterations = renamed.get("iterations", ITERATIONS)
    if not isinstance(iterations, int) or isinstance(iterations, bool):
        raise ValueError(f"nitn must be an int, not {iterations!r}")
    return renamed, neval * iterations


class FunctionService(math_pb2_grpc.FunctionServicer):
    """Serves one numpy-vectorised function as yarf.v1.Function (handle 0)."""

    def __init__(self, f: VectorFunction, input_dimensions: int) -> None:
        self.f = f
        self.input_dimensions = input_dimensions
        probe = self._call(np.full((1, input_dimensions), 0.5, np.float32))
        self.output_dimensions = probe.shape[1]

    def _call(self, points: np.ndarray) -> np.ndarray:
        """f's values as float32, the type the server integrates; values that
        float32 would change beyond rounding are refused, not changed."""
        returned = np.asarray(self.f(points))
        if np.iscomplexobj(returned):
            raise TypeError(
                "the function returned complex values: return the real and imaginary "
                "parts as two outputs"
            )
        if returned.dtype.kind not in "biuf":
            raise TypeError(f"the function returned {returned.dtype} values, not numbers")
        with np.errstate(over="ignore"):  # overflow is checked next
            values = returned.astype(np.float32)
        if np.any(np.isinf(values) & np.isfinite(returned)):
            raise ValueError(
                "the function returned a value beyond float32's range (3.4e38), "
                "which the server integrates in: scale it down"
            )
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
    evaluations: int | None = None,
    seed: int = 0,
    sampler: str | None = None,
    server: str | Client | None = None,
    **options: PropertyValue,
) -> Integral:
    """∫ f over the box [lower, upper] by the server's Integrator ``method``.

    ``evaluations`` is the budget, never exceeded (default 100 000).
    ``options`` configure the integrator (e.g. ``iterations=10``), by yarf's
    names or Lepage's (``nitn``, ``alpha``, ``beta``; ``neval``, his points
    per iteration, sets evaluations = neval · nitn; see LEPAGE_OPTIONS);
    ``sampler`` names the point set (None: "sobol_nd" for rqmc, else
    "independent"); ``server`` is an address or a Client, else a local
    yarfd is started. Warns (IntegrationWarning) when Q < 0.05.
    """
    if len(lower) != len(upper) or not lower:
        raise ValueError("lower and upper need one bound per dimension")
    options, evaluations = lepage_options(options, evaluations)
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
    outputs = len(reply.estimate)
    result = Integral(
        estimate=np.array(reply.estimate),
        standard_error=np.array(reply.standard_error),
        evaluations=reply.evaluations,
        chi2_per_dof=_nan_unless_given(reply.chi2_per_dof, outputs),
        q=_nan_unless_given(reply.q, outputs),
    )
    if not result.trustworthy:
        warnings.warn(
            f"{method}: Q = {np.nanmin(result.q):.3f} < {SMALL_Q}: the iterations disagree "
            "beyond their errors, so the standard error is not to be trusted "
            "(more evaluations per iteration, or more iterations discarded, may help)",
            IntegrationWarning,
            stacklevel=2,
        )
    return result
