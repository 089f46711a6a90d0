"""Surfaces as Mitsuba 3 renders them: UVs, vertex normals, smooth shading, curves.

Each scene is one Mitsuba XML file that yarf's importer and Mitsuba 3
(scalar_rgb, made in the test) both read; yarf's render must pass Mitsuba's
own render-regression criterion against Mitsuba's (imagestats.pixel_z_test).
The path tracer, the light tracer and the bidirectional path tracer must
also agree with each other on the smooth-shaded scene (block z-test), so
that shading normals are handled alike for radiance and for importance.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from imagestats import block_z_test, pixel_z_test
from surface_scenes import (
    SPP,
    positions_only_ply,
    render_mitsuba,
    uv_sphere,
    uv_sphere_obj,
    uv_sphere_ply,
    write_scene,
)

from yarf import Client, RenderResult, component, load_scene
from yarf.assets import upload_scene_assets
from yarf.v1 import scene_pb2

INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
EXAMPLES = Path(__file__).resolve().parents[1] / "components" / "python" / "examples"
NEAREST_CLAMPED = (
    '<string name="filter_type" value="nearest"/><string name="wrap_mode" value="clamp"/>'
    '<transform name="to_uv"><scale x="1.5" y="1.5"/></transform>'
)
LOW_POLY = uv_sphere_obj(segments=12, rings=6)
GREY = '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf>'


def low_poly_sphere(face_normals: bool) -> str:
    flat = '<boolean name="face_normals" value="true"/>' if face_normals else ""
    return f'<shape type="obj"><string name="filename" value="sphere.obj"/>{flat}{GREY}</shape>'


def png(path: Path) -> None:
    """A 32×16 8-bit sRGB image of coloured stripes and blocks (its top rows red),
    and alpha.png beside it."""
    from PIL import Image

    rows, columns = np.mgrid[0:16, 0:32]
    image = np.zeros((16, 32, 3), np.uint8)
    image[..., 0] = np.where(rows < 4, 230, 40)
    image[..., 1] = (columns * 8 % 256).astype(np.uint8)
    image[..., 2] = np.where((rows // 4 + columns // 4) % 2 == 0, 200, 20)
    Image.fromarray(image).save(path)
    # Beside it, a grey 6×6 checker of opaque and clear cells, for cut-outs.
    cells = np.indices((6, 6)).sum(axis=0) % 2
    Image.fromarray((cells * 255).astype(np.uint8), mode="L").save(path.with_name("alpha.png"))
    # And normal maps: ridges across u (tilted ±35° in x), and the flat map.
    tilt = np.radians(35) * np.sin(np.linspace(0, 8 * np.pi, 64, endpoint=False))
    normal = np.stack([np.sin(tilt), np.zeros_like(tilt), np.cos(tilt)], axis=-1)
    ridges = np.broadcast_to(normal, (32, 64, 3))
    # A height map: ridges across u, and bumps across v, in 8-bit grey.
    u, v = np.meshgrid(np.linspace(0, 1, 64, endpoint=False), np.linspace(0, 1, 32, endpoint=False))
    height = 0.5 + 0.35 * np.sin(16 * np.pi * u) + 0.12 * np.cos(8 * np.pi * v)
    Image.fromarray(np.round(height * 255).astype(np.uint8), mode="L").save(
        path.with_name("height.png")
    )
    for name, normals in (
        ("ridges.png", ridges),
        ("flat.png", np.full((4, 4, 3), [0.0, 0.0, 1.0])),
    ):
        encoded = np.round((np.asarray(normals) + 1) / 2 * 255).astype(np.uint8)
        Image.fromarray(encoded).save(path.with_name(name))


def bitmap(name: str, extra: str = "") -> str:
    return (
        f'<texture type="bitmap" name="{name}">'
        f'<string name="filename" value="tex.png"/>{extra}</texture>'
    )


def normal_mapped(image: str) -> str:
    """A sphere of a grey diffuse seen through the normal map ``image``."""
    return (
        '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="normalmap">'
        f'<texture type="bitmap" name="normalmap"><string name="filename" value="{image}"/>'
        f'<boolean name="raw" value="true"/></texture>{GREY}</bsdf></shape>'
    )


TEXTURED = {
    "textured diffuse sphere": (
        f'<shape type="sphere"><float name="radius" value="0.9"/>'
        f'<bsdf type="diffuse">{bitmap("reflectance")}</bsdf></shape>'
    ),
    "textured rough conductor": (
        '<shape type="sphere"><float name="radius" value="0.9"/>'
        '<bsdf type="roughconductor"><string name="material" value="none"/>'
        '<string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>'
        f"{bitmap('specular_reflectance')}</bsdf></shape>"
    ),
    "nearest-filtered texture, clamped": (
        f'<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="diffuse">'
        f"{bitmap('reflectance', NEAREST_CLAMPED)}</bsdf></shape>"
    ),
    "normal map": normal_mapped("ridges.png"),
    "normal map, identity": normal_mapped("flat.png"),
    # The opacity is a bitmap: Mitsuba's checkerboard gives a float (eval_1)
    # with its two colours swapped.
    "alpha-masked leaf and its shadow": (
        '<shape type="rectangle"><transform name="to_world"><scale value="0.9"/>'
        '<rotate x="1" angle="-70"/><rotate y="1" angle="20"/><translate y="0.2"/></transform>'
        '<bsdf type="mask"><texture type="bitmap" name="opacity">'
        '<string name="filename" value="alpha.png"/><boolean name="raw" value="true"/>'
        '<string name="filter_type" value="nearest"/></texture>'
        '<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.7, 0.2"/>'
        "</bsdf></bsdf></bsdf></shape>"
    ),
    # A tile facing the camera, its bumps tilted by up to ~35°: gentle enough
    # that no view falls below a bumped facet.
    "bump map": (
        '<shape type="rectangle"><transform name="to_world"><scale value="0.9"/>'
        '<rotate x="1" angle="-15"/><translate y="0.1"/></transform><bsdf type="bumpmap">'
        '<texture type="bitmap" name="height"><string name="filename" value="height.png"/>'
        '<boolean name="raw" value="true"/></texture><float name="scale" value="0.05"/>'
        f"{GREY}</bsdf></shape>"
    ),
    "checkerboard plane at grazing angles": (
        '<shape type="rectangle"><transform name="to_world"><scale value="3"/>'
        '<rotate x="1" angle="-90"/><translate y="-0.9"/></transform>'
        '<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">'
        '<rgb name="color0" value="0.9, 0.9, 0.8"/><rgb name="color1" value="0.05, 0.1, 0.2"/>'
        '<transform name="to_uv"><scale x="24" y="24"/></transform></texture></bsdf></shape>'
    ),
    "checkerboard at grazing angles": (
        '<shape type="sphere"><float name="radius" value="0.5"/>'
        '<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">'
        '<rgb name="color0" value="0.9, 0.2, 0.1"/><rgb name="color1" value="0.1, 0.3, 0.8"/>'
        '<transform name="to_uv"><scale x="6" y="3"/></transform></texture></bsdf></shape>'
    ),
}


def coloured_sphere(attribute: str) -> str:
    """The low-poly sphere (sphere.ply) whose reflectance is a mesh attribute."""
    return (
        '<shape type="ply"><string name="filename" value="sphere.ply"/><bsdf type="diffuse">'
        '<texture type="mesh_attribute" name="reflectance">'
        f'<string name="name" value="{attribute}"/></texture></bsdf></shape>'
    )


def strands() -> str:
    """Five wavy strands rising above the floor and thinning, as a Mitsuba curve
    file: "x y z radius" per control point, strands apart by empty lines.
    Their thick lower ends stand in the light: rays from the floor enter the
    tubes there, and must leave them as Mitsuba's rays do."""
    lines = []
    for k in range(5):
        for i in range(6):
            t = i / 5
            x = -1.2 + 0.6 * k + 0.3 * math.sin(3 * t + k)
            z = 0.4 * math.cos(2 * t + k)
            lines.append(f"{x:.4f} {-1 + 1.9 * t:.4f} {z:.4f} {0.14 - 0.08 * t:.4f}")
        lines.append("")
    return "\n".join(lines)


def curves(kind: str, scale: float = 1, bsdf: str = GREY) -> str:
    """The strands as Mitsuba's ``kind`` of curve (its radii untouched by to_world)."""
    placed = (
        f'<transform name="to_world"><scale value="{scale}"/></transform>' if scale != 1 else ""
    )
    return f'<shape type="{kind}"><string name="filename" value="hair.txt"/>{placed}{bsdf}</shape>'


# Blonde hair, its scales tilted the other way, and black hair with
# smoother fibres: the fibre model's lobes and absorption.
BLONDE = (
    '<bsdf type="hair"><float name="eumelanin" value="0.3"/>'
    '<float name="scale_tilt" value="-3"/></bsdf>'
)
DARK = (
    '<bsdf type="hair"><float name="eumelanin" value="4"/>'
    '<float name="longitudinal_roughness" value="0.15"/>'
    '<float name="azimuthal_roughness" value="0.5"/></bsdf>'
)


SHAPES = {
    "vertex-coloured mesh": (
        coloured_sphere("vertex_color"),
        {"sphere.ply": uv_sphere_ply(12, 6, per_face=False)},
    ),
    "face-coloured mesh": (
        coloured_sphere("face_color"),
        {"sphere.ply": uv_sphere_ply(12, 6, per_face=True)},
    ),
    "smooth low-poly sphere": (low_poly_sphere(False), {"sphere.obj": LOW_POLY}),
    # No normals in the file: Mitsuba computes smooth ones (angle-weighted).
    "low-poly sphere without normals": (
        f'<shape type="ply"><string name="filename" value="sphere.ply"/>{GREY}</shape>',
        {"sphere.ply": positions_only_ply(uv_sphere(12, 6))},
    ),
    "faceted low-poly sphere": (low_poly_sphere(True), {"sphere.obj": LOW_POLY}),
    "B-spline curves": (curves("bsplinecurve"), {"hair.txt": strands()}),
    "B-spline curves, scaled": (curves("bsplinecurve", 1.25), {"hair.txt": strands()}),
    "straight curves": (curves("linearcurve"), {"hair.txt": strands()}),
    "blonde hair": (curves("bsplinecurve", bsdf=BLONDE), {"hair.txt": strands()}),
    "dark hair": (curves("bsplinecurve", bsdf=DARK), {"hair.txt": strands()}),
    "cylinder": (
        '<shape type="cylinder"><float name="radius" value="0.6"/>'
        '<point name="p0" x="0" y="-1" z="0"/><point name="p1" x="0" y="0.8" z="0"/>'
        # Its inside is in view: twosided makes it reflect like the outside.
        f'<bsdf type="twosided">{GREY}</bsdf></shape>',
        {},
    ),
    # Mitsuba's diffuse alone is one-sided: the inside is black.
    "open cylinder, one-sided": (
        '<shape type="cylinder"><float name="radius" value="0.6"/>'
        '<point name="p0" x="0" y="-1" z="0"/><point name="p1" x="0" y="0.8" z="0"/>'
        f"{GREY}</shape>",
        {},
    ),
    "cube": (
        '<shape type="cube"><transform name="to_world"><scale value="0.7"/>'
        '<rotate y="1" angle="30"/><translate y="-0.3"/></transform>'
        f"{GREY}</shape>",
        {},
    ),
}


def assert_matches_mitsuba(client: Client, scene: scene_pb2.Scene, path: Path, name: str) -> None:
    """yarf's render of ``scene`` passes Mitsuba's criterion against Mitsuba's of ``path``."""
    reference, reference_variance = render_mitsuba(path)
    result = client.render(scene, spp=SPP, seed=3, sampler=INDEPENDENT, timeout=600)
    assert result.pixels.shape == reference.shape
    test = pixel_z_test(result.pixels, result.variance, reference, reference_variance)
    assert test.ok, (
        f"{name}: {100 * test.passed:.2f}% of pixel channels within |z| < {test.threshold:.2f} "
        f"(Mitsuba's bar: 99.75%); worst:\n{test.worst}"
    )


def assert_agrees(result: RenderResult, reference: RenderResult, label: str) -> None:
    """Two yarf renders agree within their noise: means of 4×4 blocks, block z-test."""
    test = block_z_test(
        result.pixels,
        result.variance,
        reference.pixels,
        reference.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"{label}:\n{test.report()}"


@pytest.mark.parametrize("name", list(SHAPES))
def test_shape_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    shape, files = SHAPES[name]
    path = write_scene(tmp_path, shape, files)
    assert_matches_mitsuba(client, load_scene(path), path, name)


@pytest.mark.parametrize("name", list(TEXTURED))
def test_texture_matches_mitsuba(client: Client, tmp_path: Path, name: str) -> None:
    png(tmp_path / "tex.png")
    path = write_scene(tmp_path, TEXTURED[name])
    scene = load_scene(path)
    assert scene.textures, "the importer made no texture"
    upload_scene_assets(client, scene, tmp_path)
    assert_matches_mitsuba(client, scene, path, name)


@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_transports_agree_with_shading_normals(
    client: Client, tmp_path: Path, transport: str
) -> None:
    """On the smooth low-poly sphere, textured: shading normals and textures alike
    for radiance and importance."""
    png(tmp_path / "tex.png")
    textured = (
        '<shape type="obj"><string name="filename" value="sphere.obj"/>'
        f'<bsdf type="diffuse">{bitmap("reflectance")}</bsdf></shape>'
    )
    scene = load_scene(write_scene(tmp_path, textured, {"sphere.obj": LOW_POLY}))
    upload_scene_assets(client, scene, tmp_path)

    def render(name: str, spp: int, seed: int) -> RenderResult:
        method = component(name, max_depth=4)
        result = client.render(
            scene, spp=spp, seed=seed, transport=method, sampler=INDEPENDENT, timeout=600
        )
        assert np.isfinite(result.pixels).all()
        return result

    reference = render("path", 1024, 1)
    other = render(transport, 512, 2)
    assert_agrees(other, reference, f"{transport} vs path, smooth shading")


def test_python_texture_renders_as_the_cpp_one(client: Client, tmp_path: Path) -> None:
    """The SDK's py_checkerboard, out of process, against yarfd's checkerboard."""
    scene = load_scene(write_scene(tmp_path, TEXTURED["checkerboard at grazing angles"]))
    (texture,) = scene.textures
    assert texture.texture.class_name == "checkerboard"
    reference = client.render(scene, spp=256, seed=1, sampler=INDEPENDENT, timeout=600)
    with ComponentProcess.python(
        [f"{EXAMPLES / 'checkerboard.py'}:Checkerboard"], f"unix:{tmp_path / 'texture.sock'}"
    ) as process:
        texture.texture.class_name = "py_checkerboard"
        texture.texture.address = process.address
        remote = client.render(scene, spp=256, seed=2, sampler=INDEPENDENT, timeout=600)
    assert_agrees(remote, reference, "py_checkerboard vs checkerboard")
    assert abs(remote.pixels.mean() - reference.pixels.mean()) < 0.02 * reference.pixels.mean()
