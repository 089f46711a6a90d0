"""White furnace: a camera inside a closed, uniformly emitting diffuse sphere.

Every path sees the same radiance, so every pixel's expectation is known in
closed form: with reflectance a and emitted radiance Le, the k-th bounce adds
Le·a^k. Unbounded depth gives Le/(1−a); max_depth 3 (the emitter seen
directly plus two bounces) gives Le·(1 + a + a²).
"""

from __future__ import annotations

import numpy as np
import pytest

from yarf import Client, RenderResult, component, properties, rgb, vec3
from yarf.v1 import scene_pb2

# (reflectance a, emitted radiance Le)
FURNACES = [(0.5, 1.0), (0.8, 0.25)]
SPP = 64
SIZE = 32
# Bound on |image mean − expected|: SIGMAS standard deviations of the mean
# (from the server's per-pixel variance) plus a relative slack for float32.
SIGMAS = 4.0
RELATIVE_SLACK = 1e-3


def furnace(reflectance: float, radiance: float) -> scene_pb2.Scene:
    scene = scene_pb2.Scene()
    scene.camera.origin.CopyFrom(vec3(0, 0, 0))
    scene.camera.target.CopyFrom(vec3(0, 0, 1))
    scene.camera.up.CopyFrom(vec3(0, 1, 0))
    scene.camera.fov = 90.0
    scene.film.width = SIZE
    scene.film.height = SIZE
    scene.materials.add(
        name="wall", class_name="lambertian", properties=properties(reflectance=rgb(reflectance))
    )
    # The sphere's normal points outward; flipped, it faces the centre, so the
    # camera sees (and is lit by) the emitting, reflecting side.
    shell = scene.shapes.add(name="shell", material="wall", flip_normals=True)
    shell.sphere.center.CopyFrom(vec3(0, 0, 0))
    shell.sphere.radius = 1.0
    shell.emitter.CopyFrom(component("diffuse_area", radiance=rgb(radiance)))
    return scene


def assert_image_mean_is(result: RenderResult, expected: float) -> None:
    pixels = result.pixels.astype(np.float64)
    variance = result.variance.astype(np.float64)
    assert pixels.shape == (SIZE, SIZE, 3)
    assert np.isfinite(pixels).all() and np.isfinite(variance).all()
    assert (variance >= 0).all()
    count = SIZE * SIZE
    for channel in range(3):
        mean = pixels[..., channel].mean()
        # Pixels are independent estimates: the variance of their mean is
        # the sum of their variances over count².
        sigma = np.sqrt(variance[..., channel].sum()) / count
        bound = SIGMAS * sigma + RELATIVE_SLACK * expected
        assert abs(mean - expected) < bound, (
            f"channel {channel}: image mean {mean:.6f}, expected {expected:.6f} "
            f"(|difference| {abs(mean - expected):.2e} ≥ bound {bound:.2e}; "
            f"σ of the mean {sigma:.2e})"
        )


@pytest.mark.parametrize(("reflectance", "radiance"), FURNACES)
def test_unbounded_depth_furnace_equals_radiance_over_one_minus_albedo(
    client: Client, reflectance: float, radiance: float
) -> None:
    result = client.render(
        furnace(reflectance, radiance),
        spp=SPP,
        seed=11,
        transport=component("path", max_depth=-1),
        timeout=60,
    )
    assert_image_mean_is(result, radiance / (1.0 - reflectance))


@pytest.mark.parametrize(("reflectance", "radiance"), FURNACES)
def test_depth_three_furnace_sums_emission_and_two_bounces(
    client: Client, reflectance: float, radiance: float
) -> None:
    result = client.render(
        furnace(reflectance, radiance),
        spp=SPP,
        seed=12,
        transport=component("path", max_depth=3),
        timeout=60,
    )
    assert_image_mean_is(result, radiance * (1.0 + reflectance + reflectance**2))
