"""Ambient occlusion against view factors computed in closed form.

An orthographic camera looks straight down on a floor (z = 0, x > 0)
that meets a wall standing in the plane x = 0. A floor point at distance
d from the wall reads 1 − F, F the cosine-weighted share of its
hemisphere the wall fills (the view factor from a differential area):
exactly, by Lambert's contour formula, for the finite wall; for an
occlusion ray bounded by maxdistance r, the wall's part within r is a
half disc of radius √(r² − d²) and F = (atan(ρ/d) − dρ/r²)/π.

The wall runs along the film's y axis, so the pixels of one column share
their expectation: each column's mean is z-tested against its analytic
value with the variance the film reports, Šidák-corrected over columns.
A z-test assumes a near-normal mean, so columns expected to see almost
no occlusion are instead checked to read exactly 1, as they must.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
from conftest import small_scene

from yarf import Client, RenderResult, component, transform, vec3
from yarf.v1 import scene_pb2

SIZE = 32
SPP = 128
FAMILY_ALPHA = 1e-3
# The floor seen: x in [X0, X0 + VIEW], y in [-VIEW/2, VIEW/2].
X0, VIEW = 0.25, 2.0
# The wall: x = 0, |y| <= WALL_HALF_WIDTH, 0 <= z <= WALL_HEIGHT.
WALL_HALF_WIDTH, WALL_HEIGHT = 200.0, 200.0
# Sub-pixel points per axis over which a pixel's expectation is averaged.
SUBPIXELS = 8


def rectangle(
    scene: scene_pb2.Scene,
    x_axis: tuple,
    y_axis: tuple,
    normal: tuple,
    center: tuple,
    material: str = "grey",
) -> None:
    """The unit square [-1, 1]² spanned along x_axis, y_axis about center."""
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x_axis, y_axis, normal, center
    shape = scene.shapes.add(material=material)
    shape.rectangle.SetInParent()
    shape.to_world.CopyFrom(transform(m))


def floor_scene(wall: bool) -> scene_pb2.Scene:
    scene = small_scene(SIZE)
    del scene.shapes[:]
    camera = scene.camera
    camera.model = scene_pb2.Camera.ORTHOGRAPHIC
    camera.origin.CopyFrom(vec3(X0 + VIEW / 2, 0, 5))
    camera.target.CopyFrom(vec3(X0 + VIEW / 2, 0, 0))
    camera.up.CopyFrom(vec3(0, 1, 0))
    camera.view_size = VIEW
    # Each sample counts in its own pixel alone: pixels are independent.
    scene.film.filter.kind = scene_pb2.ReconstructionFilter.BOX
    scene.film.filter.radius = 0.5
    rectangle(scene, (50, 0, 0), (0, 50, 0), (0, 0, 1), (50, 0, 0))
    if wall:
        rectangle(
            scene,
            (0, WALL_HALF_WIDTH, 0),
            (0, 0, WALL_HEIGHT / 2),
            (1, 0, 0),
            (0, 0, WALL_HEIGHT / 2),
        )
    return scene


def render(
    client: Client, scene: scene_pb2.Scene, seed: int = 0, **ao: bool | float
) -> RenderResult:
    return client.render(
        scene,
        spp=SPP,
        seed=seed,
        transport=component("ambient_occlusion", **ao),
        sampler=component("independent"),
    )


def floor_points() -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of SUBPIXELS² points per pixel, each [SIZE, SIZE, SUBPIXELS²]."""
    pixel = VIEW / SIZE
    sub = (np.arange(SUBPIXELS) + 0.5) / SUBPIXELS
    across = (np.arange(SIZE)[:, None] + sub[None, :]).reshape(-1) * pixel
    x = X0 + across  # film columns run along +x
    y = VIEW / 2 - across  # film rows run down along -y
    xs = x.reshape(SIZE, SUBPIXELS)
    ys = y.reshape(SIZE, SUBPIXELS)
    gx = np.broadcast_to(xs[None, :, None, :], (SIZE, SIZE, SUBPIXELS, SUBPIXELS))
    gy = np.broadcast_to(ys[:, None, :, None], (SIZE, SIZE, SUBPIXELS, SUBPIXELS))
    return gx.reshape(SIZE, SIZE, -1), gy.reshape(SIZE, SIZE, -1)


def wall_view_factor(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """View factor from the upward floor element at (x, y, 0) to the wall
    rectangle: Lambert's formula, Σ over edges of the angle they subtend
    times the cosine of their plane's normal with the floor's, over 2π."""
    corners = np.array(
        [
            [0, -WALL_HALF_WIDTH, 0],
            [0, WALL_HALF_WIDTH, 0],
            [0, WALL_HALF_WIDTH, WALL_HEIGHT],
            [0, -WALL_HALF_WIDTH, WALL_HEIGHT],
        ]
    )
    p = np.stack([x, y, np.zeros_like(x)], axis=-1)
    total = np.zeros_like(x)
    for i in range(4):
        a, b = corners[i] - p, corners[(i + 1) % 4] - p
        cross = np.cross(a, b)
        cosine = (a * b).sum(-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
        total += np.arccos(np.clip(cosine, -1, 1)) * cross[..., 2] / np.linalg.norm(cross, axis=-1)
    return np.abs(total) / (2 * math.pi)


def half_disc_view_factor(d: np.ndarray, r: float) -> np.ndarray:
    """View factor from a floor element at distance d from the wall to
    the wall's points within r of it: a half disc of radius ρ = √(r² − d²)."""
    rho = np.sqrt(np.maximum(r * r - d * d, 0))
    return np.where(d < r, (np.arctan2(rho, d) - d * rho / (r * r)) / math.pi, 0.0)


def expected(open_fraction: np.ndarray) -> np.ndarray:
    """Per pixel, the mean of the sub-pixel values."""
    return open_fraction.mean(axis=-1)


def column_means(result: RenderResult) -> tuple[np.ndarray, np.ndarray]:
    """Each column's mean of the red channel and the variance of that mean."""
    pixels = result.pixels[..., 0].astype(np.float64)
    variance = result.variance[..., 0].astype(np.float64)
    return pixels.mean(axis=0), variance.sum(axis=0) / SIZE**2


def sidak_z(tests: int) -> float:
    alpha = 1.0 - (1.0 - FAMILY_ALPHA) ** (1.0 / tests)
    return NormalDist().inv_cdf(1.0 - alpha / 2.0)


def assert_columns_match(result: RenderResult, reference: np.ndarray, cosine: bool) -> np.ndarray:
    """z-tests each column's mean against the reference image's; returns the z-scores."""
    means, variance = column_means(result)
    target = reference.mean(axis=0)
    # The normal approximation needs a fair count of occluded samples;
    # columns with fewer are (with cosine sampling) exactly 1 or not tested.
    occluded_samples = (1 - target) * SIZE * SPP
    tested = occluded_samples >= 25 if cosine else np.full(SIZE, True)
    if cosine:
        clear = occluded_samples < 1e-9
        assert (np.abs(result.pixels[:, clear, 0] - 1) < 1e-6).all()
    z = (means[tested] - target[tested]) / np.sqrt(variance[tested])
    threshold = sidak_z(int(tested.sum()))
    assert tested.sum() >= 8
    assert np.abs(z).max() < threshold, (z, means[tested], target[tested])
    return z


def test_an_open_plane_reads_one(client: Client) -> None:
    scene = floor_scene(wall=False)
    cosine = render(client, scene, cossample=True).pixels
    # Every cosine-weighted direction is open and weighs cos/(π·pdf) = 1.
    np.testing.assert_allclose(cosine, 1.0, atol=1e-6)
    uniform = render(client, scene, cossample=False)
    # Uniform directions weigh 2 cos θ, cos θ uniform in [0, 1]: mean 1.
    mean = float(uniform.pixels[..., 0].astype(np.float64).mean())
    sigma = math.sqrt(float(uniform.variance[..., 0].astype(np.float64).sum())) / SIZE**2
    assert abs(mean - 1) < sidak_z(1) * sigma, (mean, sigma)
    # ...and each sample varies as 2U does: variance 1/3.
    per_sample = float(uniform.variance[..., 0].astype(np.float64).mean()) * SPP
    assert abs(per_sample - 1 / 3) < 0.02, per_sample


def test_a_floor_beside_a_wall_reads_one_minus_the_walls_view_factor(client: Client) -> None:
    x, y = floor_points()
    reference = expected(1 - wall_view_factor(x, y))
    # The wall is large beside the floor seen: nearly half the hemisphere.
    assert 0.5 < reference.min() and reference.max() < 0.51
    result = render(client, floor_scene(wall=True), cossample=True)
    assert_columns_match(result, reference, cosine=True)


def test_maxdistance_counts_the_wall_within_it_alone(client: Client) -> None:
    r = 1.0
    x, _ = floor_points()
    reference = expected(1 - half_disc_view_factor(x, r))
    result = render(client, floor_scene(wall=True), cossample=True, maxdistance=r)
    assert_columns_match(result, reference, cosine=True)
    # Beyond r the wall is out of reach: a whole band reads exactly 1.
    assert (reference[:, -8:] == 1).all()


def test_uniform_directions_estimate_what_cosine_ones_do(client: Client) -> None:
    scene = floor_scene(wall=True)
    x, _ = floor_points()
    reference = expected(1 - half_disc_view_factor(x, 1.5))
    cosine = render(client, scene, seed=1, cossample=True, maxdistance=1.5)
    uniform = render(client, scene, seed=2, cossample=False, maxdistance=1.5)
    assert_columns_match(uniform, reference, cosine=False)
    # The two estimators agree with each other, column by column.
    (a, va), (b, vb) = column_means(cosine), column_means(uniform)
    z = (a - b) / np.sqrt(va + vb)
    assert np.abs(z).max() < sidak_z(SIZE), z


def test_null_boundaries_are_passed_by_camera_and_occlusion_rays(client: Client) -> None:
    # Under a ceiling at z = 2, a null sheet at z = 1 over the floor, the
    # camera between them. Within maxdistance 1.5 the floor reaches
    # nothing; a ray stopped by the sheet would see the ceiling within it.
    scene = floor_scene(wall=False)
    scene.camera.origin.z = 1.5
    scene.materials.add(name="boundary", class_name="null")
    rectangle(scene, (50, 0, 0), (0, 50, 0), (0, 0, 1), (0, 0, 1), "boundary")
    rectangle(scene, (50, 0, 0), (0, -50, 0), (0, 0, -1), (0, 0, 2))
    open_floor = render(client, scene, cossample=True, maxdistance=1.5).pixels
    np.testing.assert_allclose(open_floor, 1.0, atol=1e-6)
    # Within 2.5 the ceiling, seen past the sheet, fills the cone cos θ >
    # 2/2.5, whose cosine-weighted share is 1 − 0.8²: the floor reads 0.64.
    covered = render(client, scene, cossample=True, maxdistance=2.5)
    mean = float(covered.pixels[..., 0].astype(np.float64).mean())
    sigma = math.sqrt(float(covered.variance[..., 0].astype(np.float64).sum())) / SIZE**2
    assert abs(mean - 0.64) < sidak_z(1) * sigma, (mean, sigma)
