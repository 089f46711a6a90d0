"""pbrt-v4's subsurface material as a dielectric boundary around the
scattering medium its BSSRDF approximates, walked through by volpath.

White furnace: under a uniform sky, a sphere whose medium absorbs nothing
returns every bit of light, whatever its boundary's index, as long as the
walk under its surface is not cut short; every pixel is the sky's radiance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from imagestats import pixel_z_test
from test_surfaces import INDEPENDENT

from yarf import Client, load_scene

SKY = 0.5
SCENE = """LookAt 0 0 4  0 0 0  0 1 0
Camera "perspective" "float fov" 35
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" {maxdepth}
WorldBegin
LightSource "infinite" "rgb L" [{sky} {sky} {sky}]
Material "subsurface" "float eta" {eta} {coefficients}
Shape "sphere" "float radius" 1
"""


def furnace(
    client: Client, folder: Path, *, eta: float, maxdepth: int, coefficients: str
) -> np.ndarray:
    path = folder / "furnace.pbrt"
    path.write_text(SCENE.format(sky=SKY, eta=eta, maxdepth=maxdepth, coefficients=coefficients))
    scene = load_scene(path)
    assert scene.transport.class_name == "volpath"
    assert [m.class_name for m in scene.materials] == ["dielectric"]
    assert [s.interior for s in scene.shapes] == [scene.media[0].name]
    result = client.render(scene, spp=64, seed=2, sampler=INDEPENDENT, timeout=300)
    test = pixel_z_test(
        result.pixels,
        result.variance,
        np.full_like(result.pixels, SKY),
        np.zeros(result.pixels.shape),
    )
    passed = f"{100 * test.passed:.2f}% of pixel channels within |z| < {test.threshold:.2f}"
    assert test.ok, f"{passed}:\n{test.worst}"
    return result.pixels


@pytest.mark.parametrize("eta", [1.0, 1.33])
def test_a_subsurface_sphere_that_absorbs_nothing_vanishes_in_a_white_furnace(
    client: Client, tmp_path: Path, eta: float
) -> None:
    # Five bounces of pbrt's, each an entry or exit (or, at 1.33, a
    # reflection inside): the walk between them, some 25 scatterings deep
    # at this density, counts as none.
    furnace(
        client,
        tmp_path,
        eta=eta,
        maxdepth=5 if eta == 1.0 else 200,
        coefficients='"rgb sigma_a" [0 0 0] "rgb sigma_s" [5 5 5]',
    )


def test_reflectance_and_mean_free_path_set_the_medium(client: Client, tmp_path: Path) -> None:
    # A reflectance of 1 is an albedo of 1: no absorption, the furnace holds.
    furnace(
        client,
        tmp_path,
        eta=1.0,
        maxdepth=5,
        coefficients='"rgb reflectance" [1 1 1] "rgb mfp" [0.2 0.2 0.2]',
    )
