"""Rendering with any integrator: the adaptive ones render the same
expected image as mean-sample Monte Carlo (their maps change the variance,
never the mean)."""

from __future__ import annotations

import numpy as np
import pytest

from yarf import Client, RenderResult, component
from yarf.v1 import scene_pb2


def image_mean(result: RenderResult) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel image mean and the variance of that mean."""
    count = result.pixels.shape[0] * result.pixels.shape[1]
    mean = result.pixels.astype(np.float64).mean(axis=(0, 1))
    return mean, result.variance.astype(np.float64).sum(axis=(0, 1)) / count**2


@pytest.mark.parametrize("integrator", ["vegas", "vegas_plus"])
def test_adaptive_integrators_render_the_mean_sample_image_in_expectation(
    client: Client, cornell_box: scene_pb2.Scene, integrator: str
) -> None:
    independent = scene_pb2.ComponentSpec(class_name="independent")
    reference = client.render(cornell_box, spp=64, seed=11, sampler=independent)
    adaptive = client.render(
        cornell_box,
        spp=32,
        seed=12,
        sampler=independent,
        integrator=scene_pb2.ComponentSpec(class_name=integrator),
    )
    assert np.isfinite(adaptive.pixels).all()
    (m_ref, v_ref), (m_ada, v_ada) = image_mean(reference), image_mean(adaptive)
    z = (m_ada - m_ref) / np.sqrt(v_ref + v_ada)
    assert (np.abs(z) < 5).all(), f"{integrator}: image means {m_ada} vs {m_ref}, z = {z}"
    assert (np.abs(m_ada - m_ref) < 0.01 * m_ref).all()


def test_vegas_renders_the_same_image_for_the_same_seed(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    vegas = scene_pb2.ComponentSpec(class_name="vegas")
    first = client.render(cornell_box, spp=8, seed=3, integrator=vegas)
    second = client.render(cornell_box, spp=8, seed=3, integrator=vegas)
    assert first.pixels.tobytes() == second.pixels.tobytes()


@pytest.mark.parametrize("transport", ["path", "light"])
def test_several_samples_per_pass_render_the_same_samples(
    client: Client, cornell_box: scene_pb2.Scene, transport: str
) -> None:
    # Batches of 4 samples per pixel draw the same sample indices of the same
    # per-pixel sequences as 4 passes of one: the same image up to the order
    # of summation, camera samples and splats alike.
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = 32
    images = [
        client.render(
            scene,
            spp=8,
            seed=3,
            transport=scene_pb2.ComponentSpec(class_name=transport),
            integrator=component("mean_sample", samples_per_pass=per_pass),
        ).pixels
        for per_pass in (1, 4)
    ]
    assert images[0].mean() > 0
    np.testing.assert_allclose(images[1], images[0], rtol=1e-4, atol=1e-6)
