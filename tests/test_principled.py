"""Mitsuba 3's principled (Disney) BSDFs as yarf renders them.

Each scene is one Mitsuba XML file (a shape of a principled or principledthin
material in the lit room of surface_scenes.py) that yarf's importer maps to
yarf's model of the same name and Mitsuba 3 (scalar_rgb, made in the test)
renders itself; yarf's render must pass Mitsuba's own render-regression
criterion against Mitsuba's (test_surfaces.assert_matches_mitsuba).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from surface_scenes import write_scene
from test_surfaces import assert_matches_mitsuba, png

from yarf import Client, load_scene
from yarf.assets import upload_scene_assets


def principled_sphere(parameters: dict[str, float]) -> str:
    """A sphere of a warm principled material with the given float parameters."""
    floats = "".join(
        f'<float name="{name}" value="{value}"/>' for name, value in parameters.items()
    )
    return (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="principled">'
        f'<rgb name="base_color" value="0.8, 0.45, 0.2"/>{floats}</bsdf></shape>'
    )


PRINCIPLED = {
    # Part metal, part diffuse, under a clear coat.
    "coated metallic sphere": {
        "metallic": 0.3,
        "roughness": 0.4,
        "spec_trans": 0.0,
        "clearcoat": 0.5,
    },
    # Mostly rough glass: refraction in and out of the sphere, and its
    # shadow lit through it.
    "glassy sphere": {"spec_trans": 0.8, "roughness": 0.4},
}


@pytest.mark.parametrize("name", list(PRINCIPLED))
def test_principled_sphere_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    path = write_scene(tmp_path, principled_sphere(PRINCIPLED[name]), max_depth=6)
    scene = load_scene(path)
    assert scene.materials, "the importer made no material"
    assert any(m.class_name == "principled" for m in scene.materials), (
        "principled was not mapped to yarf's principled model"
    )
    assert_matches_mitsuba(client, scene, path, name)


def thin(parameters: str) -> str:
    """A principledthin BSDF with the given parameters (XML)."""
    return f'<bsdf type="principledthin">{parameters}</bsdf>'


PRINCIPLED_THIN = {
    # Textured colour (a checkerboard) and roughness (an image's luminance),
    # with a little specular transmission, tint and sheen.
    "textured thin sphere": (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        + thin(
            '<texture type="checkerboard" name="base_color">'
            '<rgb name="color0" value="0.8, 0.3, 0.1"/><rgb name="color1" value="0.2, 0.5, 0.7"/>'
            '<transform name="to_uv"><scale x="6" y="3"/></transform></texture>'
            '<texture type="bitmap" name="roughness"><string name="filename" value="tex.png"/>'
            '<boolean name="raw" value="true"/></texture>'
            '<float name="spec_trans" value="0.3"/><float name="spec_tint" value="0.4"/>'
            '<float name="sheen" value="0.6"/><float name="flatness" value="0.3"/>'
        )
        + "</shape>"
    ),
    # A leaf held up to the light: rough transmission and translucency carry
    # the light through it onto the floor, which the camera sees beneath it.
    "translucent thin leaf": (
        '<shape type="rectangle"><transform name="to_world"><scale value="0.9"/>'
        '<rotate x="1" angle="-70"/><rotate y="1" angle="20"/><translate y="0.2"/></transform>'
        + thin(
            '<rgb name="base_color" value="0.35, 0.75, 0.2"/>'
            '<float name="spec_trans" value="0.5"/><float name="diff_trans" value="1.2"/>'
            '<float name="roughness" value="0.4"/><float name="anisotropic" value="0.5"/>'
            '<float name="eta" value="1.33"/>'
        )
        + "</shape>"
    ),
}


@pytest.mark.parametrize("name", list(PRINCIPLED_THIN))
def test_principled_thin_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    png(tmp_path / "tex.png")
    path = write_scene(tmp_path, PRINCIPLED_THIN[name])
    scene = load_scene(path)
    assert any(m.class_name == "principledthin" for m in scene.materials), (
        "principledthin was not mapped to yarf's principledthin model"
    )
    upload_scene_assets(client, scene, tmp_path)
    assert_matches_mitsuba(client, scene, path, name)
