"""In-process components served over gRPC: Factory.Create, then the
interface's own service on the same endpoint, with dense batch arrays."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import grpc
import numpy as np
import pytest

from yarf import Client, properties, rgb
from yarf.client import array_to_numpy, numpy_to_array
from yarf.integrate import serve_function
from yarf.v1 import math_pb2, math_pb2_grpc, surface_pb2, surface_pb2_grpc

MakeInstance = Callable[..., int]


@pytest.fixture
def instance(client: Client) -> Iterator[MakeInstance]:
    """Makes instances for one test and releases them after it."""
    handles: list[int] = []

    def make(class_name: str, **values: object) -> int:
        handle = client.create(class_name, properties(**values)).handle
        handles.append(handle)
        return handle

    yield make
    for handle in handles:
        client.release(handle)


def upper_hemisphere(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def test_sobol_points_over_grpc_are_deterministic_and_stratified(
    client: Client, instance: MakeInstance
) -> None:
    sampler = math_pb2_grpc.SamplerStub(client.channel)
    handle = instance("sobol")
    request = math_pb2.GenerateSamplesRequest(
        handle=handle, first_index=0, count=256, dimensions=4, seed=3
    )
    points = array_to_numpy(sampler.Generate(request).points)
    again = array_to_numpy(sampler.Generate(request).points)
    assert points.shape == (256, 4)
    assert points.tobytes() == again.tobytes()
    assert ((points >= 0) & (points < 1)).all()
    for pair in (0, 2):  # one point in each cell of a 16 × 16 grid, per pair
        cells = (points[:, pair] * 16).astype(int) * 16 + (points[:, pair + 1] * 16).astype(int)
        assert np.unique(cells).size == 256


def test_lambertian_over_grpc_is_reflectance_over_pi(
    client: Client, instance: MakeInstance
) -> None:
    model = surface_pb2_grpc.SurfaceModelStub(client.channel)
    handle = instance("lambertian", reflectance=rgb(0.6, 0.3, 0.1))
    n = 4096
    wi, wo = upper_hemisphere(n, 1), upper_hemisphere(n, 2)
    uv = np.zeros((n, 2), np.float32)
    query = surface_pb2.SurfaceQuery(
        handle=handle, wi=numpy_to_array(wi), wo=numpy_to_array(wo), uv=numpy_to_array(uv)
    )
    value = array_to_numpy(model.Evaluate(query).value)
    np.testing.assert_allclose(value, np.tile([0.6, 0.3, 0.1], (n, 1)) / np.pi, rtol=1e-5)
    pdf = array_to_numpy(model.Pdf(query).pdf)
    np.testing.assert_allclose(pdf, wo[:, 2] / np.pi, rtol=1e-4)

    uniform = np.random.default_rng(3).random((n, 3), dtype=np.float32)
    sample = model.Sample(
        surface_pb2.SampleSurfaceRequest(
            handle=handle,
            wi=numpy_to_array(wi),
            uv=numpy_to_array(uv),
            uniform=numpy_to_array(uniform),
        )
    )
    weight = array_to_numpy(sample.weight)
    # Cosine-weighted sampling of a Lambertian: every weight is the albedo.
    np.testing.assert_allclose(weight, np.tile([0.6, 0.3, 0.1], (n, 1)), rtol=1e-4)
    diffuse_reflection = surface_pb2.SCATTER_REFLECT | surface_pb2.SCATTER_DIFFUSE
    assert (array_to_numpy(sample.flags) == diffuse_reflection).all()


def test_diffuse_area_emits_from_its_front_only_over_grpc(
    client: Client, instance: MakeInstance
) -> None:
    emitter = surface_pb2_grpc.EmitterStub(client.channel)
    handle = instance("diffuse_area", radiance=rgb(2.0, 3.0, 4.0))
    w = np.array([[0, 0, 1], [0.6, 0, 0.8], [0, 0, -1]], np.float32)
    reply = emitter.Radiance(
        surface_pb2.RadianceRequest(
            handle=handle, w=numpy_to_array(w), uv=numpy_to_array(np.zeros((3, 2), np.float32))
        )
    )
    radiance = array_to_numpy(reply.radiance)
    np.testing.assert_allclose(radiance, [[2, 3, 4], [2, 3, 4], [0, 0, 0]])


def test_spot_light_samples_directions_inside_its_cone_over_grpc(
    client: Client, instance: MakeInstance
) -> None:
    emitter = surface_pb2_grpc.EmitterStub(client.channel)
    handle = instance("spot", intensity=rgb(1.0), cutoff_angle=30.0)
    uniform = np.random.default_rng(5).random((1000, 2), dtype=np.float32)
    sampled = emitter.SampleDirection(
        surface_pb2.SampleDirectionRequest(handle=handle, uniform=numpy_to_array(uniform))
    )
    w, pdf = array_to_numpy(sampled.w), array_to_numpy(sampled.pdf)
    assert (w[:, 2] >= np.cos(np.radians(30)) - 1e-6).all()
    # Uniform in the cone: 1/(2π(1 − cos 30°)) everywhere, as PdfDirection says.
    np.testing.assert_allclose(pdf, 1 / (2 * np.pi * (1 - np.cos(np.radians(30)))), rtol=1e-5)
    check = emitter.PdfDirection(surface_pb2.PdfDirectionRequest(handle=handle, w=sampled.w))
    np.testing.assert_allclose(array_to_numpy(check.pdf), pdf, rtol=1e-5)


def test_bad_batches_wrong_interfaces_and_released_handles_are_refused(
    client: Client, instance: MakeInstance
) -> None:
    model = surface_pb2_grpc.SurfaceModelStub(client.channel)
    sampler = math_pb2_grpc.SamplerStub(client.channel)
    handle = instance("lambertian")
    wi = np.zeros((4, 3), np.float32)
    short_uv = np.zeros((3, 2), np.float32)
    with pytest.raises(grpc.RpcError) as bad_shape:
        model.Evaluate(
            surface_pb2.SurfaceQuery(
                handle=handle,
                wi=numpy_to_array(wi),
                wo=numpy_to_array(wi),
                uv=numpy_to_array(short_uv),
            )
        )
    assert bad_shape.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "rows" in bad_shape.value.details()

    with pytest.raises(grpc.RpcError) as wrong_interface:
        sampler.Generate(math_pb2.GenerateSamplesRequest(handle=handle, count=4, dimensions=2))
    assert wrong_interface.value.code() == grpc.StatusCode.FAILED_PRECONDITION
    assert "lambertian" in wrong_interface.value.details()

    released = client.create("sobol").handle
    client.release(released)
    with pytest.raises(grpc.RpcError) as gone:
        sampler.Generate(math_pb2.GenerateSamplesRequest(handle=released, count=4, dimensions=2))
    assert gone.value.code() == grpc.StatusCode.NOT_FOUND

    with pytest.raises(grpc.RpcError) as absurd:
        sampler.Generate(
            math_pb2.GenerateSamplesRequest(handle=instance("sobol"), count=1 << 30, dimensions=64)
        )
    assert absurd.value.code() == grpc.StatusCode.INVALID_ARGUMENT


def test_cosine_hemisphere_warp_over_grpc_has_density_cos_over_pi(
    client: Client, instance: MakeInstance
) -> None:
    warp = math_pb2_grpc.WarpStub(client.channel)
    handle = instance("cosine_hemisphere")
    signature = warp.Signature(math_pb2.WarpSignatureRequest(handle=handle))
    assert (signature.domain_dimensions, signature.image_dimensions) == (2, 3)
    uniform = np.random.default_rng(5).random((8192, 2), dtype=np.float32)
    reply = warp.Forward(math_pb2.WarpRequest(handle=handle, points=numpy_to_array(uniform)))
    directions, pdf = array_to_numpy(reply.points), array_to_numpy(reply.pdf)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1, atol=1e-5)
    np.testing.assert_allclose(pdf, directions[:, 2] / np.pi, rtol=1e-4, atol=1e-6)
    # Cosine-weighted: E[cos θ] = 2/3.
    assert abs(directions[:, 2].mean() - 2 / 3) < 0.01
    back = warp.Inverse(math_pb2.WarpRequest(handle=handle, points=reply.points))
    np.testing.assert_allclose(array_to_numpy(back.points), uniform, atol=1e-4)


def test_root_finders_over_grpc_find_the_root_of_a_python_function(
    client: Client, instance: MakeInstance
) -> None:
    finder = math_pb2_grpc.RootFinderStub(client.channel)

    def cubic(x: np.ndarray) -> np.ndarray:
        t = x[:, 0].astype(np.float64)
        return np.stack([t**3 - 2 * t - 5, 3 * t**2 - 2], axis=1)

    with serve_function(cubic, 1) as address:
        for name in ("bisection", "newton", "brent"):
            reply = finder.FindRoot(
                math_pb2.FindRootRequest(
                    handle=instance(name),
                    function_address=address,
                    lower=2,
                    upper=3,
                    tolerance=1e-6,
                    max_iterations=100,
                )
            )
            assert reply.root == pytest.approx(2.0945514815423265, abs=1e-5), name
        with pytest.raises(grpc.RpcError) as no_bracket:
            finder.FindRoot(
                math_pb2.FindRootRequest(
                    handle=instance("brent"),
                    function_address=address,
                    lower=3,
                    upper=4,
                    tolerance=1e-6,
                    max_iterations=100,
                )
            )
    assert no_bracket.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "bracket" in no_bracket.value.details()
