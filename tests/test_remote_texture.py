"""Python textures out of process that read more of a surface point than its uv.

yarfd sends a remote texture each point's world position, where on which
shape it lies and the mesh attributes the texture asked for
(texture.proto's TextureQuery). A texture of world position must colour a
plane by where its points are; a Python mesh attribute must render as
yarfd's own mesh_attribute.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from imagestats import assert_renders_agree
from surface_scenes import uv_sphere_ply, write_scene

from yarf import Client, RenderResult, load_scene
from yarf.assets import upload_scene_assets
from yarf.v1 import component_pb2, scene_pb2

INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
EXAMPLES = Path(__file__).resolve().parents[1] / "components" / "python" / "examples"
# Radiance of every direction of the sky: a diffuse surface that sees only
# the sky reflects its albedo times this (L = ρ·L_sky), wherever it is.
SKY = 1.0
UNIFORM_SKY = f'<emitter type="constant"><rgb name="radiance" value="{SKY}"/></emitter>'
# A square 8 units wide in the plane z = 0 facing the camera (at x = 0), so
# that it fills the image and x = 0 is the image's middle column boundary.
# Its checkerboard is a stand-in the importer knows, replaced in the test.
WALL = (
    '<shape type="rectangle"><transform name="to_world"><scale value="4"/></transform>'
    '<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></shape>'
)
ABOVE = (0.7, 0.1, 0.1)
BELOW = (0.1, 0.6, 0.2)


def rgb(value: tuple[float, float, float]) -> component_pb2.Property:
    prop = component_pb2.Property()
    prop.rgb_value.r, prop.rgb_value.g, prop.rgb_value.b = value
    return prop


def half_means(result: RenderResult) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The mean RGB of the image's left and right halves and their standard errors."""
    width = result.pixels.shape[1]
    halves = (slice(0, width // 2), slice(width // 2, width))
    means = [result.pixels[:, half].reshape(-1, 3).mean(axis=0) for half in halves]
    errors = [
        np.sqrt(result.variance[:, half].reshape(-1, 3).sum(axis=0))
        / (result.pixels[:, half].size / 3)
        for half in halves
    ]
    return means[0], errors[0], means[1], errors[1]


def test_a_python_texture_colours_a_plane_by_world_position(client: Client, tmp_path: Path) -> None:
    """py_axis_split on a diffuse wall under a uniform sky: the half at x > 0
    reflects ``above``·L_sky, the half at x < 0 ``below``·L_sky."""
    scene = load_scene(write_scene(tmp_path, WALL, floor="", lights=UNIFORM_SKY))
    (texture,) = scene.textures
    with ComponentProcess.python(
        [f"{EXAMPLES / 'axis_split.py'}:AxisSplit"], f"unix:{tmp_path / 'texture.sock'}"
    ) as process:
        texture.texture.class_name = "py_axis_split"
        texture.texture.address = process.address
        texture.texture.properties.Clear()
        texture.texture.properties.values["above"].CopyFrom(rgb(ABOVE))
        texture.texture.properties.values["below"].CopyFrom(rgb(BELOW))
        result = client.render(scene, spp=64, seed=1, sampler=INDEPENDENT, timeout=600)
    assert np.isfinite(result.pixels).all()
    left, left_error, right, right_error = half_means(result)
    # Each half within 5 standard errors (and 0.1 % for the estimator's bias
    # in float32) of its albedo times the sky.
    for mean, error, albedo, side in (
        (left, left_error, BELOW, "x < 0"),
        (right, right_error, ABOVE, "x > 0"),
    ):
        expected = np.array(albedo) * SKY
        assert np.all(np.abs(mean - expected) <= 5 * error + 1e-3 * expected), (
            f"{side}: {mean} ± {error}, expected {expected}"
        )
    # The colour ratio of the halves is the albedos' (the sky cancels).
    np.testing.assert_allclose(right / left, np.array(ABOVE) / np.array(BELOW), rtol=0.03)


@pytest.mark.parametrize("attribute", ["vertex_color", "face_color"])
def test_a_python_mesh_attribute_renders_as_the_cpp_one(
    client: Client, tmp_path: Path, attribute: str
) -> None:
    """py_mesh_attribute, out of process, against yarfd's mesh_attribute on a
    coloured low-poly sphere: the attribute reaches the texture at each point."""
    sphere = (
        '<shape type="ply"><string name="filename" value="sphere.ply"/><bsdf type="diffuse">'
        '<texture type="mesh_attribute" name="reflectance">'
        f'<string name="name" value="{attribute}"/></texture></bsdf></shape>'
    )
    per_face = attribute.startswith("face_")
    ply = {"sphere.ply": uv_sphere_ply(12, 6, per_face=per_face)}
    scene = load_scene(write_scene(tmp_path, sphere, ply))
    upload_scene_assets(client, scene, tmp_path)
    (texture,) = scene.textures
    reference = client.render(scene, spp=256, seed=1, sampler=INDEPENDENT, timeout=600)
    with ComponentProcess.python(
        [f"{EXAMPLES / 'mesh_attribute.py'}:MeshAttribute"], f"unix:{tmp_path / 'texture.sock'}"
    ) as process:
        texture.texture.class_name = "py_mesh_attribute"
        texture.texture.address = process.address
        remote = client.render(scene, spp=256, seed=2, sampler=INDEPENDENT, timeout=600)
    assert_renders_agree(remote, reference, "py_mesh_attribute vs mesh_attribute")
    # And over the whole image, as the Python checkerboard's test.
    assert abs(remote.pixels.mean() - reference.pixels.mean()) < 0.02 * reference.pixels.mean()
