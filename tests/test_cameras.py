"""Cameras as Mitsuba 3 renders them: the orthographic sensor, its view set
by its to_world's scale, against Mitsuba's own render of the same file
(Mitsuba's render-regression criterion); light paths cannot reach it, and
the methods that need them say so."""

from __future__ import annotations

from pathlib import Path

import pytest
from surface_scenes import scene_xml
from test_surfaces import assert_matches_mitsuba

from yarf import Client, component, load_scene
from yarf.v1 import render_pb2

PERSPECTIVE = '<sensor type="perspective">\n    <float name="fov" value="40"/>'
# A view 3.2 units wide: x in [-1, 1] of the sensor's space, scaled by 1.6.
ORTHOGRAPHIC = '<sensor type="orthographic">\n    <float name="near_clip" value="0.5"/>'
ORTHOGRAPHIC_PLACEMENT = '<transform name="to_world">\n      <scale value="1.6"/>'
SPHERE = (
    '<shape type="sphere"><float name="radius" value="0.9"/>'
    '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
    '<float name="alpha" value="0.3"/></bsdf></shape>'
)


def orthographic_scene(folder: Path) -> Path:
    text = scene_xml(SPHERE)
    assert PERSPECTIVE in text
    text = text.replace(PERSPECTIVE, ORTHOGRAPHIC).replace(
        '<transform name="to_world">\n      <lookat', ORTHOGRAPHIC_PLACEMENT + "\n      <lookat", 1
    )
    path = folder / "scene.xml"
    path.write_text(text)
    return path


def test_orthographic_camera_matches_mitsuba(client: Client, tmp_path: Path) -> None:
    path = orthographic_scene(tmp_path)
    scene = load_scene(path)
    assert scene.camera.model == scene.camera.ORTHOGRAPHIC
    assert scene.camera.view_size == pytest.approx(3.2)
    assert_matches_mitsuba(client, scene, path, "orthographic camera")


@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_light_paths_refuse_an_orthographic_camera(
    client: Client, tmp_path: Path, transport: str
) -> None:
    scene = load_scene(orthographic_scene(tmp_path))
    job = client.submit(scene, spp=1, transport=component(transport))
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED
    assert "orthographic camera cannot be reached by light paths" in status.error
