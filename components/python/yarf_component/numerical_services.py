"""The services of math.proto (Function, Sampler, Generator, Warp, RootFinder,
Integrator) over a Host's instances.

Replies carry what the instance returned, converted to float32 and
unchecked (the caller validates them); an Integrator's integrand and
sampler, and a RootFinder's function, are checked, as the SDK is their
caller (integrand.py).
"""

from __future__ import annotations

from collections.abc import Iterator

import grpc
import numpy as np

from yarf.v1 import math_pb2, math_pb2_grpc
from yarf_component.arrays import MAX_VALUES, Batch, float32
from yarf_component.calls import RpcFailure, invalid, rpc, user_code
from yarf_component.host import Host
from yarf_component.integrand import resolve_integrand, resolve_sampler
from yarf_component.numerical import (
    Function,
    Generator,
    Integrator,
    NoRoot,
    RootFinder,
    Sampler,
    Warp,
)


def _dimensions(instance: object, *names: str) -> list[int]:
    with user_code(instance, names[0]):
        return [int(getattr(instance, name)) for name in names]


class FunctionService(math_pb2_grpc.FunctionServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Signature(
        self, request: math_pb2.FunctionSignatureRequest, context: grpc.ServicerContext
    ) -> math_pb2.FunctionSignature:
        function = self._host.instance(request.handle, Function)
        d, k = _dimensions(function, "input_dimensions", "output_dimensions")
        return math_pb2.FunctionSignature(input_dimensions=d, output_dimensions=k)

    def _evaluate(self, request: math_pb2.EvaluateRequest) -> math_pb2.EvaluateReply:
        function = self._host.instance(request.handle, Function)
        (d,) = _dimensions(function, "input_dimensions")
        points = Batch().floats(request.points, "points", d)
        with user_code(function, "evaluate"):
            values = float32(function.evaluate(points))
        return math_pb2.EvaluateReply(values=values, sequence=request.sequence)

    @rpc
    def Evaluate(
        self, request: math_pb2.EvaluateRequest, context: grpc.ServicerContext
    ) -> math_pb2.EvaluateReply:
        return self._evaluate(request)

    def EvaluateStream(
        self, requests: Iterator[math_pb2.EvaluateRequest], context: grpc.ServicerContext
    ) -> Iterator[math_pb2.EvaluateReply]:
        for request in requests:
            try:
                reply = self._evaluate(request)
            except RpcFailure as failure:
                context.abort(failure.code, failure.message)
            yield reply


class SamplerService(math_pb2_grpc.SamplerServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Generate(
        self, request: math_pb2.GenerateSamplesRequest, context: grpc.ServicerContext
    ) -> math_pb2.GenerateSamplesReply:
        sampler = self._host.instance(request.handle, Sampler)
        if request.count * request.dimensions > MAX_VALUES:
            raise invalid(
                f"batch of {request.count * request.dimensions} values exceeds {MAX_VALUES}"
            )
        with user_code(sampler, "generate"):
            points = sampler.generate(
                request.first_index, request.count, request.dimensions, request.seed
            )
            return math_pb2.GenerateSamplesReply(points=float32(points))


class GeneratorService(math_pb2_grpc.GeneratorServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Next(
        self, request: math_pb2.GeneratorRequest, context: grpc.ServicerContext
    ) -> math_pb2.GeneratorReply:
        generator = self._host.instance(request.handle, Generator)
        if request.count > MAX_VALUES:
            raise invalid(f"batch of {request.count} values exceeds {MAX_VALUES}")
        with user_code(generator, "next"):
            values = generator.next(request.seed, request.stream, request.offset, request.count)
            return math_pb2.GeneratorReply(values=float32(values))


class WarpService(math_pb2_grpc.WarpServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Signature(
        self, request: math_pb2.WarpSignatureRequest, context: grpc.ServicerContext
    ) -> math_pb2.WarpSignature:
        warp = self._host.instance(request.handle, Warp)
        m, n = _dimensions(warp, "domain_dimensions", "image_dimensions")
        return math_pb2.WarpSignature(domain_dimensions=m, image_dimensions=n)

    def _points(self, request: math_pb2.WarpRequest, domain: bool) -> tuple[Warp, np.ndarray]:
        warp = self._host.instance(request.handle, Warp)
        (columns,) = _dimensions(warp, "domain_dimensions" if domain else "image_dimensions")
        return warp, Batch().floats(request.points, "points", columns)

    @rpc
    def Forward(
        self, request: math_pb2.WarpRequest, context: grpc.ServicerContext
    ) -> math_pb2.WarpReply:
        warp, points = self._points(request, domain=True)
        with user_code(warp, "forward"):
            image, pdf = warp.forward(points)
            return math_pb2.WarpReply(points=float32(image), pdf=float32(pdf))

    @rpc
    def Inverse(
        self, request: math_pb2.WarpRequest, context: grpc.ServicerContext
    ) -> math_pb2.WarpReply:
        warp, points = self._points(request, domain=False)
        with user_code(warp, "inverse", unimplemented=True):
            preimage, pdf = warp.inverse(points)
            return math_pb2.WarpReply(points=float32(preimage), pdf=float32(pdf))

    @rpc
    def Pdf(
        self, request: math_pb2.WarpRequest, context: grpc.ServicerContext
    ) -> math_pb2.WarpReply:
        warp, points = self._points(request, domain=False)
        with user_code(warp, "pdf"):
            return math_pb2.WarpReply(pdf=float32(warp.pdf(points)))


def _doubles(values: object) -> list[float]:
    return np.atleast_1d(np.asarray(values, dtype=np.float64)).tolist()


class RootFinderService(math_pb2_grpc.RootFinderServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def FindRoot(
        self, request: math_pb2.FindRootRequest, context: grpc.ServicerContext
    ) -> math_pb2.FindRootReply:
        finder = self._host.instance(request.handle, RootFinder)
        f = resolve_integrand(self._host, request.function_address, request.function_handle)
        if f.input_dimensions != 1:
            raise invalid(f"{f.name} takes {f.input_dimensions} inputs; a root finder's takes 1")
        if not request.lower < request.upper:
            raise invalid(f"the bracket [{request.lower}, {request.upper}] is empty")
        if not request.tolerance > 0:
            raise invalid(f"tolerance must be positive, not {request.tolerance}")
        with user_code(finder, "find_root"):
            try:
                root, iterations = finder.find_root(
                    f, request.lower, request.upper, request.tolerance, request.max_iterations
                )
            except NoRoot as error:
                raise invalid(f"{type(finder).__name__}.find_root: {error}") from None
            return math_pb2.FindRootReply(root=float(root), iterations=int(iterations))


class IntegratorService(math_pb2_grpc.IntegratorServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Integrate(
        self, request: math_pb2.IntegrateRequest, context: grpc.ServicerContext
    ) -> math_pb2.IntegrateReply:
        integrator = self._host.instance(request.handle, Integrator)
        f = resolve_integrand(self._host, request.function_address, request.function_handle)
        sampler = resolve_sampler(self._host, request.sampler_handle, request.seed)
        d = f.input_dimensions
        if len(request.lower) != d or len(request.upper) != d:
            raise invalid(f"the box needs {d} lower and upper bounds")
        if not 1 <= request.evaluations <= 1 << 36:
            raise invalid("evaluations must lie in [1, 2^36]")
        lower = np.array(request.lower, dtype=np.float64)
        upper = np.array(request.upper, dtype=np.float64)
        with user_code(integrator, "integrate"):
            answer = integrator.integrate(
                f, lower, upper, request.evaluations, request.seed, sampler
            )
            if len(answer) not in (3, 5):
                raise ValueError(
                    "integrate returned a tuple of "
                    f"{len(answer)}, not (estimate, error, evaluations[, chi2_per_dof, q])"
                )
            estimate, error, evaluations = answer[:3]
            chi2, q = answer[3:] if len(answer) == 5 else ([], [])
            return math_pb2.IntegrateReply(
                estimate=_doubles(estimate),
                standard_error=_doubles(error),
                evaluations=int(evaluations),
                chi2_per_dof=_doubles(chi2),
                q=_doubles(q),
            )
