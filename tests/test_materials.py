"""Materials as Mitsuba 3 renders them, made of other materials: Mitsuba's
blendbsdf (yarf's blend, which pbrt-v4's mix also becomes), its weight a
constant or an image, against Mitsuba's own render of the same file
(Mitsuba's render-regression criterion)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from surface_scenes import write_scene
from test_lights import write_pfm
from test_surfaces import assert_matches_mitsuba

from yarf import Client, load_scene
from yarf.assets import upload_scene_assets

DIFFUSE = '<bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.2, 0.1"/></bsdf>'
ROUGH_GOLD = (
    '<bsdf type="roughconductor"><string name="material" value="Au"/>'
    '<float name="alpha" value="0.2"/></bsdf>'
)
# A weight image: columns from 0.1 to 0.9. (Not a checkerboard: Mitsuba
# reads a checkerboard as a float with its two colours swapped, eval_1
# against eval, which yarf does not copy.)
IMAGE_WEIGHT = (
    '<texture type="bitmap" name="weight"><string name="filename" value="weight.pfm"/>'
    '<string name="filter_type" value="nearest"/></texture>'
)
BLENDS = {
    "constant weight": '<float name="weight" value="0.35"/>',
    "image weight": IMAGE_WEIGHT,
}


@pytest.mark.parametrize("name", list(BLENDS))
def test_blendbsdf_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    shape = (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        f'<bsdf type="blendbsdf">{BLENDS[name]}{DIFFUSE}{ROUGH_GOLD}</bsdf></shape>'
    )
    columns = np.linspace(0.1, 0.9, 8, dtype=np.float32)
    write_pfm(tmp_path / "weight.pfm", np.broadcast_to(columns[None, :, None], (4, 8, 3)).copy())
    path = write_scene(tmp_path, shape)
    scene = load_scene(path)
    upload_scene_assets(client, scene, tmp_path)
    assert [m.class_name for m in scene.materials if m.class_name == "blend"] == ["blend"]
    assert_matches_mitsuba(client, scene, path, f"blendbsdf, {name}")


# Mitsuba 3's pplastic as it renders in RGB: a rough coating and a diffuse
# base reflecting apart.
PPLASTIC = {
    "beckmann": '<float name="alpha" value="0.2"/>',
    "anisotropic ggx": (
        '<string name="distribution" value="ggx"/>'
        '<float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/>'
    ),
}


@pytest.mark.parametrize("name", list(PPLASTIC))
def test_pplastic_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    shape = (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        f'<bsdf type="pplastic">{PPLASTIC[name]}'
        '<rgb name="diffuse_reflectance" value="0.6, 0.3, 0.1"/></bsdf></shape>'
    )
    path = write_scene(tmp_path, shape)
    scene = load_scene(path)
    assert "pplastic" in {m.class_name for m in scene.materials}
    assert_matches_mitsuba(client, scene, path, f"pplastic, {name}")
