"""yarf's Cornell box agrees with Mitsuba 3's within Monte Carlo noise.

Mitsuba renders ../shared/scenes/mitsuba-cbox/cbox-rgb.xml (scalar_rgb,
independent sampler) with two seeds: their mean is the reference and their
difference estimates its variance. yarf renders scenes/cornell-box/scene.json,
the same scene, and reports its own variance. Means of 16×16-pixel blocks
must pass a z-test with a Šidák-corrected threshold, and the whole image's
mean must agree within 1%.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from conftest import SHARED
from imagestats import block_z_test

from yarf import Client, RenderResult
from yarf.v1 import scene_pb2

MITSUBA_SCENE = SHARED / "scenes" / "mitsuba-cbox" / "cbox-rgb.xml"
SIZE = 256
MAX_DEPTH = 6
MITSUBA_SPP = 32
MITSUBA_SEEDS = (1, 2)
YARF_SPP = 64
BLOCK = 16
# Family-wise rate of false alarms over all blocks and channels.
FAMILY_ALPHA = 1e-3
MEAN_TOLERANCE = 0.01


def render_mitsuba() -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's image (mean of two seeds) and the variance of each pixel of it."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    assert MITSUBA_SCENE.exists(), f"{MITSUBA_SCENE} is missing (shared/ beside the repository)"
    scene = mi.load_file(str(MITSUBA_SCENE), res=SIZE, max_depth=MAX_DEPTH)
    first, second = (
        np.array(mi.render(scene, spp=MITSUBA_SPP, seed=seed), dtype=np.float64)[..., :3]
        for seed in MITSUBA_SEEDS
    )
    # Two independent estimates x1, x2 of each pixel: their mean has variance
    # σ²/2, and (x1 − x2)²/4 estimates it without bias.
    return (first + second) / 2, (first - second) ** 2 / 4


@pytest.fixture(scope="module")
def mitsuba_reference() -> tuple[np.ndarray, np.ndarray]:
    start = time.monotonic()
    reference = render_mitsuba()
    print(f"Mitsuba: 2 × {MITSUBA_SPP} spp in {time.monotonic() - start:.1f} s")
    return reference


@pytest.fixture(scope="module")
def yarf_render(client: Client, cornell_box: scene_pb2.Scene) -> RenderResult:
    return client.render(cornell_box, spp=YARF_SPP, seed=7, timeout=120)


def test_cornell_box_blocks_match_mitsuba_within_noise(
    yarf_render: RenderResult, mitsuba_reference: tuple[np.ndarray, np.ndarray]
) -> None:
    reference, reference_variance = mitsuba_reference
    pixels = yarf_render.pixels.astype(np.float64)
    variance = yarf_render.variance.astype(np.float64)
    assert pixels.shape == reference.shape == (SIZE, SIZE, 3)

    test = block_z_test(
        pixels, variance, reference, reference_variance, block=BLOCK, family_alpha=FAMILY_ALPHA
    )
    failing = test.failing
    assert len(failing) == 0, (
        f"{len(failing)} of {test.z.size} block means differ from Mitsuba's beyond "
        f"|z| < {test.threshold:.2f} (Šidák, family α = {FAMILY_ALPHA}); worst:\n{test.report()}"
    )


def test_cornell_box_image_mean_matches_mitsuba_within_one_percent(
    yarf_render: RenderResult, mitsuba_reference: tuple[np.ndarray, np.ndarray]
) -> None:
    reference, _ = mitsuba_reference
    yarf_mean = yarf_render.pixels.astype(np.float64).mean(axis=(0, 1))
    mitsuba_mean = reference.mean(axis=(0, 1))
    relative = np.abs(yarf_mean - mitsuba_mean) / mitsuba_mean
    assert (relative < MEAN_TOLERANCE).all(), (
        f"image mean (RGB): yarf {yarf_mean}, Mitsuba {mitsuba_mean}, "
        f"relative difference {relative}"
    )
