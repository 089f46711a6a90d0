"""Whitted and distribution ray tracing, point and spot lights, motion blur.

Each image is checked against what geometry and optics predict, computed
here by casting the same camera rays in numpy: shadows and mirror images
on exact pixels, the out-of-focus disc of the thin-lens formula, the smear
of a moving occluder, the falloff of point and spot lights. The
distribution ray tracer also meets the path tracer restricted to its paths.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import REPO
from imagestats import block_z_test

from yarf import Client, component, load_scene, properties, rgb, transform, vec3
from yarf.scene import property_value
from yarf.v1 import scene_pb2

SIZE = 32


def look_at_scene(
    origin: tuple, target: tuple, up: tuple, fov: float, size: int = SIZE
) -> scene_pb2.Scene:
    scene = scene_pb2.Scene()
    scene.camera.origin.CopyFrom(vec3(*origin))
    scene.camera.target.CopyFrom(vec3(*target))
    scene.camera.up.CopyFrom(vec3(*up))
    scene.camera.fov = fov
    scene.film.width = scene.film.height = size
    scene.materials.add(
        name="black", class_name="lambertian", properties=properties(reflectance=rgb(0))
    )
    return scene


def rectangle(
    scene: scene_pb2.Scene, material: str, matrix: np.ndarray, name: str = ""
) -> scene_pb2.SceneShape:
    shape = scene.shapes.add(name=name, material=material)
    shape.rectangle.SetInParent()
    shape.to_world.CopyFrom(transform(matrix))
    return shape


def placed(center: tuple, half_x: float, half_y: float, axes: str = "xy") -> np.ndarray:
    """A rectangle of half sizes (half_x, half_y) at center, in the plane of ``axes``."""
    m = np.eye(4)
    columns = {"xy": (0, 1, 2), "xz": (0, 2, 1)}[axes]
    m[:, :3] = 0
    m[columns[0], 0] = half_x
    m[columns[1], 1] = half_y
    # The normal: +z for "xy", -y for "xz" (facing a camera on the -y side).
    m[columns[2], 2] = 1 if axes == "xy" else -1
    m[:3, 3] = center
    m[3, 3] = 1
    return m


def camera_rays(scene: scene_pb2.Scene, offsets: list[tuple[float, float]]) -> np.ndarray:
    """Unit directions [len(offsets), H, W, 3] through pixel (i + ox, j + oy)."""
    cam = scene.camera
    origin = np.array([cam.origin.x, cam.origin.y, cam.origin.z])
    forward = np.array([cam.target.x, cam.target.y, cam.target.z]) - origin
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [cam.up.x, cam.up.y, cam.up.z])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    width, height = scene.film.width, scene.film.height
    tan_x = math.tan(math.radians(cam.fov) / 2)
    tan_y = tan_x * height / width
    out = []
    for ox, oy in offsets:
        fx = (np.arange(width) + ox) / width
        fy = (np.arange(height) + oy) / height
        x, y = np.meshgrid((2 * fx - 1) * tan_x, (1 - 2 * fy) * tan_y)
        d = x[..., None] * right + y[..., None] * up + forward
        out.append(d / np.linalg.norm(d, axis=-1, keepdims=True))
    return np.stack(out)


# Pixel centre and four points near its corners: a pixel whose five rays
# agree is not crossed by an edge.
PROBES = [(0.5, 0.5), (0.02, 0.02), (0.98, 0.02), (0.02, 0.98), (0.98, 0.98)]


def hit_plane(
    origin: np.ndarray, d: np.ndarray, axis: int, level: float
) -> tuple[np.ndarray, np.ndarray]:
    """Distance to the plane coordinate[axis] = level (inf if parallel or behind), and the point."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (level - origin[..., axis]) / d[..., axis]
    t = np.where(t > 1e-6, t, np.inf)
    return t, origin + d * np.where(np.isfinite(t), t, 0)[..., None]


# --- Whitted -----------------------------------------------------------------


def test_whitted_shadow_falls_where_geometry_puts_it(client: Client) -> None:
    # A floor lit by a point light, a black square between them.
    scene = look_at_scene((0, 0, 10), (0, 0, 0), (0, 1, 0), 60)
    scene.materials.add(
        name="floor", class_name="lambertian", properties=properties(reflectance=rgb(0.8))
    )
    rectangle(scene, "floor", placed((0, 0, 0), 5, 5))
    rectangle(scene, "black", placed((0, 0, 3), 1, 1))
    light = scene.lights.add(name="bulb")
    light.emitter.CopyFrom(component("point", intensity=rgb(50)))
    light_at = np.array([3.0, 0.0, 6.0])
    light.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 3], [0, 1, 0, 0], [0, 0, 1, 6], [0, 0, 0, 1.0]]))
    )
    image = client.render(scene, spp=16, transport=component("whitted")).pixels

    origin = np.array([0.0, 0, 10])
    d = camera_rays(scene, PROBES)
    t_occluder, on_occluder = hit_plane(origin, d, 2, 3.0)
    sees_occluder = np.all(np.abs(on_occluder[..., :2]) <= 1, axis=-1) & np.isfinite(t_occluder)
    _, on_floor = hit_plane(origin, d, 2, 0.0)
    floor = np.all(np.abs(on_floor[..., :2]) <= 5, axis=-1)
    # The shadow ray from the floor point to the light crosses z = 3 at:
    s = 3.0 / light_at[2]
    crossing = on_floor[..., :2] + s * (light_at[:2] - on_floor[..., :2])
    shadowed = np.all(np.abs(crossing) <= 1, axis=-1)
    to_light = light_at - on_floor
    dist2 = (to_light**2).sum(axis=-1)
    lit = 0.8 / math.pi * 50 * (to_light[..., 2] / np.sqrt(dist2)) / dist2
    expected = np.where(sees_occluder | shadowed | ~floor, 0.0, lit)

    dark = np.all(expected == 0, axis=0)
    bright = np.all(expected > 0, axis=0)
    assert dark.sum() > 30 and bright.sum() > 300
    assert (image[dark] == 0).all(), "light inside the shadow or on the black square"
    np.testing.assert_allclose(image[bright][:, 0], expected.mean(axis=0)[bright], rtol=0.02)
    # The shadow is where the projection puts it: left of the square's view.
    shadow_only = dark & ~np.any(sees_occluder, axis=0)
    assert shadow_only.sum() > 20


def test_whitted_mirror_shows_the_reflection_where_geometry_puts_it(client: Client) -> None:
    # A mirror floor and a red emitting square standing on the far side.
    scene = look_at_scene((0, -6, 6), (0, 0, 0), (0, 0, 1), 60)
    scene.materials.add(name="mirror", class_name="mirror")
    rectangle(scene, "mirror", placed((0, 0, 0), 5, 5))
    sign = rectangle(scene, "black", placed((0, 3, 1.5), 1.5, 1.0, "xz"), "sign")
    sign.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1, 0, 0)))
    image = client.render(scene, spp=16, transport=component("whitted", max_depth=3)).pixels

    origin = np.array([0.0, -6, 6])
    d = camera_rays(scene, PROBES)

    def hits_sign(o: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t, p = hit_plane(o, dirs, 1, 3.0)
        inside = (np.abs(p[..., 0]) <= 1.5) & (np.abs(p[..., 2] - 1.5) <= 1.0) & (dirs[..., 1] > 0)
        return np.where(inside, t, np.inf), inside

    t_sign, direct = hits_sign(origin, d)
    t_mirror, on_mirror = hit_plane(origin, d, 2, 0.0)
    mirror = (t_mirror < t_sign) & np.all(np.abs(on_mirror[..., :2]) <= 5, axis=-1)
    reflected_dir = d * np.array([1, 1, -1])
    _, reflected = hits_sign(on_mirror, reflected_dir)
    red = np.where(mirror, reflected, direct)

    full = np.all(red, axis=0)
    empty = np.all(~red, axis=0)
    via_mirror = full & np.all(mirror, axis=0)
    assert via_mirror.sum() > 10 and (full & ~np.all(mirror, axis=0)).sum() > 20
    np.testing.assert_allclose(image[full], np.tile([1.0, 0, 0], (full.sum(), 1)), atol=1e-5)
    assert (image[empty] == 0).all()


# --- Distribution ray tracing -----------------------------------------------


def blur_radius(image: np.ndarray) -> float:
    """Radius of the uniform disc with the image's second moment, in pixels."""
    weight = image.sum(axis=2)
    ys, xs = np.mgrid[: image.shape[0], : image.shape[1]] + 0.5
    total = weight.sum()
    cx, cy = (weight * xs).sum() / total, (weight * ys).sum() / total
    second = (weight * ((xs - cx) ** 2 + (ys - cy) ** 2)).sum() / total
    # A disc of radius a has E[r²] = a²/2; square pixels add 1/6.
    return math.sqrt(2 * (second - 1 / 6))


@pytest.mark.parametrize("depth", [2.5, 5.0])
def test_out_of_focus_point_spreads_into_the_thin_lens_disc(client: Client, depth: float) -> None:
    size, fov, lens, focus, radius = 64, 30.0, 0.5, 2.5, 0.1
    scene = look_at_scene((0, 0, depth), (0, 0, 0), (0, 1, 0), fov, size)
    scene.camera.model = scene_pb2.Camera.THIN_LENS
    scene.camera.lens_radius = lens
    scene.camera.focus_distance = focus
    ball = scene.shapes.add(name="ball", material="black")
    ball.sphere.radius = radius
    ball.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1)))
    image = client.render(scene, spp=256, transport=component("distribution")).pixels
    pixels_per_tan = size / 2 / math.tan(math.radians(fov) / 2)
    # A ray through lens point l (|l| ≤ R) and the ball's centre lands at
    # l·(1/F − 1/z) in tangent space: a disc of radius R·|1/F − 1/z|.
    disc = lens * abs(1 / focus - 1 / depth) * pixels_per_tan
    ball_image = radius / depth * pixels_per_tan
    expected = math.hypot(disc, ball_image)
    assert blur_radius(image) == pytest.approx(expected, rel=0.04)


def test_moving_occluder_smears_as_its_motion_predicts(client: Client) -> None:
    scene = look_at_scene((0, 0, 5), (0, 0, 0), (0, 1, 0), 40)
    scene.camera.shutter = 1.0
    backdrop = rectangle(scene, "black", placed((0, 0, -1), 6, 6), "backdrop")
    backdrop.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1)))
    mover = rectangle(scene, "black", placed((-1, 0, 0), 0.5, 0.5), "mover")
    mover.to_world_end.CopyFrom(transform(placed((1, 0, 0), 0.5, 0.5)))
    image = client.render(scene, spp=64, transport=component("distribution")).pixels[..., 0]

    # Where the ray through a pixel crosses z = 0, the square covers it for
    # the part of the shutter interval its x range [-1.5+2t, -0.5+2t] holds x.
    d = camera_rays(scene, [(0.5, 0.5)])[0]
    _, p = hit_plane(np.array([0.0, 0, 5]), d, 2, 0.0)
    x, y = p[..., 0], p[..., 1]
    covered = np.clip(np.minimum(1, (x + 1.5) / 2) - np.maximum(0, (x + 0.5) / 2), 0, 1)
    expected = np.where(np.abs(y) <= 0.5, 1 - covered, 1.0)
    pixel = (x[0, 1] - x[0, 0]) * 1.5
    inner = np.abs(np.abs(y) - 0.5) > pixel
    for kink in (-1.5, -0.5, 0.5, 1.5):
        inner &= np.abs(x - kink) > pixel
    smeared = inner & (expected > 0.05) & (expected < 0.95)
    assert smeared.sum() > 50
    np.testing.assert_allclose(image[inner], expected[inner], atol=0.04)
    # With the shutter shut to an instant, the square sits at to_world.
    scene.camera.shutter = 0.0
    still = client.render(scene, spp=16, transport=component("distribution")).pixels[..., 0]
    at_start = (np.abs(x + 1) < 0.5 - pixel) & (np.abs(y) < 0.5 - pixel)
    assert (still[at_start] == 0).all() and at_start.sum() > 10


def test_distribution_ray_tracer_meets_the_path_tracer_restricted_to_its_paths(
    client: Client,
) -> None:
    # Lambertian walls, a purely glossy box, a glass sphere: every model is
    # all-diffuse or all-non-diffuse.
    scene = load_scene(REPO / "scenes" / "cornell-box" / "glossy.json")
    scene.film.width = scene.film.height = 48
    for m in scene.materials:
        if m.class_name != "phong":
            continue
        kd = m.properties.values["diffuse_reflectance"].rgb_value
        if m.name == "box":
            m.properties.values["diffuse_reflectance"].CopyFrom(property_value(rgb(0)))
            m.properties.values["specular_reflectance"].CopyFrom(property_value(rgb(0.8)))
        else:
            m.class_name = "lambertian"
            reflectance = properties(reflectance=rgb(kd.r, kd.g, kd.b))
            m.properties.CopyFrom(reflectance)
    independent = scene_pb2.ComponentSpec(class_name="independent")
    drt = client.render(
        scene,
        spp=256,
        seed=1,
        sampler=independent,
        transport=component("distribution", max_depth=6),
    )
    pt = client.render(
        scene,
        spp=256,
        seed=2,
        sampler=independent,
        transport=component("path", max_depth=6, diffuse_indirect=False),
    )
    full = client.render(
        scene, spp=64, seed=3, sampler=independent, transport=component("path", max_depth=6)
    )
    test = block_z_test(
        drt.pixels, drt.variance, pt.pixels, pt.variance, block=8, family_alpha=1e-3
    )
    assert not test.failing.size, test.report()
    # Diffuse interreflection is what the restriction leaves out.
    assert full.pixels.mean() > 1.1 * pt.pixels.mean()


# --- Point and spot lights ---------------------------------------------------


def test_point_and_spot_lights_light_a_floor_as_the_inverse_square_law_says(client: Client) -> None:
    scene = look_at_scene((0, 0, 10), (0, 0, 0), (0, 1, 0), 60)
    scene.materials.add(
        name="floor", class_name="lambertian", properties=properties(reflectance=rgb(0.5))
    )
    rectangle(scene, "floor", placed((0, 0, 0), 8, 8))
    spot = scene.lights.add(name="spot")
    # Shining straight down from (0, 0, 4): +z of the light is -z of the world.
    spot.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 4], [0, 0, 0, 1.0]]))
    )
    spot.emitter.CopyFrom(component("spot", intensity=rgb(20), cutoff_angle=30.0, beam_width=20.0))
    point = scene.lights.add(name="point")
    point.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 4], [0, 1, 0, 3], [0, 0, 1, 2], [0, 0, 0, 1.0]]))
    )
    point.emitter.CopyFrom(component("point", intensity=rgb(5)))

    # Pixel averages from a 4×4 grid of rays in each pixel.
    grid = [((a + 0.5) / 4, (b + 0.5) / 4) for a in range(4) for b in range(4)]
    d = camera_rays(scene, grid)
    _, p = hit_plane(np.array([0.0, 0, 10]), d, 2, 0.0)

    def irradiance(light: np.ndarray, intensity: np.ndarray) -> np.ndarray:
        v = light - p
        dist2 = (v**2).sum(axis=-1)
        return intensity * (v[..., 2] / np.sqrt(dist2)) / dist2

    angle = np.degrees(np.arctan2(np.hypot(p[..., 0], p[..., 1]), 4.0))
    falloff = np.clip((30 - angle) / 10, 0, 1)
    expected = (
        0.5
        / math.pi
        * (irradiance(np.array([0, 0, 4.0]), 20 * falloff) + irradiance(np.array([4, 3, 2.0]), 5))
    )
    # Pixels the spot's cone edges (20° and 30°) do not cross.
    clear = ~np.any(np.diff(np.sign(angle - 20), axis=0) != 0, axis=0)
    clear &= ~np.any(np.diff(np.sign(angle - 30), axis=0) != 0, axis=0)
    assert clear.sum() > 800 and (np.all(falloff == 0, axis=0) & clear).sum() > 100
    truth = expected.mean(axis=0)[clear]
    whitted = client.render(scene, spp=64, transport=component("whitted", max_depth=2)).pixels
    np.testing.assert_allclose(whitted[clear][:, 0], truth, rtol=0.02)
    # The others choose one light per sample: compare within their noise.
    for transport in ("distribution", "path"):
        result = client.render(scene, spp=64, transport=component(transport, max_depth=2))
        error = result.pixels[clear][:, 0] - truth
        sigma = np.sqrt(result.variance[clear][:, 0])
        assert (np.abs(error) < 5 * sigma + 0.01 * truth).all(), transport


def test_point_and_spot_lights_agree_across_unbiased_methods(client: Client) -> None:
    # The Cornell box lit by a spot light and a point light instead of its lamp.
    scene = load_scene(REPO / "scenes" / "cornell-box" / "scene.json")
    scene.film.width = scene.film.height = 48
    for shape in scene.shapes:
        shape.ClearField("emitter")
    spot = scene.lights.add(name="spot")
    spot.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 278], [0, 0, -1, 500], [0, 1, 0, 280], [0, 0, 0, 1.0]]))
    )
    spot.emitter.CopyFrom(component("spot", intensity=rgb(4e4), cutoff_angle=50.0))
    point = scene.lights.add(name="point")
    point.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 120], [0, 1, 0, 400], [0, 0, 1, 200], [0, 0, 0, 1.0]]))
    )
    point.emitter.CopyFrom(component("point", intensity=rgb(1e4)))
    independent = scene_pb2.ComponentSpec(class_name="independent")
    results = {
        name: client.render(
            scene, spp=spp, seed=seed, sampler=independent, transport=component(name, max_depth=5)
        )
        # The light tracer reaches the box's corners through rare, large
        # contributions (light bounced off the walls into a shadow): enough
        # samples that its variance estimate holds them.
        for name, spp, seed in (("path", 256, 1), ("light", 256, 2), ("bdpt", 64, 3))
    }
    reference = results["path"]
    assert reference.pixels.mean() > 0.01
    for name in ("light", "bdpt"):
        test = block_z_test(
            results[name].pixels,
            results[name].variance,
            reference.pixels,
            reference.variance,
            block=8,
            family_alpha=1e-3,
        )
        assert not test.failing.size, f"{name}:\n" + test.report()


# --- Lights from infinitely far -----------------------------------------------


@pytest.mark.parametrize("transport", ["path", "bdpt", "distribution"])
def test_constant_environment_lights_a_grey_sphere_to_its_albedo(
    client: Client, transport: str
) -> None:
    # The white furnace: a convex Lambertian ball of albedo 0.5 under unit
    # radiance from everywhere reflects 0.5; the background is 1.
    scene = look_at_scene((0, 0, 4), (0, 0, 0), (0, 1, 0), 40)
    scene.materials.add(
        name="grey", class_name="lambertian", properties=properties(reflectance=rgb(0.5))
    )
    ball = scene.shapes.add(name="ball", material="grey")
    ball.sphere.radius = 1.0
    sky = scene.lights.add(name="sky", kind=scene_pb2.Light.ENVIRONMENT)
    sky.emitter.CopyFrom(component("constant", radiance=rgb(1)))
    result = client.render(scene, spp=64, transport=component(transport, max_depth=3))
    d = camera_rays(scene, PROBES)
    # The ball covers a pixel when all five rays pass within its radius.
    origin = np.array([0.0, 0, 4])
    along = -(d @ origin)
    miss = np.linalg.norm(origin + d * along[..., None], axis=-1)
    on_ball, off_ball = np.all(miss < 1, axis=0), np.all(miss > 1, axis=0)
    assert on_ball.sum() > 100 and off_ball.sum() > 100
    pixels, sigma = result.pixels, np.sqrt(result.variance)
    for region, value in ((off_ball, 1.0), (on_ball, 0.5)):
        assert abs(pixels[region].mean() - value) < 0.01 * value
        assert (np.abs(pixels[region] - value) <= 6 * sigma[region] + 0.01 * value).all()


def test_directional_light_lights_a_floor_by_its_cosine_and_casts_a_parallel_shadow(
    client: Client,
) -> None:
    scene = look_at_scene((0, 0, 10), (0, 0, 0), (0, 1, 0), 60)
    scene.materials.add(
        name="floor", class_name="lambertian", properties=properties(reflectance=rgb(0.6))
    )
    rectangle(scene, "floor", placed((0, 0, 0), 8, 8))
    rectangle(scene, "black", placed((0, 0, 2), 1, 1))
    sun = scene.lights.add(name="sun", kind=scene_pb2.Light.DIRECTIONAL)
    sun.emitter.CopyFrom(component("directional", irradiance=rgb(3)))
    # Light travelling along (sin 30°, 0, −cos 30°): +z of a rotation about y.
    t = math.radians(30)
    rotation = np.array(
        [
            [math.cos(t), 0, math.sin(t), 0],
            [0, 1, 0, 0],
            [-math.sin(t), 0, -math.cos(t), 0],
            [0, 0, 0, 1],
        ]
    )
    sun.to_world.CopyFrom(transform(rotation))
    image = client.render(scene, spp=16, transport=component("whitted", max_depth=2)).pixels[..., 0]

    d = camera_rays(scene, PROBES)
    origin = np.array([0.0, 0, 10])
    _, on_floor = hit_plane(origin, d, 2, 0.0)
    _, on_square = hit_plane(origin, d, 2, 2.0)
    sees_square = np.all(np.abs(on_square[..., :2]) <= 1, axis=-1)
    # Back along the light from the floor point to z = 2: x shifts by 2·tan 30°.
    shadowed = (np.abs(on_floor[..., 0] - 2 * math.tan(t)) <= 1) & (np.abs(on_floor[..., 1]) <= 1)
    lit = ~(sees_square | shadowed)
    dark, bright = np.all(~lit, axis=0), np.all(lit, axis=0)
    assert dark.sum() > 40 and bright.sum() > 400
    assert (image[dark] == 0).all()
    np.testing.assert_allclose(image[bright], 0.6 / math.pi * 3 * math.cos(t), rtol=0.005)
