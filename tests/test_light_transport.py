"""Three unbiased light transport methods converge to the same images.

The eye path tracer, the light tracer and the bidirectional path tracer
estimate the same path integral by different sampling. On the Cornell box,
its glossy variant (modified Phong walls, a glass sphere and its caustic)
and the Veach-style MIS scene, means of 8×8-pixel blocks of each method
must agree with the path tracer's within a Šidák-corrected z-test built
from the renders' own variance estimates, and the RMSE between two methods
must fall like 1/√spp.

A light tracer cannot see specular surfaces directly (the camera is a
pinhole), and sees near-specular ones only through rare, huge
contributions whose variance its estimate cannot capture at test sample
counts: it is compared outside the pixels where the glass sphere (glossy
box) or the sharpest plate, α = 0.005 (MIS scene), is in view.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from imagestats import assert_renders_agree, block_z_test

from yarf import Client, LocalServer, RenderResult, component, load_scene, properties, rgb
from yarf.v1 import render_pb2, scene_pb2

SCENES = {
    "cornell-box": REPO / "scenes" / "cornell-box" / "scene.json",
    "cornell-box-glossy": REPO / "scenes" / "cornell-box" / "glossy.json",
    "veach-mis": REPO / "scenes" / "veach-mis" / "scene.json",
}
WIDTH = 64
BLOCK = 8
MAX_DEPTH = 6
FAMILY_ALPHA = 1e-3
# Samples per pixel of each method, for similar noise in similar time.
SPP = {"path": 512, "light": 256, "bdpt": 128}
INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
# Materials the light tracer is not compared on, where they are in view.
HIDDEN_FROM_LIGHT_TRACER = {
    "cornell-box": set(),
    "cornell-box-glossy": {"glass"},
    "veach-mis": {"plate0"},
}


def method(name: str) -> scene_pb2.ComponentSpec:
    return component(name, max_depth=MAX_DEPTH)


def small(path: Path) -> scene_pb2.Scene:
    """The scene at WIDTH pixels across, its aspect ratio kept (a multiple of BLOCK)."""
    scene = load_scene(path)
    height = scene.film.height * WIDTH // scene.film.width
    scene.film.width, scene.film.height = WIDTH, height - height % BLOCK
    # Lights chosen uniformly: chosen by power, the MIS scene's far fill
    # light would take 99% of the light tracer's paths, leaving the plates'
    # reflections of the four small lights to rare, huge contributions.
    scene.light_sampler = scene.LIGHT_SAMPLER_UNIFORM
    return scene


def render(client: Client, scene: scene_pb2.Scene, name: str, spp: int, seed: int) -> RenderResult:
    result = client.render(
        scene, spp=spp, seed=seed, transport=method(name), sampler=INDEPENDENT, timeout=600
    )
    assert np.isfinite(result.pixels).all() and np.isfinite(result.variance).all()
    return result


def in_view(client: Client, scene: scene_pb2.Scene, materials: set[str]) -> np.ndarray:
    """Pixels where a surface made of one of ``materials`` is seen directly.

    Renders the scene with those surfaces turned into white emitters and
    everything else black, emitters only (max_depth 1).
    """
    mask = scene_pb2.Scene()
    mask.CopyFrom(scene)
    del mask.materials[:]
    mask.materials.add(
        name="black", class_name="lambertian", properties=properties(reflectance=rgb(0))
    )
    for shape in mask.shapes:
        shape.ClearField("emitter")
        if shape.material in materials:
            shape.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1)))
        shape.material = "black"
    result = client.render(mask, spp=4, seed=1, transport=component("path", max_depth=1))
    return result.pixels.max(axis=2) > 0


@pytest.fixture(scope="module")
def path_references(client: Client) -> dict[str, RenderResult]:
    return {
        name: render(client, small(path), "path", SPP["path"], 1) for name, path in SCENES.items()
    }


@pytest.mark.parametrize("scene_name", list(SCENES))
@pytest.mark.parametrize("transport", ["light", "bdpt"])
def test_method_agrees_with_the_path_tracer_within_noise(
    client: Client, path_references: dict[str, RenderResult], scene_name: str, transport: str
) -> None:
    scene = small(SCENES[scene_name])
    reference = path_references[scene_name]
    result = render(client, scene, transport, SPP[transport], 2)
    pixels, variance = result.pixels.copy(), result.variance.copy()
    ref_pixels, ref_variance = reference.pixels.copy(), reference.variance.copy()
    if transport == "light":
        hidden = in_view(client, scene, HIDDEN_FROM_LIGHT_TRACER[scene_name])
        for image in (pixels, variance, ref_pixels, ref_variance):
            image[hidden] = 0
    test = block_z_test(
        pixels, variance, ref_pixels, ref_variance, block=BLOCK, family_alpha=FAMILY_ALPHA
    )
    assert not test.failing.size, (
        f"{transport} vs path on {scene_name}: blocks beyond |z| {test.threshold:.2f}:\n"
        + test.report()
    )
    # The whole image agrees too, within 2%.
    assert np.allclose(pixels.mean(axis=(0, 1)), ref_pixels.mean(axis=(0, 1)), rtol=0.02)


@pytest.mark.parametrize("scene_name", ["cornell-box", "cornell-box-glossy"])
def test_bdpt_with_roulette_from_the_first_segment_agrees_with_the_path_tracer(
    client: Client, path_references: dict[str, RenderResult], scene_name: str
) -> None:
    # Russian roulette may end either subpath at its first vertex: the
    # survivors' throughput is divided by their survival probability, so
    # the image keeps its expectation and only its noise grows.
    scene = small(SCENES[scene_name])
    reference = path_references[scene_name]
    result = client.render(
        scene,
        spp=SPP["bdpt"],
        seed=3,
        transport=component("bdpt", max_depth=MAX_DEPTH, rr_depth=1),
        sampler=INDEPENDENT,
        timeout=600,
    )
    assert np.isfinite(result.pixels).all()
    assert_renders_agree(
        result,
        reference,
        f"bdpt with rr_depth 1 vs path on {scene_name}",
        block=BLOCK,
        family_alpha=FAMILY_ALPHA,
    )
    assert np.allclose(
        result.pixels.mean(axis=(0, 1)), reference.pixels.mean(axis=(0, 1)), rtol=0.02
    )


def test_bdpt_at_a_depth_whose_subpaths_outgrow_a_batch_agrees_with_the_path_tracer(
    client: Client,
) -> None:
    # At max_depth 1000 a batch's subpaths would take hundreds of MB: bdpt
    # evaluates it in runs of points, and makes only the vertices reached.
    scene = small(SCENES["cornell-box"])
    reference = client.render(
        scene,
        spp=SPP["path"],
        seed=5,
        transport=component("path", max_depth=-1),
        sampler=INDEPENDENT,
        timeout=600,
    )
    result = client.render(
        scene,
        spp=SPP["bdpt"],
        seed=6,
        transport=component("bdpt", max_depth=1000),
        sampler=INDEPENDENT,
        timeout=600,
    )
    assert_renders_agree(
        result,
        reference,
        "bdpt at max_depth 1000 vs path unbounded",
        block=BLOCK,
        family_alpha=FAMILY_ALPHA,
    )


def test_rmse_between_methods_falls_like_one_over_root_spp(client: Client) -> None:
    scene = small(SCENES["cornell-box"])

    def rmse(spp: int) -> float:
        # The 1% largest squared errors are left out: a few pixels (the
        # light's edge, caustic paths) carry heavy-tailed noise that makes
        # a single image's plain RMSE a poor estimate of its expectation.
        a = render(client, scene, "path", spp, 10 + spp)
        b = render(client, scene, "bdpt", spp, 20 + spp)
        squared = np.sort(((a.pixels - b.pixels) ** 2).mean(axis=2).ravel())
        return float(np.sqrt(squared[: int(0.99 * squared.size)].mean()))

    low, high = rmse(8), rmse(128)
    # Sixteen times the samples: a quarter of the error, within noise.
    assert 3.0 < low / high < 5.3, f"RMSE {low:.5f} at 8 spp, {high:.5f} at 128 spp"


def test_cli_renders_with_the_transport_asked_for(server: LocalServer, tmp_path: Path) -> None:
    script = Path(sys.executable).parent / "yarf"
    base = [str(script), "render", str(SCENES["cornell-box"]), "--spp", "2"]
    base += ["--server", server.address, "-q"]
    output = tmp_path / "bdpt.png"
    run = subprocess.run(
        [*base, "-o", str(output), "--transport", "bdpt", "--max-depth", "3"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert output.read_bytes()[:4] == b"\x89PNG"
    with server.client() as client:
        assert client.list()[0].state == render_pb2.SUCCEEDED
    unknown = subprocess.run(
        [*base, "-o", str(tmp_path / "x.png"), "--transport", "no_such_transport"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert unknown.returncode != 0
    assert "no_such_transport" in unknown.stderr and "Traceback" not in unknown.stderr
