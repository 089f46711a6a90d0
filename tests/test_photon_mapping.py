"""Photon mapping and SPPM converge to the path integral the unbiased methods estimate.

Small renders of the shipped Cornell boxes are compared with references
from the unbiased transports: the eye path tracer on the diffuse box, the
bidirectional path tracer for the glass sphere's caustic. Photon density
estimates are biased, so the tests check what the methods promise: the
photon map's error falls as photons grow, final gathering lands within a
stated tolerance, SPPM's error falls as passes accumulate (Knaus & Zwicker:
bias and variance both vanish), and the caustic map renders the caustic
that bidirectional path tracing converges to (and without it the caustic
is missing).
"""

from __future__ import annotations

from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import REPO
from imagestats import block_means

from yarf import Client, RenderResult, component, load_scene
from yarf.v1 import render_pb2, scene_pb2

DIFFUSE_BOX = REPO / "scenes" / "cornell-box" / "scene.json"
GLOSSY_BOX = REPO / "scenes" / "cornell-box" / "glossy.json"
# The caustic of the glass sphere on the floor of the glossy box at 48×48
# pixels: rows and columns well inside its bright spot.
CAUSTIC_WIDTH = 48
CAUSTIC = (slice(40, 44), slice(28, 36))


def small(path: Path, width: int) -> scene_pb2.Scene:
    scene = load_scene(path)
    scene.film.width = scene.film.height = width
    return scene


def render(
    client: Client, scene: scene_pb2.Scene, transport: scene_pb2.ComponentSpec, spp: int, seed: int
) -> RenderResult:
    result = client.render(scene, spp=spp, seed=seed, transport=transport, timeout=600)
    assert np.isfinite(result.pixels).all()
    return result


def block_rmse(image: np.ndarray, reference: np.ndarray, block: int = 4) -> float:
    """RMSE of block means: the low-frequency error density estimation makes, less pixel noise."""
    difference = block_means(image, block) - block_means(reference, block)
    return float(np.sqrt((difference**2).mean()))


def rmse(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(((image - reference) ** 2).mean()))


@pytest.fixture(scope="module")
def diffuse_reference(client: Client) -> np.ndarray:
    """The diffuse box at 32×32 by the path tracer, 4096 spp (its noise is far below the tests')."""
    return render(client, small(DIFFUSE_BOX, 32), component("path"), 4096, 1).pixels


@pytest.fixture(scope="module")
def caustic_reference(client: Client) -> np.ndarray:
    """The glossy box by the bidirectional path tracer, which finds the caustic easily."""
    return render(client, small(GLOSSY_BOX, CAUSTIC_WIDTH), component("bdpt"), 256, 1).pixels


def test_photon_map_error_falls_as_photons_grow(
    client: Client, diffuse_reference: np.ndarray
) -> None:
    scene = small(DIFFUSE_BOX, 32)

    def error(photons: int) -> float:
        # Without final gathering the global map is seen directly: its
        # density estimate's error is what shows.
        transport = component("photon_map", photons=photons, caustic_photons=0, final_gather=False)
        return block_rmse(render(client, scene, transport, 256, 2).pixels, diffuse_reference)

    coarse, fine = error(2_000), error(50_000)
    # Measured: 0.0064 and 0.0017.
    assert fine < 0.5 * coarse, f"block RMSE {coarse:.5f} at 2000 photons, {fine:.5f} at 50000"


def test_final_gathering_matches_the_path_tracer(
    client: Client, diffuse_reference: np.ndarray
) -> None:
    scene = small(DIFFUSE_BOX, 32)
    transport = component("photon_map", photons=50_000, caustic_photons=0)
    pixels = render(client, scene, transport, 256, 3).pixels
    mean, reference_mean = pixels.mean(), diffuse_reference.mean()
    # Measured: block RMSE 0.9% of the image mean, the means 0.2% apart.
    assert block_rmse(pixels, diffuse_reference) < 0.03 * reference_mean
    assert abs(mean - reference_mean) < 0.02 * reference_mean, f"{mean:.5f} vs {reference_mean:.5f}"


def test_sppm_converges_as_passes_accumulate(client: Client, diffuse_reference: np.ndarray) -> None:
    scene = small(DIFFUSE_BOX, 32)
    transport = component("sppm", photons_per_pass=20_000)
    errors = {
        spp: rmse(render(client, scene, transport, spp, 4).pixels, diffuse_reference)
        for spp in (4, 64)
    }
    # Knaus & Zwicker's rate, α = 2/3: the error falls at least like
    # N^(−α/2), 16^(1/3) ≈ 2.5 for sixteen times the passes (measured: 10,
    # as the few first passes' wide, noisy estimates average out).
    assert errors[4] / errors[64] > 16 ** (1 / 3), errors
    final = render(client, scene, transport, 64, 5).pixels
    assert abs(final.mean() - diffuse_reference.mean()) < 0.01 * diffuse_reference.mean()


def test_sppm_passes_are_deterministic(client: Client) -> None:
    scene = small(DIFFUSE_BOX, 16)
    transport = component("sppm", photons_per_pass=5_000)
    first = render(client, scene, transport, 8, 6).pixels
    second = render(client, scene, transport, 8, 6).pixels
    np.testing.assert_array_equal(first, second)


def caustic_mean(pixels: np.ndarray) -> float:
    return float(pixels[CAUSTIC].mean())


def test_caustic_map_renders_the_caustic(client: Client, caustic_reference: np.ndarray) -> None:
    scene = small(GLOSSY_BOX, CAUSTIC_WIDTH)
    transport = component("photon_map", photons=50_000, caustic_photons=200_000)
    value, reference = (
        caustic_mean(render(client, scene, transport, 64, 7).pixels),
        caustic_mean(caustic_reference),
    )
    # The caustic is far brighter than the floor across the image (2.2
    # times); the photon map's is measured 3.5% above bdpt's.
    assert reference > 1.5 * caustic_reference[CAUSTIC[0], :].mean()
    assert abs(value - reference) < 0.1 * reference, f"caustic {value:.4f} vs bdpt {reference:.4f}"


def test_without_caustic_photons_the_caustic_is_missing(
    client: Client, caustic_reference: np.ndarray
) -> None:
    scene = small(GLOSSY_BOX, CAUSTIC_WIDTH)
    transport = component("photon_map", photons=50_000, caustic_photons=0)
    value, reference = (
        caustic_mean(render(client, scene, transport, 64, 8).pixels),
        caustic_mean(caustic_reference),
    )
    # Measured: about 40% of the reference.
    assert value < 0.6 * reference, f"caustic {value:.4f} vs bdpt {reference:.4f}"


def test_sppm_renders_the_caustic(client: Client, caustic_reference: np.ndarray) -> None:
    scene = small(GLOSSY_BOX, CAUSTIC_WIDTH)
    value = caustic_mean(render(client, scene, component("sppm"), 16, 9).pixels)
    reference = caustic_mean(caustic_reference)
    # Measured: 1.6% below bdpt's after 16 passes.
    assert abs(value - reference) < 0.1 * reference, f"caustic {value:.4f} vs bdpt {reference:.4f}"


def refusal(client: Client, transport: scene_pb2.ComponentSpec) -> str:
    """Why a job with ``transport`` is refused at Submit, or else fails."""
    try:
        job_id = client.submit(small(DIFFUSE_BOX, 8), spp=1, seed=0, transport=transport)
    except grpc.RpcError as error:
        assert error.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
        return str(error.details())  # type: ignore[attr-defined]
    status = client.wait(job_id, timeout=30)
    assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
    return status.error


@pytest.mark.parametrize(
    ("transport", "message"),
    [
        (component("photon_map", photons=-1), "photons: -1 is below 0"),
        (component("photon_map", photons=10**10), "photons: 10000000000 is above 50000000"),
        (component("photon_map", caustic_photons=-5), "caustic_photons: -5 is below 0"),
        (component("photon_map", nearest=0), "nearest: 0 is below 1"),
        (component("sppm", photons_per_pass=-1), "photons_per_pass: -1 is below 1"),
        (component("sppm", alpha=1.5), "alpha: 1.5 is above 1"),
        (component("sppm", alpha=0.0), "'alpha' must be in (0, 1)"),
    ],
    ids=[
        "photons",
        "too_many_photons",
        "caustic_photons",
        "nearest",
        "photons_per_pass",
        "alpha",
        "alpha_zero",
    ],
)
def test_bad_properties_are_refused_with_a_clear_error(
    client: Client, transport: scene_pb2.ComponentSpec, message: str
) -> None:
    """At Submit where the declared parameters refuse them, else when the job runs."""
    reason = refusal(client, transport)
    assert message in reason, reason
