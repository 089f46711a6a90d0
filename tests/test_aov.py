"""The aov transport: what the first surface a camera ray meets is.

An orthographic camera at height 5 looks straight down on a floor (z = 0)
whose left half is a Lambertian of reflectance (0.2, 0.4, 0.8) and right
half a perfect silver mirror. With a box filter of radius 0.5 every pixel
averages its own samples, so each variable has a value known in closed
form: depth 5, normals (0, 0, 1), z = 0, the Lambertian's albedo exactly
(one cosine-weighted sample is f cos / pdf = ρ), the mirror's 1, the
shapes' and materials' indices, and −1 where nothing is hit.
"""

from __future__ import annotations

from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import small_scene

from yarf import Client, RenderResult, component, properties, rgb, transform, vec3
from yarf.v1 import render_pb2, scene_pb2

SIZE = 16
SPP = 16
VIEW = 2.0
HEIGHT = 5.0
DIFFUSE = (0.2, 0.4, 0.8)


def half(scene: scene_pb2.Scene, x_center: float, material: str) -> None:
    """The half of the floor [x_center − 0.5, x_center + 0.5] × [-1, 1] at z = 0."""
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = (0.5, 0, 0), (0, 1, 0), (0, 0, 1), (x_center, 0, 0)
    shape = scene.shapes.add(material=material)
    shape.rectangle.SetInParent()
    shape.to_world.CopyFrom(transform(m))


def floor_scene(view: float = VIEW) -> scene_pb2.Scene:
    scene = small_scene(SIZE)
    del scene.shapes[:]
    del scene.materials[:]
    camera = scene.camera
    camera.model = scene_pb2.Camera.ORTHOGRAPHIC
    camera.origin.CopyFrom(vec3(0, 0, HEIGHT))
    camera.target.CopyFrom(vec3(0, 0, 0))
    camera.up.CopyFrom(vec3(0, 1, 0))
    camera.view_size = view
    scene.film.filter.kind = scene_pb2.ReconstructionFilter.BOX
    scene.film.filter.radius = 0.5
    scene.materials.add(
        name="paint", class_name="lambertian", properties=properties(reflectance=rgb(*DIFFUSE))
    )
    scene.materials.add(
        name="silver", class_name="conductor", properties=properties(specular_reflectance=rgb(1.0))
    )
    half(scene, -0.5, "paint")
    half(scene, 0.5, "silver")
    return scene


def render(client: Client, aov: str, scene: scene_pb2.Scene | None = None) -> RenderResult:
    return client.render(
        scene or floor_scene(),
        spp=SPP,
        seed=3,
        transport=component("aov", aov=aov),
        sampler=component("independent"),
    )


def test_depth_normals_and_position_of_a_floor_seen_from_above(client: Client) -> None:
    np.testing.assert_allclose(render(client, "depth").pixels, HEIGHT, rtol=1e-6)
    for normal in ("geo_normal", "sh_normal"):
        pixels = render(client, normal).pixels
        np.testing.assert_allclose(pixels[..., :2], 0, atol=1e-6)
        np.testing.assert_allclose(pixels[..., 2], 1, atol=1e-6)
    position = render(client, "position").pixels
    np.testing.assert_allclose(position[..., 2], 0, atol=1e-5)
    # Film columns run along +x and rows down along -y: each pixel's mean
    # position lies within the pixel.
    pixel = VIEW / SIZE
    left = -VIEW / 2 + pixel * np.arange(SIZE)
    assert np.all((position[..., 0] >= left[None, :]) & (position[..., 0] <= left[None, :] + pixel))
    top = VIEW / 2 - pixel * np.arange(SIZE)
    assert np.all((position[..., 1] <= top[:, None]) & (position[..., 1] >= top[:, None] - pixel))


def test_albedo_is_the_models_directional_albedo(client: Client) -> None:
    albedo = render(client, "albedo").pixels
    paint, silver = albedo[:, : SIZE // 2], albedo[:, SIZE // 2 :]
    np.testing.assert_allclose(paint, np.broadcast_to(DIFFUSE, paint.shape), rtol=1e-5)
    np.testing.assert_allclose(silver, 1, rtol=1e-5)


def test_indices_of_shapes_and_materials_and_minus_one_where_nothing_is_hit(
    client: Client,
) -> None:
    # A wider view than the floor: the outer columns see nothing.
    scene = floor_scene(view=4.0)
    shapes = render(client, "shape_index", scene).pixels[..., 0]
    materials = render(client, "material_index", scene).pixels[..., 0]
    quarter = SIZE // 4
    np.testing.assert_array_equal(shapes[:, :quarter], -1)
    np.testing.assert_array_equal(shapes[quarter + 1 : -quarter - 1, quarter : SIZE // 2], 0)
    np.testing.assert_array_equal(shapes[quarter + 1 : -quarter - 1, SIZE // 2 : -quarter], 1)
    np.testing.assert_array_equal(materials[quarter + 1 : -quarter - 1, quarter : SIZE // 2], 0)
    np.testing.assert_array_equal(materials[quarter + 1 : -quarter - 1, SIZE // 2 : -quarter], 1)
    np.testing.assert_array_equal(materials[:, -quarter:], -1)
    uv = render(client, "uv", scene).pixels
    inside = uv[quarter + 1 : -quarter - 1, quarter : SIZE // 2]
    assert np.all((inside[..., :2] >= 0) & (inside[..., :2] <= 1)) and np.all(inside[..., 2] == 0)
    # u grows along the rectangle's x axis, left to right.
    assert np.all(np.diff(inside[..., 0], axis=1) > 0)


def test_null_boundaries_are_not_surfaces(client: Client) -> None:
    scene = floor_scene()
    scene.materials.add(name="boundary", class_name="null")
    m = np.diag([5.0, 5.0, 1.0, 1.0])
    m[2, 3] = 1.0
    sheet = scene.shapes.add(material="boundary")
    sheet.rectangle.SetInParent()
    sheet.to_world.CopyFrom(transform(m))
    np.testing.assert_allclose(render(client, "depth", scene).pixels, HEIGHT, rtol=1e-6)


def test_an_unknown_variable_is_refused_naming_the_known_ones(client: Client) -> None:
    with pytest.raises((grpc.RpcError, RuntimeError), match="'albedo', 'sh_normal'"):
        render(client, "normals")


def test_a_job_renders_the_aovs_it_asks_for_beside_its_image(
    client: Client, tmp_path: Path
) -> None:
    scene = small_scene(SIZE)
    job = client.submit(scene, 8, seed=5, aovs=["depth", "albedo", "shape_index"])
    client.wait(job)
    result = client.raw(job)
    # Listed in a fixed order, whatever the request's.
    assert list(result.aovs) == ["albedo", "depth", "shape_index"]
    for name, image in result.aovs.items():
        # Each is what the aov transport renders alone, with the job's
        # sampler, seed and spp.
        alone = client.render(scene, spp=8, seed=5, transport=component("aov", aov=name))
        np.testing.assert_array_equal(image, alone.pixels, err_msg=name)
    assert np.isin(result.aovs["shape_index"][..., 0], [-1, 0, 1]).mean() > 0.5
    # An EXR holds them as channels NAME.R, NAME.G, NAME.B after R, G, B.
    import OpenImageIO as oiio

    path = tmp_path / "job.exr"
    path.write_bytes(client.result(job, render_pb2.GetResultRequest.EXR).image)
    image = oiio.ImageInput.open(str(path))
    try:
        names = list(image.spec().channelnames)
    finally:
        image.close()
    assert names == ["R", "G", "B"] + [f"{n}.{c}" for n in result.aovs for c in "RGB"]


@pytest.mark.parametrize(
    ("aovs", "message"),
    [(["normals"], "aov 'normals' is not one of albedo, sh_normal"), (["uv", "uv"], "twice")],
)
def test_unknown_or_repeated_aovs_are_refused_at_submit(
    client: Client, aovs: list[str], message: str
) -> None:
    with pytest.raises(grpc.RpcError, match=message) as refused:
        client.submit(small_scene(SIZE), 4, aovs=aovs)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
