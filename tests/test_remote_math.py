"""Numerical components in other processes, end to end: a Python warp,
generator, root finder and integrator made on yarfd by class name
(Factory.Create of a registered class) answer through yarfd's own Warp,
Generator, RootFinder and Integrator services as the C++ classes do; the
root finder and the integrator call back the integrand, which yarfd
serves them for the call; a component that answers wrongly or hangs fails
the call naming itself and the call, and yarfd goes on."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path

import grpc
import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import REPO

from yarf import Client, LocalServer, integrate
from yarf.client import array_to_numpy, numpy_to_array
from yarf.integrate import serve_function
from yarf.v1 import component_pb2, math_pb2, math_pb2_grpc

EXAMPLES = REPO / "components" / "python" / "examples"
FAULTY = Path(__file__).resolve().parent / "components" / "faulty_math.py"
TARGETS = [
    f"{EXAMPLES / 'cosine_hemisphere.py'}:CosineHemisphere",
    f"{EXAMPLES / 'pcg32.py'}:Pcg32",
    f"{EXAMPLES / 'bisection.py'}:Bisection",
    f"{EXAMPLES / 'vegas.py'}:Vegas",
    f"{EXAMPLES / 'halton.py'}:Halton",
    f"{FAULTY}:FaultyWarp",
    f"{FAULTY}:FaultyGenerator",
    f"{FAULTY}:FaultyRootFinder",
    f"{FAULTY}:FaultyIntegrator",
]


@pytest.fixture(scope="module")
def components(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ComponentProcess]:
    socket = tmp_path_factory.mktemp("math") / "math.sock"
    with ComponentProcess.python(TARGETS, f"unix:{socket}") as process:
        yield process


@pytest.fixture(scope="module")
def registered(client: Client, components: ComponentProcess) -> Iterator[str]:
    """The components' classes, registered with the session's yarfd."""
    client.registry.Register(
        component_pb2.RegisterRequest(address=components.address, lease_seconds=3600)
    )
    yield components.address
    client.registry.Unregister(component_pb2.UnregisterRequest(address=components.address))


def made(client: Client, class_name: str, **values: str) -> int:
    properties = component_pb2.Properties()
    for key, value in values.items():
        properties.values[key].string_value = value
    return client.create(class_name, properties).handle


def uniform_points(count: int, seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).random((count, 2), np.float32)


def test_a_python_warp_on_yarfd_agrees_with_the_cpp_warp(client: Client, registered: str) -> None:
    warp = math_pb2_grpc.WarpStub(client.channel)
    python, cpp = made(client, "py_cosine_hemisphere"), made(client, "cosine_hemisphere")
    signature = warp.Signature(math_pb2.WarpSignatureRequest(handle=python))
    assert (signature.domain_dimensions, signature.image_dimensions) == (2, 3)
    uniform = numpy_to_array(uniform_points(4096))
    forward = {
        h: warp.Forward(math_pb2.WarpRequest(handle=h, points=uniform)) for h in (python, cpp)
    }
    np.testing.assert_allclose(
        array_to_numpy(forward[python].points), array_to_numpy(forward[cpp].points), atol=2e-6
    )
    np.testing.assert_allclose(
        array_to_numpy(forward[python].pdf), array_to_numpy(forward[cpp].pdf), rtol=1e-5, atol=1e-6
    )
    directions = forward[cpp].points
    pdf = {h: warp.Pdf(math_pb2.WarpRequest(handle=h, points=directions)) for h in (python, cpp)}
    np.testing.assert_allclose(
        array_to_numpy(pdf[python].pdf), array_to_numpy(pdf[cpp].pdf), rtol=1e-5, atol=1e-6
    )
    # The Python warp has no inverse: yarfd says so, naming it and the call.
    with pytest.raises(grpc.RpcError) as inverse:
        warp.Inverse(math_pb2.WarpRequest(handle=python, points=directions))
    assert f"component 'py_cosine_hemisphere' at {registered}" in inverse.value.details()
    assert "Warp.Inverse failed: UNIMPLEMENTED" in inverse.value.details()


def test_a_python_generator_on_yarfd_gives_the_numbers_of_the_cpp_pcg32(
    client: Client, registered: str
) -> None:
    generator = math_pb2_grpc.GeneratorStub(client.channel)
    python, cpp = made(client, "py_pcg32"), made(client, "pcg32")
    for seed, stream, offset in [(42, 54, 0), (7, 3, 123_456_789)]:
        numbers = [
            array_to_numpy(
                generator.Next(
                    math_pb2.GeneratorRequest(
                        handle=h, seed=seed, stream=stream, offset=offset, count=2000
                    )
                ).values
            )
            for h in (python, cpp)
        ]
        np.testing.assert_array_equal(numbers[0], numbers[1])
        assert numbers[0].shape == (2000,) and np.all((numbers[0] >= 0) & (numbers[0] < 1))


def find_root(client: Client, handle: int, address: str, lower: float, upper: float) -> float:
    stub = math_pb2_grpc.RootFinderStub(client.channel)
    request = math_pb2.FindRootRequest(
        handle=handle,
        function_address=address,
        lower=lower,
        upper=upper,
        tolerance=1e-6,
        max_iterations=100,
    )
    return stub.FindRoot(request, timeout=30).root


def test_a_python_root_finder_on_yarfd_finds_the_analytic_root(
    client: Client, registered: str
) -> None:
    # The cube root of 2, found by the Python bisection and by the C++ brent,
    # both calling back the function this process serves, through yarfd.
    with serve_function(lambda x: x[:, 0] ** 3 - 2, 1) as address:
        python = find_root(client, made(client, "py_bisection"), address, 0.0, 2.0)
        cpp = find_root(client, made(client, "brent"), address, 0.0, 2.0)
    assert python == pytest.approx(2 ** (1 / 3), abs=2e-6)
    assert python == pytest.approx(cpp, abs=4e-6)


def test_a_python_root_finder_refuses_a_bracket_without_a_root(
    client: Client, registered: str
) -> None:
    with (
        serve_function(lambda x: x[:, 0] ** 2 + 1, 1) as address,
        pytest.raises(grpc.RpcError) as refused,
    ):
        find_root(client, made(client, "py_bisection"), address, -1.0, 1.0)
    assert "RootFinder.FindRoot failed: INVALID_ARGUMENT" in refused.value.details()
    assert "same sign" in refused.value.details()


def peak(x: np.ndarray) -> np.ndarray:
    return np.exp(-np.sum((x - 0.4) ** 2, axis=1) / (2 * 0.1**2))


# ∫_0^1 of one axis's Gaussian: σ √(π/2) (erf(0.6 / σ√2) + erf(0.4 / σ√2)), squared.
PEAK_INTEGRAL = (
    0.1
    * math.sqrt(math.pi / 2)
    * (math.erf(0.6 / (0.1 * math.sqrt(2))) + math.erf(0.4 / (0.1 * math.sqrt(2))))
) ** 2


def test_the_python_vegas_on_yarfd_integrates_within_its_error(
    client: Client, registered: str
) -> None:
    python = integrate(
        peak, [0, 0], [1, 1], method="py_vegas", evaluations=60_000, seed=3, server=client
    )
    cpp = integrate(peak, [0, 0], [1, 1], method="vegas", evaluations=60_000, seed=3, server=client)
    assert 0 < python.standard_error[0] < 0.01 * PEAK_INTEGRAL
    assert abs(python.estimate[0] - PEAK_INTEGRAL) < 4 * python.standard_error[0]
    joint = np.hypot(python.standard_error[0], cpp.standard_error[0])
    assert abs(python.estimate[0] - cpp.estimate[0]) < 4 * joint
    assert 0 < python.evaluations <= 60_000
    assert python.q.shape == (1,) and 0 <= python.q[0] <= 1


def test_the_python_vegas_draws_from_a_sampler_of_its_own_process(
    client: Client, registered: str
) -> None:
    # py_halton made on yarfd lives in the integrator's process: the request
    # names it there by its handle, and the estimate stays within its error.
    result = integrate(
        peak,
        [0, 0],
        [1, 1],
        method="py_vegas",
        sampler="py_halton",
        evaluations=40_000,
        seed=5,
        server=client,
    )
    assert 0 < result.standard_error[0] < 0.02 * PEAK_INTEGRAL
    assert abs(result.estimate[0] - PEAK_INTEGRAL) < 4 * result.standard_error[0]
    # Its own independent points for the same seed give another estimate.
    own = integrate(
        peak, [0, 0], [1, 1], method="py_vegas", evaluations=40_000, seed=5, server=client
    )
    assert own.estimate[0] != result.estimate[0]


def test_a_remote_integrator_cannot_take_a_sampler_of_yarfd(
    client: Client, registered: str
) -> None:
    # IntegrateRequest names a sampler by its handle in the integrator's
    # own process: yarfd's sobol cannot be lent to it, and the error says why.
    with pytest.raises(grpc.RpcError) as refused:
        integrate(
            peak,
            [0, 0],
            [1, 1],
            method="py_vegas",
            sampler="sobol",
            evaluations=5000,
            server=client,
        )
    assert "component 'py_vegas'" in refused.value.details()
    assert "cannot draw its points from sampler 'sobol'" in refused.value.details()


# (class, fault, what the error must say besides the class and the call).
def warp_forward(client: Client, handle: int) -> None:
    stub = math_pb2_grpc.WarpStub(client.channel)
    stub.Forward(math_pb2.WarpRequest(handle=handle, points=numpy_to_array(uniform_points(64))))


def generator_next(client: Client, handle: int) -> None:
    stub = math_pb2_grpc.GeneratorStub(client.channel)
    stub.Next(math_pb2.GeneratorRequest(handle=handle, seed=1, count=64))


def root_finder_find_root(client: Client, handle: int) -> None:
    with serve_function(lambda x: x[:, 0] - 0.5, 1) as address:
        find_root(client, handle, address, 0.0, 1.0)


def integrator_integrate(client: Client, handle: int) -> None:
    with serve_function(lambda x: x[:, 0], 1) as address:
        stub = math_pb2_grpc.IntegratorStub(client.channel)
        request = math_pb2.IntegrateRequest(
            handle=handle, function_address=address, lower=[0], upper=[1], evaluations=64
        )
        stub.Integrate(request, timeout=30)


CALLS = {
    "faulty_warp": ("Warp.Forward", warp_forward),
    "faulty_generator": ("Generator.Next", generator_next),
    "faulty_root_finder": ("RootFinder.FindRoot", root_finder_find_root),
    "faulty_integrator": ("Integrator.Integrate", integrator_integrate),
}
FAULTS = [
    ("faulty_warp", "shape", "points of shape [63, 2]"),
    ("faulty_warp", "nan", "non-finite value"),
    ("faulty_warp", "range", "negative pdf"),
    ("faulty_generator", "shape", "values of shape [63]"),
    ("faulty_generator", "nan", "non-finite value"),
    ("faulty_generator", "range", "outside [0, 1)"),
    ("faulty_root_finder", "range", "outside the bracket"),
    ("faulty_root_finder", "nan", "outside the bracket"),
    ("faulty_integrator", "shape", "2 values of estimate for 1 outputs"),
    ("faulty_integrator", "nan", "non-finite estimate"),
    ("faulty_integrator", "range", "negative standard_error"),
]


@pytest.mark.parametrize(("class_name", "fault", "words"), FAULTS)
def test_a_faulty_reply_fails_the_call_naming_the_class_and_the_call(
    client: Client, registered: str, class_name: str, fault: str, words: str
) -> None:
    method, call = CALLS[class_name]
    with pytest.raises(grpc.RpcError) as failure:
        call(client, made(client, class_name, fault=fault))
    details = failure.value.details()
    assert f"component '{class_name}' at {registered}: {method} returned" in details, details
    assert words in details, details
    assert client.is_serving()


@pytest.fixture(scope="module")
def impatient_server(components: ComponentProcess) -> Iterator[Client]:
    """A yarfd that gives component calls one second."""
    args = ["--component", components.address, "--component-timeout", "1"]
    with LocalServer(extra_args=args) as local, local.client() as c:
        yield c


@pytest.mark.parametrize("class_name", list(CALLS))
def test_a_hanging_component_fails_the_call_at_the_deadline(
    impatient_server: Client, components: ComponentProcess, class_name: str
) -> None:
    method, call = CALLS[class_name]
    started = time.monotonic()
    with pytest.raises(grpc.RpcError) as failure:
        call(impatient_server, made(impatient_server, class_name, fault="hang"))
    details = failure.value.details()
    assert f"component '{class_name}' at {components.address}: {method} failed" in details
    assert "DEADLINE_EXCEEDED" in details
    assert time.monotonic() - started < 10
    # yarfd still answers, and the component's good classes still work.
    generator = math_pb2_grpc.GeneratorStub(impatient_server.channel)
    reply = generator.Next(
        math_pb2.GeneratorRequest(handle=made(impatient_server, "py_pcg32"), seed=1, count=8)
    )
    assert array_to_numpy(reply.values).shape == (8,)
