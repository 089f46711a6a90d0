"""Lights as Mitsuba 3 renders them: lights at infinity, environment maps,
directional lights, sphere lights sampled by solid angle.

Each scene is one Mitsuba XML file that yarf's importer and Mitsuba 3
(scalar_rgb, made in the test) both read; yarf's render must pass Mitsuba's
render-regression criterion against Mitsuba's (imagestats.pixel_z_test).
Every transport must also see the environment: a white furnace (a diffuse
sphere under a uniform sky reads its albedo), and agreement with the path
tracer under an environment map (block z-test).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from imagestats import block_z_test
from surface_scenes import AREA_LIGHT, SIZE, write_scene
from test_surfaces import INDEPENDENT, assert_matches_mitsuba

from yarf import Client, RenderResult, component, load_scene, properties, rgb, transform
from yarf.assets import upload_scene_assets
from yarf.v1 import scene_pb2

GREY = '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf>'
SPHERE = f'<shape type="sphere"><float name="radius" value="0.9"/>{GREY}</shape>'
ENVMAP = (
    '<emitter type="envmap"><string name="filename" value="sky.pfm"/>'
    '<float name="scale" value="1.5"/>'
    '<transform name="to_world"><rotate y="1" angle="60"/></transform></emitter>'
)


def write_pfm(path: Path, rgb: np.ndarray) -> None:
    """An RGB float image as PFM (rows stored bottom to top)."""
    height, width, _ = rgb.shape
    with path.open("wb") as out:
        out.write(f"PF\n{width} {height}\n-1.0\n".encode())
        out.write(np.ascontiguousarray(rgb[::-1], dtype="<f4").tobytes())


def sky(path: Path) -> None:
    """A 64×32 latitude-longitude sky: blue above, brown below, and a small
    bright sun (a few texels), so that sampling by the map matters."""
    rows, columns = np.mgrid[0:32, 0:64]
    elevation = 1 - (rows + 0.5) / 16  # 1 at the zenith, -1 at the nadir
    image = np.where(
        (elevation > 0)[..., None],
        np.stack([0.3 + 0.2 * elevation, 0.5 + 0.2 * elevation, 0.9 + 0.1 * elevation], -1),
        np.array([0.25, 0.18, 0.1]),
    )
    sun = (abs(rows - 9) <= 1) & (abs(columns - 20) <= 1)
    image[sun] = [200.0, 180.0, 150.0]
    write_pfm(path, image.astype(np.float32))


def projected_image(path: Path) -> None:
    """An 8×8 image for the projector: red grows to the right, green down, a
    blue border on the left column and a white texel near the top right, so
    that a flipped or turned projection shows."""
    rows, columns = np.mgrid[0:8, 0:8]
    image = np.stack([(columns + 1) / 8, (rows + 1) / 8, np.full((8, 8), 0.15)], -1)
    image[:, 0] = [0.1, 0.2, 1.0]
    image[1, 6] = [1.0, 1.0, 1.0]
    write_pfm(path, image.astype(np.float32))


# Mitsuba's projector: the image's irradiance at unit distance (times π),
# seen from above, its up along −z; over the sphere and the floor.
PROJECTOR = (
    '<emitter type="projector"><transform name="to_world">'
    '<lookat origin="0.4, 3, 0.8" target="0, -0.5, 0" up="0, 0, -1"/></transform>'
    '<texture type="bitmap" name="irradiance"><string name="filename" value="projected.pfm"/>'
    '</texture><float name="scale" value="6"/><float name="fov" value="50"/></emitter>'
)


LIGHTS = {
    "constant sky": (
        SPHERE,
        '<emitter type="constant"><rgb name="radiance" value="0.8, 0.9, 1"/></emitter>',
    ),
    "directional light": (
        SPHERE,
        '<emitter type="directional"><vector name="direction" x="-0.3" y="-1" z="-0.5"/>'
        '<rgb name="irradiance" value="3, 2.8, 2.5"/></emitter>',
    ),
    # A glossy sphere lit by a small sphere light: light samples by solid
    # angle and BSDF samples weighted against them.
    "sphere light on a glossy sphere": (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="roughconductor">'
        '<string name="material" value="Au"/><float name="alpha" value="0.15"/></bsdf></shape>',
        '<shape type="sphere"><point name="center" x="1.2" y="1.8" z="1.5"/>'
        '<float name="radius" value="0.25"/>'
        '<emitter type="area"><rgb name="radiance" value="30, 30, 30"/></emitter></shape>',
    ),
    # Mitsuba's spot light: full intensity within beam_width, falling
    # linearly in angle to cutoff_angle; the edge crosses the floor.
    "spot light at its falloff edge": (
        SPHERE,
        '<emitter type="spot"><transform name="to_world">'
        '<lookat origin="0.5, 3, 0.5" target="0, 0, 0" up="0, 0, 1"/></transform>'
        '<rgb name="intensity" value="20, 18, 15"/><float name="cutoff_angle" value="25"/>'
        '<float name="beam_width" value="12"/></emitter>',
    ),
    "envmap-lit diffuse sphere": (SPHERE, ENVMAP),
    "envmap-lit rough conductor": (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="roughconductor">'
        '<string name="material" value="Cu"/><float name="alpha" value="0.2"/></bsdf></shape>',
        ENVMAP,
    ),
    "envmap-lit rough dielectric": (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="roughdielectric">'
        '<float name="alpha" value="0.2"/><float name="int_ior" value="1.5"/></bsdf></shape>',
        ENVMAP,
    ),
    "projector on a floor": (SPHERE, PROJECTOR),
}


@pytest.mark.parametrize("name", list(LIGHTS))
def test_light_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    shape, lights = LIGHTS[name]
    sky(tmp_path / "sky.pfm")
    projected_image(tmp_path / "projected.pfm")
    path = write_scene(tmp_path, shape, lights=lights, max_depth=6)
    scene = load_scene(path)
    upload_scene_assets(client, scene, tmp_path)
    assert_matches_mitsuba(client, scene, path, name)


def covered_pixels(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the pixels the scene's camera (scene_xml's: from (0, 1.5, 4)
    toward the origin, 40° across) sees wholly on a sphere of ``radius`` at the
    origin, and wholly beside it."""
    eye = np.array([0.0, 1.5, 4.0])
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    half = math.tan(math.radians(20))
    corners = np.linspace(-half, half, 4 * SIZE + 1)
    x, y = np.meshgrid(corners, -corners)
    d = forward + x[..., None] * right + y[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    # |eye + t d|² = r² has a root where (d·eye)² − |eye|² + r² ≥ 0.
    hits = (d @ eye) ** 2 - eye @ eye + radius**2 >= 0
    # Each pixel's 5×5 corners and inner points, and a pixel's margin around
    # them (the reconstruction filter reaches a little beyond).
    inside = np.zeros((SIZE, SIZE), bool)
    outside = np.zeros((SIZE, SIZE), bool)
    for row in range(SIZE):
        for column in range(SIZE):
            near = hits[max(0, 4 * row - 4) : 4 * row + 9, max(0, 4 * column - 4) : 4 * column + 9]
            inside[row, column] = near.all()
            outside[row, column] = not near.any()
    return inside, outside


FURNACE_TRANSPORTS = {
    "path": component("path"),
    "light": component("light"),
    "bdpt": component("bdpt"),
    "distribution": component("distribution"),
    "irradiance_cache": component("irradiance_cache"),
    "photon_map": component("photon_map"),
    "sppm": component("sppm"),
}


@pytest.mark.parametrize("transport", list(FURNACE_TRANSPORTS))
def test_white_furnace_under_a_uniform_sky(client: Client, tmp_path: Path, transport: str) -> None:
    """A diffuse sphere of albedo 0.5 under a sky of radiance 1, nothing else:
    being convex it reads 0.5 wherever it is seen, the sky 1 around it."""
    sphere = (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="diffuse">'
        '<rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>'
    )
    sky_light = '<emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>'
    scene = load_scene(write_scene(tmp_path, sphere, lights=sky_light, floor="", max_depth=8))
    result = client.render(
        scene, spp=256, seed=5, transport=FURNACE_TRANSPORTS[transport], timeout=600
    )
    inside, outside = covered_pixels(0.9)
    assert inside.sum() > 100 and outside.sum() > 100
    for mask, expected, where in ((inside, 0.5, "on the sphere"), (outside, 1.0, "around it")):
        values = result.pixels[mask]
        # Density estimates blur a little; everything else is unbiased.
        error = np.abs(values.mean(axis=0) - expected).max()
        noise = 4 * math.sqrt(result.variance[mask].mean() / mask.sum()) + 1e-4
        tolerance = noise + (0.01 if transport in ("photon_map", "sppm") else 0)
        assert error < tolerance, (
            f"{transport} {where}: mean {values.mean(axis=0)} against {expected} "
            f"(tolerance {tolerance:.4f})"
        )


def render_envmap_scene(
    client: Client, scene: scene_pb2.Scene, name: str, seed: int, **values: object
) -> RenderResult:
    result = client.render(
        scene,
        spp=1024,
        seed=seed,
        transport=component(name, max_depth=5, **values),
        sampler=INDEPENDENT,
        timeout=600,
    )
    assert np.isfinite(result.pixels).all()
    return result


@pytest.fixture(scope="module")
def envmap_scene_and_path_reference(
    client: Client, tmp_path_factory: pytest.TempPathFactory
) -> tuple[scene_pb2.Scene, RenderResult]:
    """A diffuse sphere on a floor under the sky map, and the path tracer's
    image of it, which every other transport is compared with."""
    folder = tmp_path_factory.mktemp("envmap")
    sky(folder / "sky.pfm")
    scene = load_scene(write_scene(folder, SPHERE, lights=ENVMAP, max_depth=5))
    upload_scene_assets(client, scene, folder)
    return scene, render_envmap_scene(client, scene, "path", 1)


@pytest.mark.parametrize("transport", ["light", "bdpt", "photon_map", "sppm"])
def test_transports_agree_under_an_environment_map(
    client: Client,
    envmap_scene_and_path_reference: tuple[scene_pb2.Scene, RenderResult],
    transport: str,
) -> None:
    """A diffuse sphere on a floor under the sky map: paths from the camera and
    from the environment (its disk around the scene) estimate the same image."""
    scene, reference = envmap_scene_and_path_reference
    # The photon map blurs the sphere's contact shadow by the radius of its
    # estimates: enough photons shrink the blur below the noise.
    density = {"photons": 1_000_000} if transport == "photon_map" else {}
    other = render_envmap_scene(client, scene, transport, 2, **density)
    test = block_z_test(
        other.pixels,
        other.variance,
        reference.pixels,
        reference.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"{transport} vs path under an envmap:\n{test.report()}"


@pytest.mark.parametrize(
    "light", ["directional light", "sphere light on a glossy sphere", "constant sky"]
)
@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_light_paths_agree_with_the_path_tracer(
    client: Client, tmp_path: Path, transport: str, light: str
) -> None:
    """Light paths from a directional light (a disk of parallel rays), a sphere
    light and a uniform sky against camera paths, on the room's floor."""
    shape, lights = LIGHTS[light]
    scene = load_scene(write_scene(tmp_path, shape, lights=lights, max_depth=5))

    def render(name: str, spp: int, seed: int) -> RenderResult:
        return client.render(
            scene,
            spp=spp,
            seed=seed,
            transport=component(name, max_depth=5),
            sampler=INDEPENDENT,
            timeout=600,
        )

    reference, other = render("path", 1024, 1), render(transport, 1024, 2)
    test = block_z_test(
        other.pixels,
        other.variance,
        reference.pixels,
        reference.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"{transport} vs path, {light}:\n{test.report()}"


def test_sphere_lights_by_solid_angle_lower_the_variance(client: Client) -> None:
    """On the Veach MIS scene at equal spp: sampling the sphere lights by the
    solid angle they subtend, not by area, lowers the per-pixel variance of
    the path tracer, and both estimate the same image."""
    scene = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "veach-mis" / "scene.json")
    scene.film.width, scene.film.height = 128, 96
    by_cone = client.render(scene, spp=64, seed=1, sampler=INDEPENDENT, timeout=600)
    scene.sphere_sampling = scene.SPHERE_SAMPLING_AREA
    by_area = client.render(scene, spp=64, seed=2, sampler=INDEPENDENT, timeout=600)
    cone, area = by_cone.variance.mean(axis=-1), by_area.variance.mean(axis=-1)
    noisy = area > 0
    median = float(np.median(cone[noisy] / area[noisy]))
    mean = float(cone.mean() / area.mean())
    # Typically a sixth in the median pixel and three quarters overall: the
    # noisiest pixels are the sharp plates' reflections of the large
    # lights, which BSDF samples find.
    assert median < 0.5 and mean < 1, (
        f"variance by solid angle / by area: median {median:.3f}, mean {mean:.3f}"
    )
    test = block_z_test(
        by_cone.pixels,
        by_cone.variance,
        by_area.pixels,
        by_area.variance,
        block=8,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"solid angle vs area sampling:\n{test.report()}"


def many_lights(width: int = 64, height: int = 48) -> scene_pb2.Scene:
    """A floor under 100 small sphere lights of equal power on a grid that
    runs from near the camera into the distance."""
    scene = scene_pb2.Scene()
    scene.camera.origin.y, scene.camera.origin.z = 3.0, 9.0
    scene.camera.up.y = 1.0
    scene.camera.fov = 50
    scene.film.width, scene.film.height = width, height
    scene.materials.add(
        name="floor", class_name="lambertian", properties=properties(reflectance=rgb(0.6))
    )
    scene.materials.add(
        name="black", class_name="lambertian", properties=properties(reflectance=rgb(0))
    )
    floor = scene.shapes.add(name="floor", material="floor")
    floor.rectangle.SetInParent()
    floor.to_world.CopyFrom(
        transform(np.array([[10, 0, 0, 0], [0, 0, 1, 0], [0, -10, 0, 0], [0, 0, 0, 1.0]]))
    )
    for k in range(100):
        light = scene.shapes.add(name=f"light{k}", material="black")
        light.sphere.center.x, light.sphere.center.y = -4.5 + (k % 10), 0.6
        light.sphere.center.z = -4.5 + (k // 10)
        light.sphere.radius = 0.05
        light.emitter.CopyFrom(component("diffuse_area", radiance=rgb(40.0)))
    return scene


def test_a_light_bvh_finds_the_lights_near_each_point(client: Client) -> None:
    """Many lights of equal power: chosen by power they are chosen evenly;
    the BVH (pbrt-v4's) weighs each by its distance and orientation too,
    which lowers the variance many times over, and both estimate the same
    image."""
    scene = many_lights()
    results = {}
    for name, choice in (("power", scene.LIGHT_SAMPLER_POWER), ("bvh", scene.LIGHT_SAMPLER_BVH)):
        scene.light_sampler = choice
        results[name] = client.render(
            scene, spp=64, seed=7, sampler=INDEPENDENT, transport=component("path", max_depth=3)
        )
    power, bvh = results["power"], results["bvh"]
    # The median pixel: the pixels that see a light's edge are noisy from
    # their coverage alone, whichever light a sample chooses.
    ratio = float(np.median(bvh.variance) / np.median(power.variance))
    assert ratio < 0.4, f"median pixel variance with the BVH / by power: {ratio:.3f}"
    test = block_z_test(
        bvh.pixels, bvh.variance, power.pixels, power.variance, block=8, family_alpha=1e-3
    )
    assert not test.failing.size, f"bvh vs power:\n{test.report()}"


@pytest.mark.parametrize("scene_name", ["veach-mis", "envmap and area light"])
def test_the_light_bvh_estimates_the_same_image(
    client: Client, tmp_path: Path, scene_name: str
) -> None:
    """Sphere lights of four sizes and a far fill light (the MIS scene), and
    an environment map beside an area light (lights at infinity are chosen
    beside the BVH): the BVH and power sampling agree within noise."""
    if scene_name == "veach-mis":
        scene = load_scene(
            Path(__file__).resolve().parents[1] / "scenes" / "veach-mis" / "scene.json"
        )
        scene.film.width, scene.film.height = 64, 48
    else:
        sky(tmp_path / "sky.pfm")
        scene = load_scene(write_scene(tmp_path, SPHERE, lights=ENVMAP + AREA_LIGHT, max_depth=4))
        upload_scene_assets(client, scene, tmp_path)
    results = {}
    for name, choice in (("power", scene.LIGHT_SAMPLER_POWER), ("bvh", scene.LIGHT_SAMPLER_BVH)):
        scene.light_sampler = choice
        results[name] = client.render(scene, spp=256, seed=11, sampler=INDEPENDENT, timeout=600)
    test = block_z_test(
        results["bvh"].pixels,
        results["bvh"].variance,
        results["power"].pixels,
        results["power"].variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"bvh vs power on {scene_name}:\n{test.report()}"


def test_large_triangle_lights_by_solid_angle_lower_the_variance(client: Client) -> None:
    """The Cornell box's lamp seen from the tops of the walls subtends a
    wide angle: sampled by the solid angle of its triangles (pbrt-v4's
    spherical triangles) rather than by area, the path tracer's variance
    falls there, and both estimate the same image."""
    scene = load_scene(
        Path(__file__).resolve().parents[1] / "scenes" / "cornell-box" / "scene.json"
    )
    scene.film.width = scene.film.height = 48
    renders = {}
    for name, choice in (
        ("solid angle", scene.TRIANGLE_SAMPLING_SOLID_ANGLE),
        ("area", scene.TRIANGLE_SAMPLING_AREA),
    ):
        scene.triangle_sampling = choice
        renders[name] = client.render(
            scene, spp=128, seed=4, sampler=INDEPENDENT, transport=component("path", max_depth=2)
        )
    by_angle, by_area = renders["solid angle"], renders["area"]
    # The walls' upper parts, just below the lamp (rows 12 to 19 of 48):
    # typically 0.4 of the variance by area.
    band = slice(12, 20)
    ratio = float(by_angle.variance[band].mean() / by_area.variance[band].mean())
    assert ratio < 0.6, f"variance below the lamp, by solid angle / by area: {ratio:.3f}"
    test = block_z_test(
        by_angle.pixels,
        by_angle.variance,
        by_area.pixels,
        by_area.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"solid angle vs area sampling:\n{test.report()}"


@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_light_paths_agree_at_the_border_under_a_wide_filter(
    client: Client, tmp_path: Path, transport: str
) -> None:
    """Mitsuba's and pbrt's default filter is a Gaussian 1.5 pixels wide: part
    of a border pixel's filter lies off the film, and splats there are
    divided by the part on it, as camera samples are by their weights, so
    light paths estimate the corners as camera paths do."""
    shape, lights = LIGHTS["constant sky"]
    scene = load_scene(write_scene(tmp_path, shape, lights=lights, max_depth=3))
    scene.film.filter.kind = scene.film.filter.GAUSSIAN
    scene.film.filter.radius = 1.5
    renders = {
        name: client.render(
            scene,
            spp=512,
            seed=seed,
            sampler=INDEPENDENT,
            transport=component(name, max_depth=3),
        )
        for name, seed in (("path", 1), (transport, 2))
    }
    test = block_z_test(
        renders[transport].pixels,
        renders[transport].variance,
        renders["path"].pixels,
        renders["path"].variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"{transport} vs path under a Gaussian filter:\n{test.report()}"
