"""Participating media as Mitsuba 3's volpath renders them.

Each scene is one Mitsuba XML file that yarf's importer and Mitsuba 3
(scalar_rgb, made in the test) both read; yarf's volpath must pass
Mitsuba's render-regression criterion against Mitsuba's volpath
(imagestats.pixel_z_test): fog lit by an area light, an object, an
emitter and a dielectric inside media, a spot light through a rough
dielectric filled with a medium, a heterogeneous grid whose albedo varies,
and an extinction that differs per channel.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from surface_scenes import write_scene
from test_lights import ENVMAP, sky
from test_surfaces import assert_matches_mitsuba

from yarf import Client, load_scene
from yarf.assets import upload_scene_assets


def homogeneous(name: str, sigma_t: str, albedo: str, g: float = 0.0, scale: float = 1.0) -> str:
    """Mitsuba reads an rgb σ_t as a reflectance (each channel at most 1):
    larger extinctions come from ``scale``."""
    phase = f'<phase type="hg"><float name="g" value="{g}"/></phase>' if g else ""
    return (
        f'<medium type="homogeneous" name="{name}"><rgb name="sigma_t" value="{sigma_t}"/>'
        f'<rgb name="albedo" value="{albedo}"/><float name="scale" value="{scale}"/>'
        f"{phase}</medium>"
    )


def phased(phase: str) -> str:
    """A fog of albedo 0.9 that scatters by ``phase`` (Mitsuba's XML)."""
    return (
        '<medium type="homogeneous" name="interior"><rgb name="sigma_t" value="1, 1, 1"/>'
        '<rgb name="albedo" value="0.9, 0.8, 0.7"/><float name="scale" value="1.5"/>'
        f"{phase}</medium>"
    )


def fog_cube(medium: str, scale: float = 1.1) -> str:
    """A null cube (Mitsuba's [-1, 1]³, scaled) holding ``medium`` as its interior."""
    return (
        f'<shape type="cube"><transform name="to_world"><scale value="{scale}"/></transform>'
        f'<bsdf type="null"/>{medium}</shape>'
    )


GREY_SPHERE = (
    '<shape type="sphere"><float name="radius" value="0.5"/>'
    '<bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf></shape>'
)
FOG = homogeneous("interior", "0.8, 0.8, 0.8", "0.7, 0.7, 0.7", g=0.4)


def write_vol(path: Path, values: np.ndarray) -> None:
    """A Mitsuba .vol grid (version 3, float32) of values[z, y, x, channel]."""
    zres, yres, xres, channels = values.shape
    header = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, xres, yres, zres, channels)
    header += struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    path.write_bytes(header + values.astype("<f4").tobytes())


def grids(folder: Path) -> None:
    """A density that thickens upward and an albedo that goes from red to blue along x."""
    z, y, x = np.mgrid[0:12, 0:12, 0:12] / 11.0
    write_vol(
        folder / "density.vol",
        (0.2 + 2.5 * y * (0.5 + 0.5 * np.sin(6 * x + 3 * z) ** 2))[..., None],
    )
    albedo = np.stack([0.9 - 0.6 * x, 0.5 + 0 * x, 0.3 + 0.6 * x], axis=-1)
    write_vol(folder / "albedo.vol", albedo)


# Both grids fill the cube [-1.1, 1.1]³.
GRID_PLACEMENT = (
    '<transform name="to_world"><translate value="-0.5, -0.5, -0.5"/><scale value="2.2"/>'
    "</transform>"
)
GRID = (
    '<medium type="heterogeneous" name="interior">'
    '<volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/>'
    f"{GRID_PLACEMENT}</volume>"
    '<volume type="gridvolume" name="albedo"><string name="filename" value="albedo.vol"/>'
    f"{GRID_PLACEMENT}</volume>"
    '<float name="scale" value="1.5"/></medium>'
)

SPOT = (
    '<emitter type="spot"><transform name="to_world">'
    '<lookat origin="0.5, 3, 0.5" target="0, 0, 0" up="0, 0, 1"/></transform>'
    '<rgb name="intensity" value="20, 18, 15"/><float name="cutoff_angle" value="30"/></emitter>'
)

# Back- and forward-peaked, values at μ = -1, -0.6, ..., 1.
TABULATED = '<phase type="tabphase"><string name="values" value="6, 1, 0.3, 0.2, 0.6, 4"/></phase>'

SCENES = {
    "fog lit by an area light": (fog_cube(FOG), {}),
    "an object inside fog": (fog_cube(FOG) + GREY_SPHERE, {}),
    "an emitter inside fog": (
        fog_cube(FOG) + '<shape type="sphere"><float name="radius" value="0.15"/>'
        '<point name="center" x="0.3" y="0" z="0.2"/>'
        '<emitter type="area"><rgb name="radiance" value="20, 15, 10"/></emitter></shape>',
        {},
    ),
    "a dielectric sphere of murky water under an envmap": (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        '<bsdf type="dielectric"><float name="int_ior" value="1.33"/></bsdf>'
        + homogeneous("interior", "1, 1, 1", "0.9, 0.8, 0.6", g=0.5, scale=1.5)
        + "</shape>",
        {"lights": ENVMAP},
    ),
    "a rough dielectric filled with fog under a spot light": (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        '<bsdf type="roughdielectric"><float name="alpha" value="0.2"/>'
        '<float name="int_ior" value="1.5"/></bsdf>'
        + homogeneous("interior", "1, 1, 1", "0.8, 0.8, 0.8", scale=1.2)
        + "</shape>",
        {"lights": SPOT},
    ),
    # Lit from one side: the phase function's shape shows in the fog's
    # brightness against the angle the camera sees the light turned by.
    "Rayleigh scattering lit by a spot light": (
        fog_cube(phased('<phase type="rayleigh"/>')),
        {"lights": SPOT},
    ),
    "a tabulated phase function lit by a spot light": (
        fog_cube(phased(TABULATED)),
        {"lights": SPOT},
    ),
    "a heterogeneous grid with spatially varying albedo": (fog_cube(GRID), {}),
    # Mitsuba's volpath samples such a medium by one channel without MIS, so
    # its estimate of the others is heavy-tailed; its volpathmis (spectral
    # MIS, as yarf's volpath) is the reference.
    "an extinction that differs per channel": (
        fog_cube(homogeneous("interior", "0.12, 0.4, 1", "0.9, 0.6, 0.8", scale=2.5)) + GREY_SPHERE,
        {"integrator": "volpathmis"},
    ),
}


@pytest.mark.parametrize("name", list(SCENES))
def test_medium_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    shape, room = SCENES[name]
    sky(tmp_path / "sky.pfm")
    grids(tmp_path)
    path = write_scene(tmp_path, shape, max_depth=8, **{"integrator": "volpath", **room})
    scene = load_scene(path)
    assert scene.media, "the importer made no medium"
    upload_scene_assets(client, scene, tmp_path)
    assert_matches_mitsuba(client, scene, path, name)
