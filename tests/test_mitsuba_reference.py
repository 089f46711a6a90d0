"""yarf's Cornell box agrees with Mitsuba 3's within Monte Carlo noise.

Mitsuba renders ../shared/scenes/mitsuba-cbox/cbox-rgb.xml (scalar_rgb,
independent sampler, max_depth 6) at 64×64 pixels with sixteen seeds: their
mean is the reference and their spread its variance (conftest's
mitsuba_cbox_reference, shared with the importer's test). yarf renders
scenes/cornell-box/scene.json, the same scene, at that size and reports its
own variance. Means of 4×4-pixel blocks (256 blocks, each averaging some
16 000 samples of either renderer) must pass a z-test with a
Šidák-corrected threshold, and the whole image's mean must agree within 1%.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MITSUBA_CBOX_SIZE
from imagestats import block_z_test

from yarf import Client, RenderResult
from yarf.v1 import scene_pb2

SIZE = MITSUBA_CBOX_SIZE
YARF_SPP = 1024
BLOCK = 4
# Family-wise rate of false alarms over all blocks and channels.
FAMILY_ALPHA = 1e-4
MEAN_TOLERANCE = 0.01


@pytest.fixture(scope="module")
def yarf_render(client: Client, cornell_box: scene_pb2.Scene) -> RenderResult:
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = SIZE
    return client.render(scene, spp=YARF_SPP, seed=7, timeout=120)


def test_cornell_box_blocks_match_mitsuba_within_noise(
    yarf_render: RenderResult, mitsuba_cbox_reference: tuple[np.ndarray, np.ndarray]
) -> None:
    reference, reference_variance = mitsuba_cbox_reference
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
    yarf_render: RenderResult, mitsuba_cbox_reference: tuple[np.ndarray, np.ndarray]
) -> None:
    reference, _ = mitsuba_cbox_reference
    yarf_mean = yarf_render.pixels.astype(np.float64).mean(axis=(0, 1))
    mitsuba_mean = reference.mean(axis=(0, 1))
    relative = np.abs(yarf_mean - mitsuba_mean) / mitsuba_mean
    assert (relative < MEAN_TOLERANCE).all(), (
        f"image mean (RGB): yarf {yarf_mean}, Mitsuba {mitsuba_mean}, "
        f"relative difference {relative}"
    )
