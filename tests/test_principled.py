"""Mitsuba 3's principled (Disney) BSDF as yarf renders it.

Each scene is one Mitsuba XML file (a sphere of a principled material in the
lit room of surface_scenes.py) that yarf's importer maps to yarf's
`principled` model and Mitsuba 3 (scalar_rgb, made in the test) renders
itself; yarf's render must pass Mitsuba's own render-regression criterion
against Mitsuba's (test_surfaces.assert_matches_mitsuba).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from surface_scenes import write_scene
from test_surfaces import assert_matches_mitsuba

from yarf import Client, load_scene


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
