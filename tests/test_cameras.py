"""Cameras as Mitsuba 3 and pbrt-v4 render them: the orthographic sensor,
its view set by its to_world's scale, against Mitsuba's own render of the
same file (Mitsuba's render-regression criterion); pbrt-v4's spherical
camera by the solid angle a sphere hides from it and where the sphere
appears; light paths cannot reach either, and the methods that need them
say so."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from surface_scenes import scene_xml
from test_surfaces import assert_matches_mitsuba

from yarf import Client, SceneError, component, load_scene
from yarf.v1 import render_pb2, scene_pb2

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


# A black sphere of radius 1 at distance 3 under a uniform sky, seen by
# pbrt-v4's spherical camera at the origin, each pixel the mean of its own
# samples (a box filter of radius ½).
SPHERICAL_PBRT = """Film "rgb" "integer xresolution" [{width}] "integer yresolution" [{height}]
    "string filename" "spherical.exr"
PixelFilter "box" "float xradius" 0.5 "float yradius" 0.5
Sampler "independent" "integer pixelsamples" 64
Integrator "path" "integer maxdepth" 1
LookAt 0 0 0  0 0 1  0 1 0
Camera "spherical" "string mapping" "{mapping}"
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "diffuse" "rgb reflectance" [0 0 0]
Translate {at}
Shape "sphere" "float radius" 1
"""
# The share of all directions the sphere hides: its cone's solid angle
# over 4π.
HIDDEN = (1 - math.sqrt(1 - (1 / 3) ** 2)) / 2


def spherical_scene(folder: Path, mapping: str, at: str, width: int, height: int) -> Path:
    path = folder / f"{mapping}.pbrt"
    path.write_text(SPHERICAL_PBRT.format(mapping=mapping, at=at, width=width, height=height))
    return path


def sky_share(pixels: np.ndarray) -> np.ndarray:
    """Each pixel's share of the sky it sees: the sky's pixels are all alike."""
    luminance = pixels[..., :3].mean(axis=2)
    return luminance / luminance.max()


def centroid(hidden: np.ndarray) -> tuple[float, float]:
    """Where on the film (x, y in [0, 1]) the hidden share lies, on average."""
    height, width = hidden.shape
    y, x = np.mgrid[0:height, 0:width]
    total = hidden.sum()
    return float((hidden * (x + 0.5)).sum() / total / width), float(
        (hidden * (y + 0.5)).sum() / total / height
    )


def test_pbrt_spherical_camera_equal_area_pixels_each_see_the_same_solid_angle(
    client: Client, tmp_path: Path
) -> None:
    # The sphere straight up: the centre of the equal-area square.
    scene = load_scene(spherical_scene(tmp_path, "equiarea", "0 3 0", 48, 48))
    assert scene.camera.model == scene_pb2.Camera.SPHERICAL
    assert scene.camera.spherical_mapping == scene_pb2.Camera.EQUAL_AREA
    share = sky_share(client.render(scene, spp=64, seed=2).pixels)
    # Every pixel sees 4π / pixel count: the mean hidden share is the
    # sphere's (with an equirectangular film it would be 0.0184, not 0.0286).
    assert 1 - share.mean() == pytest.approx(HIDDEN, abs=1.5e-3)
    x, y = centroid(1 - share)
    assert x == pytest.approx(0.5, abs=0.01) and y == pytest.approx(0.5, abs=0.01)


def test_pbrt_spherical_camera_equirect_maps_latitude_and_longitude(
    client: Client, tmp_path: Path
) -> None:
    # The sphere ahead, along the LookAt: φ = 90° from the camera's +x,
    # θ = 90° from up, so x = ¼ and y = ½ of the film.
    height = 32
    scene = load_scene(spherical_scene(tmp_path, "equirect", "0 0 3", 2 * height, height))
    assert scene.camera.spherical_mapping == scene_pb2.Camera.EQUIRECTANGULAR
    share = sky_share(client.render(scene, spp=64, seed=3).pixels)
    # A row of pixels from θ0 to θ1 spans (cos θ0 − cos θ1)·2π of solid
    # angle: weighted so, the hidden share is the sphere's again.
    edges = np.cos(np.linspace(0, math.pi, height + 1))
    row_solid_angle = (edges[:-1] - edges[1:])[:, None] / 2
    hidden = ((1 - share) * row_solid_angle).sum() / share.shape[1]
    assert hidden == pytest.approx(HIDDEN, abs=1.5e-3)
    x, y = centroid(1 - share)
    assert x == pytest.approx(0.25, abs=0.01) and y == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_light_paths_refuse_a_spherical_camera(
    client: Client, tmp_path: Path, transport: str
) -> None:
    scene = load_scene(spherical_scene(tmp_path, "equiarea", "0 3 0", 16, 16))
    job = client.submit(scene, spp=1, transport=component(transport))
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED
    assert "spherical camera cannot be reached by light paths" in status.error


def test_pbrt_spherical_camera_refuses_an_unknown_mapping(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="mapping must be"):
        load_scene(spherical_scene(tmp_path, "cubemap", "0 3 0", 16, 16))
