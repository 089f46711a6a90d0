"""The Python component SDK (components/python) over real gRPC sockets.

The SDK serves the example components in this process; the tests call
them as yarfd would: Describe and ListClasses, Create with good and bad
properties, the SurfaceModel examples against their own pdfs (Pearson's
χ² with the Wilson–Hilferty approximation), the Halton sampler's
determinism and discrepancy, VEGAS through the Integrator service on an
integrand served by the SDK's Function service, user exceptions, and the
yarf-component command with registration against a stand-in Registry.
Only the comparison of the Python surface models with the C++ ones needs
yarfd (the session's server); the rest runs without it.
"""

from __future__ import annotations

import math
import os
import select
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from concurrent import futures
from pathlib import Path
from typing import Literal

import grpc
import numpy as np
import pytest
from yarf_component import (
    Component,
    Function,
    PropertyError,
    Rgb,
    Running,
    ScatterFlags,
    Transform,
    Vec3,
    Warp,
    serve,
)
from yarf_component.loading import load_target
from yarf_component.properties import Signature

from yarf import Client, properties, rgb, transform, vec3
from yarf.client import array_to_numpy, numpy_to_array
from yarf.scene import Reference
from yarf.v1 import (
    component_pb2,
    component_pb2_grpc,
    math_pb2,
    math_pb2_grpc,
    surface_pb2,
    surface_pb2_grpc,
    transport_pb2,
    transport_pb2_grpc,
)

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = REPO / "components" / "python" / "examples"
SIGMA = 0.05
CENTRE = np.array([0.4, 0.45, 0.5, 0.55])


def example(name: str, cls: str) -> type[Component]:
    (found,) = load_target(f"{EXAMPLES / name}:{cls}")
    return found


class GaussianPeak(Function):
    """A normalised Gaussian of width SIGMA in 4-D: its integral over [0,1]^4 is known."""

    class_name = "test_gaussian_peak"
    input_dimensions = 4
    output_dimensions = 1

    def evaluate(self, points: np.ndarray) -> np.ndarray:
        r2 = np.sum((points - CENTRE) ** 2, axis=1)
        return (np.exp(-r2 / (2 * SIGMA**2)) / (2 * np.pi * SIGMA**2) ** 2)[:, None]


def peak_integral() -> float:
    s = SIGMA * math.sqrt(2)
    return math.prod(0.5 * (math.erf((1 - c) / s) + math.erf(c / s)) for c in CENTRE)


class Broken(Function):
    """Fails when called; needs a ``message``."""

    class_name = "test_broken"
    input_dimensions = 1
    output_dimensions = 1

    def __init__(self, message: str, scale: float = 1.0) -> None:
        self.message = message

    def evaluate(self, points: np.ndarray) -> np.ndarray:
        raise ZeroDivisionError(self.message)


class Disk(Warp):
    """Uniform points of the unit disk (no inverse)."""

    class_name = "test_disk"
    domain_dimensions = 2
    image_dimensions = 2

    def forward(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, phi = np.sqrt(points[:, 0]), 2 * np.pi * points[:, 1]
        return np.stack([r * np.cos(phi), r * np.sin(phi)], 1), np.full(len(points), 1 / np.pi)

    def pdf(self, points: np.ndarray) -> np.ndarray:
        return np.where(np.sum(points**2, axis=1) <= 1, 1 / np.pi, 0)


@pytest.fixture(scope="module")
def sdk() -> Iterator[Running]:
    classes = [
        example("lambertian.py", "Lambertian"),
        example("phong.py", "Phong"),
        example("halton.py", "Halton"),
        example("vegas.py", "Vegas"),
        example("ambient_occlusion.py", "AmbientOcclusion"),
        example("path.py", "PathTracer"),
        GaussianPeak,
        Broken,
        Disk,
    ]
    with serve(classes, "127.0.0.1:0") as running:
        yield running


@pytest.fixture(scope="module")
def channel(sdk: Running) -> Iterator[grpc.Channel]:
    with grpc.insecure_channel(
        sdk.address, options=[("grpc.max_receive_message_length", 256 << 20)]
    ) as opened:
        yield opened


def create(channel: grpc.Channel, class_name: str, **values: object) -> int:
    factory = component_pb2_grpc.FactoryStub(channel)
    request = component_pb2.CreateRequest(class_name=class_name, properties=properties(**values))
    return factory.Create(request, timeout=10).handle


def rpc_error(call: object) -> grpc.RpcError:
    with pytest.raises(grpc.RpcError) as caught:
        call()  # type: ignore[operator]
    return caught.value


# --- Component, Factory, Registry ---------------------------------------------


def test_lists_and_describes_its_classes(channel: grpc.Channel) -> None:
    registry = component_pb2_grpc.RegistryStub(channel)
    listed = registry.ListClasses(component_pb2.ListClassesRequest(), timeout=10).classes
    assert {"py_lambertian", "py_phong", "py_halton", "py_vegas"} <= {c.class_name for c in listed}
    describe = component_pb2_grpc.ComponentStub(channel).Describe
    info = describe(component_pb2.DescribeRequest(class_name="py_phong"), timeout=10)
    assert list(info.interfaces) == ["yarf.v1.SurfaceModel"]
    assert info.version == "1.0.0" and info.summary
    assert info.origin == "python phong"
    handle = create(channel, "py_vegas")
    by_handle = describe(component_pb2.DescribeRequest(handle=handle), timeout=10)
    assert by_handle.class_name == "py_vegas"
    assert list(by_handle.interfaces) == ["yarf.v1.Integrator"]
    unknown = rpc_error(lambda: describe(component_pb2.DescribeRequest(class_name="nope")))
    assert unknown.code() == grpc.StatusCode.NOT_FOUND
    for call in (
        lambda: registry.LoadPlugin(component_pb2.LoadPluginRequest(path="x.so")),
        lambda: registry.Register(component_pb2.RegisterRequest(address="127.0.0.1:1")),
        lambda: registry.Unregister(component_pb2.UnregisterRequest(address="127.0.0.1:1")),
    ):
        assert rpc_error(call).code() == grpc.StatusCode.UNIMPLEMENTED


def test_serves_only_the_interfaces_of_its_classes(channel: grpc.Channel) -> None:
    emitter = surface_pb2_grpc.EmitterStub(channel)
    request = surface_pb2.PdfDirectionRequest(handle=1)
    assert rpc_error(lambda: emitter.PdfDirection(request)).code() == grpc.StatusCode.UNIMPLEMENTED


def test_serves_on_a_unix_socket(tmp_path: Path) -> None:
    classes = [example("lambertian.py", "Lambertian")]
    with serve(classes, f"unix:{tmp_path}/sdk.sock") as running:
        assert running.address == f"unix:{tmp_path}/sdk.sock"
        with grpc.insecure_channel(running.address) as unix:
            describe = component_pb2_grpc.ComponentStub(unix).Describe
            info = describe(component_pb2.DescribeRequest(class_name="py_lambertian"), timeout=10)
            assert info.class_name == "py_lambertian"


def test_create_names_a_property_it_cannot_take(channel: grpc.Channel) -> None:
    unknown = rpc_error(lambda: create(channel, "py_lambertian", reflectence=rgb(0.2)))
    assert unknown.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "'reflectence'" in unknown.details() and "py_lambertian" in unknown.details()
    mistyped = rpc_error(lambda: create(channel, "py_phong", exponent="shiny"))
    assert mistyped.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "'exponent'" in mistyped.details() and "py_phong" in mistyped.details()
    missing = rpc_error(lambda: create(channel, "test_broken"))
    assert missing.code() == grpc.StatusCode.INVALID_ARGUMENT and "'message'" in missing.details()
    out_of_range = rpc_error(lambda: create(channel, "py_lambertian", reflectance=rgb(1.5)))
    assert out_of_range.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "'reflectance'" in out_of_range.details()
    # An int where a float is expected, a float where an rgb is: accepted.
    assert create(channel, "py_phong", exponent=12, diffuse_reflectance=0.3) > 0
    assert create(channel, "test_broken", message="m", scale=2) > 0


class Configured:
    """A constructor with one parameter of each kind a property can fill."""

    def __init__(
        self,
        colour: Rgb = (0.5, 0.5, 0.5),
        axis: Vec3 = (0.0, 0.0, 1.0),
        placement: Transform | None = None,
        name: str = "",
        mode: Literal["fast", "exact"] = "fast",
        count: int = 1,
        scale: float = 1.0,
        enabled: bool = True,
    ) -> None:
        pass


def test_properties_arrive_as_python_values_of_their_annotated_types() -> None:
    signature = Signature.of("configured", Configured.__init__)
    matrix = np.arange(16.0).reshape(4, 4)
    arguments = signature.arguments(
        properties(
            colour=0.25,
            axis=vec3(1, 2, 3),
            placement=transform(matrix),
            name=Reference("light"),
            mode="exact",
            count=3,
            scale=2,
            enabled=False,
        )
    )
    assert arguments["colour"] == (0.25, 0.25, 0.25)
    assert arguments["axis"] == (1.0, 2.0, 3.0)
    np.testing.assert_array_equal(arguments["placement"], matrix)
    assert arguments["name"] == "light" and arguments["mode"] == "exact"
    assert arguments["count"] == 3 and arguments["scale"] == 2.0
    assert isinstance(arguments["scale"], float) and arguments["enabled"] is False
    for key, value in (
        ("axis", rgb(1)),
        ("colour", vec3(1, 1, 1)),
        ("count", 2.5),
        ("enabled", 1),
        ("mode", "slow"),
        ("placement", 1.0),
    ):
        with pytest.raises(PropertyError, match=f"'{key}'.*configured|configured.*'{key}'"):
            signature.arguments(properties(**{key: value}))


def test_release_twice_is_not_found_and_so_are_unknown_instances(channel: grpc.Channel) -> None:
    factory = component_pb2_grpc.FactoryStub(channel)
    handle = create(channel, "py_lambertian")
    factory.Release(component_pb2.ReleaseRequest(handle=handle), timeout=10)
    again = rpc_error(lambda: factory.Release(component_pb2.ReleaseRequest(handle=handle)))
    assert again.code() == grpc.StatusCode.NOT_FOUND
    surface = surface_pb2_grpc.SurfaceModelStub(channel)
    gone = rpc_error(lambda: surface.Lobes(surface_pb2.LobesRequest(handle=handle)))
    assert gone.code() == grpc.StatusCode.NOT_FOUND
    sampler = create(channel, "py_halton")
    wrong = rpc_error(lambda: surface.Lobes(surface_pb2.LobesRequest(handle=sampler)))
    assert wrong.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "yarf.v1.SurfaceModel" in wrong.details()


def test_user_exceptions_are_internal_errors_naming_class_and_method(
    channel: grpc.Channel,
) -> None:
    handle = create(channel, "test_broken", message="on purpose")
    function = math_pb2_grpc.FunctionStub(channel)
    request = math_pb2.EvaluateRequest(
        handle=handle, points=numpy_to_array(np.zeros((4, 1), np.float32))
    )
    error = rpc_error(lambda: function.Evaluate(request, timeout=10))
    assert error.code() == grpc.StatusCode.INTERNAL
    assert error.details() == "Broken.evaluate: ZeroDivisionError: on purpose"


def test_a_warp_without_inverse_is_unimplemented(channel: grpc.Channel) -> None:
    warp = math_pb2_grpc.WarpStub(channel)
    handle = create(channel, "test_disk")
    uniform = np.random.default_rng(3).random((64, 2), dtype=np.float32)
    reply = warp.Forward(math_pb2.WarpRequest(handle=handle, points=numpy_to_array(uniform)))
    assert np.all(np.sum(array_to_numpy(reply.points) ** 2, axis=1) <= 1 + 1e-6)
    request = math_pb2.WarpRequest(handle=handle, points=numpy_to_array(uniform))
    assert rpc_error(lambda: warp.Inverse(request)).code() == grpc.StatusCode.UNIMPLEMENTED


# --- Surface models: sampling agrees with the pdf ------------------------------


def direction(cos_theta: float, phi: float) -> np.ndarray:
    sin_theta = math.sqrt(max(0.0, 1 - cos_theta * cos_theta))
    return np.array([sin_theta * math.cos(phi), sin_theta * math.sin(phi), cos_theta], np.float32)


class Surface:
    """A SurfaceModel instance over gRPC, for one wi at a time."""

    def __init__(self, channel: grpc.Channel, handle: int) -> None:
        self.stub = surface_pb2_grpc.SurfaceModelStub(channel)
        self.handle = handle

    def sample(
        self, wi: np.ndarray, uniform: np.ndarray, allowed: int = 0
    ) -> tuple[np.ndarray, ...]:
        n = len(uniform)
        reply = self.stub.Sample(
            surface_pb2.SampleSurfaceRequest(
                handle=self.handle,
                wi=numpy_to_array(np.tile(wi, (n, 1))),
                uv=numpy_to_array(np.zeros((n, 2), np.float32)),
                uniform=numpy_to_array(uniform.astype(np.float32)),
                allowed=allowed,
            ),
            timeout=30,
        )
        return tuple(array_to_numpy(a) for a in (reply.wo, reply.weight, reply.pdf, reply.flags))

    def query(self, wi: np.ndarray, wo: np.ndarray) -> surface_pb2.SurfaceQuery:
        n = len(wo)
        return surface_pb2.SurfaceQuery(
            handle=self.handle,
            wi=numpy_to_array(np.tile(wi, (n, 1)).astype(np.float32)),
            wo=numpy_to_array(wo.astype(np.float32)),
            uv=numpy_to_array(np.zeros((n, 2), np.float32)),
        )

    def evaluate(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return array_to_numpy(self.stub.Evaluate(self.query(wi, wo), timeout=30).value)

    def pdf(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return array_to_numpy(self.stub.Pdf(self.query(wi, wo), timeout=30).pdf)


def chi_square_survival(statistic: float, dof: int) -> float:
    """P(X ≥ statistic), X ~ χ²(dof), by Wilson and Hilferty's cube-root approximation."""
    variance = 2 / (9 * dof)
    z = ((statistic / dof) ** (1 / 3) - (1 - variance)) / math.sqrt(variance)
    return 0.5 * math.erfc(z / math.sqrt(2))


ROWS, COLS = 50, 100


def expected_counts(surface: Surface, wi: np.ndarray, count: int) -> np.ndarray:
    """count ∫ pdf over each (cos θ, φ) cell, by 5×5-point Gauss–Legendre quadrature."""
    nodes, weights = np.polynomial.legendre.leggauss(5)
    dz, dphi = 2 / ROWS, 2 * np.pi / COLS
    z_mid = -1 + (np.arange(ROWS) + 0.5) * dz
    phi_mid = -np.pi + (np.arange(COLS) + 0.5) * dphi
    z = z_mid[:, None, None, None] + 0.5 * dz * nodes[None, None, :, None]
    phi = phi_mid[None, :, None, None] + 0.5 * dphi * nodes[None, None, None, :]
    z, phi = np.broadcast_arrays(z, phi)
    sin = np.sqrt(np.maximum(0, 1 - z * z))
    wo = np.stack([sin * np.cos(phi), sin * np.sin(phi), z], axis=-1).reshape(-1, 3)
    pdf = surface.pdf(wi, wo).reshape(ROWS, COLS, 5, 5).astype(np.float64)
    cell = np.einsum("rcst,s,t->rc", pdf, weights, weights) * (0.5 * dz) * (0.5 * dphi)
    return (count * cell).reshape(-1)


def chi_square_p(directions: np.ndarray, expected: np.ndarray) -> float:
    """Pearson's test of directions binned in the cells; cells expecting < 5 are pooled."""
    row = np.minimum(((np.clip(directions[:, 2], -1, 1) + 1) / 2 * ROWS).astype(int), ROWS - 1)
    phi = np.arctan2(directions[:, 1], directions[:, 0])
    col = np.clip(((phi + np.pi) / (2 * np.pi) * COLS).astype(int), 0, COLS - 1)
    observed = np.bincount(row * COLS + col, minlength=ROWS * COLS).astype(np.float64)
    assert not np.any(observed[expected <= 0]), "samples where the pdf is 0"
    small = (expected > 0) & (expected < 5)
    large = expected >= 5
    statistic = np.sum((observed[large] - expected[large]) ** 2 / expected[large])
    dof = int(large.sum()) - 1
    if small.any():
        pooled = expected[small].sum()
        statistic += (observed[small].sum() - pooled) ** 2 / pooled
        dof += 1
    return chi_square_survival(float(statistic), dof)


SURFACES = [
    ("py_lambertian", {"reflectance": rgb(0.2, 0.5, 0.8)}),
    ("py_phong", {"diffuse_reflectance": rgb(0.3), "specular_reflectance": rgb(0.5)}),
    ("py_phong", {"diffuse_reflectance": rgb(0.1), "exponent": 5.0}),
]
INCIDENT = [direction(1.0, 0.0), direction(0.5, 1.0), direction(-0.8, -2.0)]


@pytest.mark.parametrize(("class_name", "values"), SURFACES)
def test_surface_samples_follow_the_pdf(
    channel: grpc.Channel, class_name: str, values: dict[str, object]
) -> None:
    surface = Surface(channel, create(channel, class_name, **values))
    count = 200_000
    for k, wi in enumerate(INCIDENT):
        uniform = np.random.default_rng(10 + k).random((count, 3))
        wo, weight, pdf, flags = surface.sample(wi, uniform)
        drawn = pdf > 0
        assert drawn.mean() > 0.9
        assert np.all(np.sign(wo[drawn, 2]) == np.sign(wi[2])), "reflection stays on wi's side"
        assert np.all(flags[drawn] & ScatterFlags.REFLECT)
        # Sample's pdf is Pdf at the sampled direction, its weight f·|cos|/pdf.
        np.testing.assert_allclose(surface.pdf(wi, wo[drawn]), pdf[drawn], rtol=1e-4)
        f = surface.evaluate(wi, wo[drawn])
        expected_weight = f * (np.abs(wo[drawn, 2]) / pdf[drawn])[:, None]
        np.testing.assert_allclose(weight[drawn], expected_weight, rtol=1e-3, atol=1e-6)
        p = chi_square_p(wo[drawn], expected_counts(surface, wi, count))
        assert p > 0.01, f"{class_name} {values}: χ² p = {p:.2g} at wi {wi}"


def test_lambertian_draws_nothing_where_the_lobe_is_excluded_or_wi_is_flat(
    channel: grpc.Channel,
) -> None:
    surface = Surface(channel, create(channel, "py_lambertian"))
    uniform = np.random.default_rng(5).random((100, 3))
    for wi, allowed in ((direction(0.6, 0.2), int(ScatterFlags.REFRACT)), (direction(0.0, 1), 0)):
        wo, weight, pdf, flags = surface.sample(wi, uniform, allowed)
        assert not wo.any() and not weight.any() and not pdf.any() and not flags.any()
    # A lobe is drawn only when all its flags are allowed.
    lobe = ScatterFlags.REFLECT | ScatterFlags.DIFFUSE
    _, weight, _, _ = surface.sample(direction(-0.3, 1), uniform, int(ScatterFlags.REFLECT))
    assert not weight.any()
    wo, weight, _, flags = surface.sample(direction(-0.3, 1), uniform, int(lobe))
    np.testing.assert_allclose(weight, 0.5)
    assert np.all(flags == lobe) and np.all(wo[:, 2] < 0)


def test_phong_white_furnace_reflects_at_most_everything(channel: grpc.Channel) -> None:
    handle = create(
        channel,
        "py_phong",
        diffuse_reflectance=rgb(0.5),
        specular_reflectance=rgb(0.5),
        exponent=30.0,
    )
    surface = Surface(channel, handle)
    count = 100_000
    for k, wi in enumerate(INCIDENT):
        _, weight, _, _ = surface.sample(wi, np.random.default_rng(20 + k).random((count, 3)))
        albedo = weight.astype(np.float64).mean(axis=0)
        error = weight.astype(np.float64).std(axis=0) / math.sqrt(count)
        assert np.all(albedo <= 1 + 4 * error), f"albedo {albedo} at wi {wi}"
        assert np.all(albedo > 0.5)


# --- Sampler --------------------------------------------------------------------


def generate(
    channel: grpc.Channel, handle: int, first: int, count: int, d: int, seed: int
) -> np.ndarray:
    sampler = math_pb2_grpc.SamplerStub(channel)
    request = math_pb2.GenerateSamplesRequest(
        handle=handle, first_index=first, count=count, dimensions=d, seed=seed
    )
    return array_to_numpy(sampler.Generate(request, timeout=30).points)


def test_halton_points_are_deterministic_stratified_and_beat_random_points(
    channel: grpc.Channel,
) -> None:
    handle = create(channel, "py_halton")
    points = generate(channel, handle, 0, 4096, 6, seed=7)
    assert points.shape == (4096, 6) and points.dtype == np.float32
    assert np.all((points >= 0) & (points < 1))
    np.testing.assert_array_equal(points, generate(channel, handle, 0, 4096, 6, seed=7))
    np.testing.assert_array_equal(points[1000:1100], generate(channel, handle, 1000, 100, 6, 7))
    assert not np.array_equal(points, generate(channel, handle, 0, 4096, 6, seed=8))
    # 3^5 consecutive points fill the 3^5 intervals of the base-3 dimension once each.
    cells = np.floor(points[:243, 1].astype(np.float64) * 243).astype(int)
    assert sorted(cells) == list(range(243))
    # ∫∫ x·y = 1/4: mean-sample estimates over 16 seeds at equal n.
    n = 1024
    halton = [
        np.mean(np.prod(generate(channel, handle, 0, n, 2, seed), axis=1)) for seed in range(16)
    ]
    rng = np.random.default_rng(0)
    independent = [np.mean(np.prod(rng.random((n, 2)), axis=1)) for _ in range(16)]
    halton_rms = math.sqrt(np.mean((np.array(halton) - 0.25) ** 2))
    independent_rms = math.sqrt(np.mean((np.array(independent) - 0.25) ** 2))
    assert halton_rms < independent_rms / 4, (halton_rms, independent_rms)


# --- Integrator -------------------------------------------------------------------


def integrate(
    channel: grpc.Channel,
    integrator: int,
    function: int,
    address: str,
    evaluations: int,
    seed: int,
    sampler: int = 0,
) -> math_pb2.IntegrateReply:
    request = math_pb2.IntegrateRequest(
        handle=integrator,
        function_handle=function,
        function_address=address,
        lower=[0.0] * 4,
        upper=[1.0] * 4,
        evaluations=evaluations,
        seed=seed,
        sampler_handle=sampler,
    )
    return math_pb2_grpc.IntegratorStub(channel).Integrate(request, timeout=60)


def test_py_vegas_reports_chi_square_and_q_of_its_iterations(
    sdk: Running, channel: grpc.Channel
) -> None:
    from scipy.stats import chi2

    (vegas_class,) = load_target(f"{EXAMPLES / 'vegas.py'}:Vegas")
    q_of = vars(sys.modules[vegas_class.__module__])["chi_square_q"]
    for dof in (1, 2, 5, 8, 15):
        for value in (0.2, 1.0, 4.0, 12.0, 40.0):
            assert q_of(value, dof) == pytest.approx(chi2.sf(value, dof), rel=1e-10, abs=1e-300)
    peak = create(channel, "test_gaussian_peak")
    vegas = create(channel, "py_vegas", iterations=10)
    reply = integrate(channel, vegas, peak, sdk.address, 100_000, seed=5)
    # Eight iterations kept (two discarded): 7 degrees of freedom.
    ((chi2_per_dof,), (q,)) = reply.chi2_per_dof, reply.q
    assert 0 <= chi2_per_dof < 4 and 0 < q <= 1
    assert q == pytest.approx(chi2.sf(7 * chi2_per_dof, 7), rel=1e-9)


def test_vegas_finds_a_gaussian_peak_far_better_than_plain_monte_carlo(
    sdk: Running, channel: grpc.Channel
) -> None:
    truth = peak_integral()
    peak = create(channel, "test_gaussian_peak")
    vegas = create(channel, "py_vegas", iterations=10, bins=50, alpha=1.5)
    plain = create(channel, "py_vegas", iterations=1, alpha=0.0, discard=0)
    evaluations = 100_000
    # The integrand is called back through this process's own Function service.
    adaptive = integrate(channel, vegas, peak, sdk.address, evaluations, seed=3)
    assert adaptive.evaluations == evaluations
    (estimate,), (error,) = adaptive.estimate, adaptive.standard_error
    assert abs(estimate - truth) < 4 * error, (estimate, error, truth)
    uniform = integrate(channel, plain, peak, sdk.address, evaluations, seed=3)
    (plain_estimate,), (plain_error,) = uniform.estimate, uniform.standard_error
    assert abs(plain_estimate - truth) < 4 * plain_error
    assert error <= plain_error / 5, (error, plain_error)
    # Deterministic; the same points whether the integrand is here or at an address.
    local = integrate(channel, vegas, peak, "", evaluations, seed=3)
    assert list(local.estimate) == list(adaptive.estimate)
    assert list(local.standard_error) == list(adaptive.standard_error)
    # With the points of a sampler of this process.
    halton = create(channel, "py_halton")
    quasi = integrate(channel, vegas, peak, "", evaluations, seed=3, sampler=halton)
    assert abs(quasi.estimate[0] - truth) < 4 * quasi.standard_error[0] + 1e-3


# --- Transports ------------------------------------------------------------------


def test_transports_say_their_dimensions_and_need_a_server_to_call_back(
    channel: grpc.Channel,
) -> None:
    stub = transport_pb2_grpc.TransportStub(channel)
    for class_name, values, dimensions in (
        ("py_ambient_occlusion", {"distance": 0.5}, 8),
        ("py_path", {"max_depth": 5}, 6 + 6 * 4),
    ):
        handle = create(channel, class_name, **values)
        request = transport_pb2.TransportDimensionsRequest(handle=handle)
        assert stub.Dimensions(request, timeout=10).dimensions == dimensions
        # This process was given no yarfd: the job's scene cannot be reached.
        prepare = transport_pb2.PrepareRequest(handle=handle, scene_handle=1)
        error = rpc_error(lambda: stub.Prepare(prepare, timeout=10))  # noqa: B023
        assert error.code() == grpc.StatusCode.FAILED_PRECONDITION
        assert "--server" in error.details()


# --- The surface models against yarfd's C++ ones --------------------------------


@pytest.mark.parametrize(
    ("cpp", "python", "values"),
    [
        ("lambertian", "py_lambertian", {"reflectance": rgb(0.2, 0.5, 0.8)}),
        (
            "phong",
            "py_phong",
            {"diffuse_reflectance": rgb(0.3), "specular_reflectance": rgb(0.5), "exponent": 7.5},
        ),
    ],
)
def test_python_surface_models_answer_as_the_cpp_ones(
    client: Client, channel: grpc.Channel, cpp: str, python: str, values: dict[str, object]
) -> None:
    reference = Surface(client.channel, client.create(cpp, properties(**values)).handle)
    ported = Surface(channel, create(channel, python, **values))
    rng = np.random.default_rng(4)
    lobes = ScatterFlags.REFLECT | ScatterFlags.DIFFUSE
    for wi in [*INCIDENT, direction(0.0, 0.3)]:
        uniform = rng.random((4096, 3))
        for allowed in (0, int(lobes), int(ScatterFlags.REFLECT | ScatterFlags.GLOSSY), 2):
            expected = reference.sample(wi, uniform, allowed)
            for got, want in zip(ported.sample(wi, uniform, allowed), expected, strict=True):
                np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-5)
        wo = rng.normal(size=(4096, 3))
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        np.testing.assert_allclose(
            ported.evaluate(wi, wo), reference.evaluate(wi, wo), rtol=1e-5, atol=1e-7
        )
        np.testing.assert_allclose(ported.pdf(wi, wo), reference.pdf(wi, wo), rtol=1e-5, atol=1e-7)


# --- The command ----------------------------------------------------------------


def component_command() -> list[str]:
    script = Path(sys.executable).parent / "yarf-component"
    return [str(script)] if script.exists() else [sys.executable, "-m", "yarf_component.cli"]


def read_line(process: subprocess.Popen[str], timeout: float = 20) -> str:
    assert process.stdout is not None
    ready, _, _ = select.select([process.stdout], [], [], timeout)
    assert ready, "no output in time"
    return process.stdout.readline().strip()


class FakeRegistry(component_pb2_grpc.RegistryServicer):
    """Stands in for yarfd's Registry: records Register and Unregister."""

    def __init__(self) -> None:
        self.registered: list[tuple[str, int]] = []
        self.unregistered: list[str] = []
        self.renewed = threading.Event()

    def Register(
        self, request: component_pb2.RegisterRequest, context: grpc.ServicerContext
    ) -> component_pb2.RegisterReply:
        self.registered.append((request.address, request.lease_seconds))
        if len(self.registered) >= 2:
            self.renewed.set()
        return component_pb2.RegisterReply(lease_seconds=request.lease_seconds)

    def Unregister(
        self, request: component_pb2.UnregisterRequest, context: grpc.ServicerContext
    ) -> component_pb2.UnregisterReply:
        self.unregistered.append(request.address)
        return component_pb2.UnregisterReply()


def test_the_command_serves_a_file_registers_and_stops_on_sigterm() -> None:
    registry = FakeRegistry()
    fake = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
    component_pb2_grpc.add_RegistryServicer_to_server(registry, fake)
    registry_address = f"127.0.0.1:{fake.add_insecure_port('127.0.0.1:0')}"
    fake.start()
    command = [
        *component_command(),
        "serve",
        f"{EXAMPLES / 'lambertian.py'}:Lambertian",
        "--listen",
        "127.0.0.1:0",
        "--register",
        registry_address,
        "--lease",
        "3",
    ]
    environment = {**os.environ, "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=environment)
    try:
        line = read_line(process)
        prefix = "yarf-component listening on "
        assert line.startswith(prefix), line
        address = line.removeprefix(prefix)
        assert not address.endswith(":0")
        with grpc.insecure_channel(address) as served:
            describe = component_pb2_grpc.ComponentStub(served).Describe
            info = describe(component_pb2.DescribeRequest(class_name="py_lambertian"), timeout=10)
            assert info.class_name == "py_lambertian"
        # Registered at start, renewed every lease/3 seconds.
        assert registry.renewed.wait(10)
        assert registry.registered[0] == (address, 3)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == 0
        assert registry.unregistered == [address]
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        fake.stop(None)
