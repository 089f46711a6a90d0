"""Media in other processes (Remote<Medium>), end to end.

- A Python homogeneous medium, out of process, renders as yarfd's C++
  ``homogeneous`` with the same coefficients under volpath: through the
  fog with an anisotropic, emitting medium, and under it with shadow rays.
- An exponential atmosphere in Python, whose majorant is its maximum
  along each ray (so tracking meets null collisions), attenuates light
  crossing a slab vertically by the analytic exp(-σ_t·H·(1 - e^{-h/H})).
- A medium process that dies, hangs or answers garbage fails its job with
  an error naming it and the call; yarfd goes on serving.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from imagestats import assert_renders_agree
from test_media import SIGMA_A, SIGMA_S, box, lit_floor_scene, orthographic_scene

from yarf import Client, RenderResult, component, rgb
from yarf.v1 import render_pb2, scene_pb2

EXAMPLES = Path(__file__).resolve().parents[1] / "components" / "python" / "examples"
FAULTY = Path(__file__).resolve().parent / "components" / "faulty_media.py"
HOMOGENEOUS = f"{EXAMPLES / 'homogeneous.py'}:Homogeneous"
EXPONENTIAL_FOG = f"{EXAMPLES / 'exponential_fog.py'}:ExponentialFog"


@pytest.fixture
def unix_address(tmp_path: Path) -> str:
    return f"unix:{tmp_path / 'medium.sock'}"


def set_medium(
    scene: scene_pb2.Scene, class_name: str, address: str = "", **values: object
) -> None:
    """The scene's medium "fog": ``class_name`` (at ``address``) with ``values``."""
    del scene.media[:]
    spec = component(class_name, **values)
    spec.address = address
    scene.media.add(name="fog", medium=spec)


def channel_means(result: RenderResult) -> tuple[np.ndarray, np.ndarray]:
    """The image's mean per channel and its standard error."""
    mean = result.pixels.reshape(-1, 3).mean(axis=0)
    noise = np.sqrt(result.variance.reshape(-1, 3).mean(axis=0) / result.pixels[..., 0].size)
    return mean, noise


# (scene, medium properties, spp): the camera looks through a slab of
# anisotropic fog that emits, lit by an area light behind it; and a floor
# lit through a slab by a directional light, which only shadow rays and
# light scattered up from the floor cross.
AGREEMENT = {
    "through anisotropic emitting fog": (
        orthographic_scene,
        {
            "sigma_a": rgb(*SIGMA_A),
            "sigma_s": rgb(*SIGMA_S),
            "g": 0.6,
            "emission": rgb(0.4, 0.1, 0.8),
        },
        256,
    ),
    "shadow rays through isotropic fog": (
        lit_floor_scene,
        {"sigma_a": rgb(*SIGMA_A), "sigma_s": rgb(*SIGMA_S)},
        256,
    ),
}


@pytest.mark.parametrize("case", list(AGREEMENT))
def test_a_python_homogeneous_medium_renders_as_the_cpp_one(
    client: Client, unix_address: str, case: str
) -> None:
    make_scene, values, spp = AGREEMENT[case]
    scene = make_scene(16)
    volpath = component("volpath")
    set_medium(scene, "homogeneous", **values)
    reference = client.render(scene, spp=spp, seed=1, transport=volpath, timeout=600)
    with ComponentProcess.python([HOMOGENEOUS], unix_address) as process:
        set_medium(scene, "py_homogeneous", process.address, **values)
        remote = client.render(scene, spp=spp, seed=2, transport=volpath, timeout=600)
    assert np.isfinite(remote.pixels).all()
    assert_renders_agree(remote, reference, f"py_homogeneous vs homogeneous, {case}")
    # And over the whole image, per channel, within 5 standard errors.
    remote_mean, remote_noise = channel_means(remote)
    reference_mean, reference_noise = channel_means(reference)
    assert np.all(
        np.abs(remote_mean - reference_mean) < 5 * np.hypot(remote_noise, reference_noise) + 1e-5
    ), (remote_mean, reference_mean)


SCALE_HEIGHT = 0.7
SLAB_HEIGHT = 2.0


def test_an_exponential_atmosphere_attenuates_a_vertical_ray_by_its_optical_depth(
    client: Client, unix_address: str
) -> None:
    """An orthographic camera looks straight down through a slab z ∈ [0, h]
    of py_exponential_fog at a unit emitter below; max_depth 1 counts what
    is seen directly, so each pixel reads exp(-∫σ_t dz) =
    exp(-σ_t(0)·H·(1 - e^{-h/H})) per channel. The majorant, σ_t(0), is
    e^{h/H} ≈ 17 times the fog's extinction at the slab's top: most tentative
    collisions there are null."""
    scene = orthographic_scene()
    (slab,) = (shape for shape in scene.shapes if shape.name == "slab")
    slab.mesh.Clear()
    box(slab, (-5, -5, 0), (5, 5, SLAB_HEIGHT))
    with ComponentProcess.python([EXPONENTIAL_FOG], unix_address) as process:
        set_medium(
            scene,
            "py_exponential_fog",
            process.address,
            sigma_a=rgb(*SIGMA_A),
            sigma_s=rgb(*SIGMA_S),
            scale_height=SCALE_HEIGHT,
        )
        # 1024 spp over 64 pixels: a standard error under 0.002 per channel,
        # against transmittances some 0.35 above the homogeneous slab's.
        result = client.render(
            scene, spp=1024, seed=1, transport=component("volpath", max_depth=1), timeout=600
        )
    sigma_t = np.array(SIGMA_A) + np.array(SIGMA_S)
    optical_depth = sigma_t * SCALE_HEIGHT * (1 - np.exp(-SLAB_HEIGHT / SCALE_HEIGHT))
    expected = np.exp(-optical_depth)
    mean, noise = channel_means(result)
    assert np.all(np.abs(mean - expected) < 5 * noise + 1e-4), (mean, expected, noise)
    # Not the homogeneous slab of the same height: the fall-off is seen.
    assert np.all(
        mean[sigma_t > 0] > np.exp(-SLAB_HEIGHT * sigma_t[sigma_t > 0]) + 10 * noise.max()
    )


# Fault isolation: (class in faulty_media.py, its class name, submit
# options, the call that fails, what the error must say).
FAULTS = {
    "crash": ("Crashing", "crashing_medium", {}, "Coefficients", ["UNAVAILABLE"]),
    "hang": (
        "Hanging",
        "hanging_medium",
        {"component_timeout": 1.0},
        "Coefficients",
        ["DEADLINE_EXCEEDED"],
    ),
    "wrong length": ("WrongLength", "short_medium", {}, "Coefficients", ["shape", "queries"]),
    "nan": ("NotANumber", "nan_medium", {}, "Coefficients", ["non-finite", "sigma_s"]),
    "negative": ("NegativeAbsorption", "negative_medium", {}, "Coefficients", ["negative sigma_a"]),
    "segments past the ray": (
        "SegmentsPastTheRay",
        "overlong_medium",
        {},
        "Majorants",
        ["the interval", "within [0, "],
    ),
    "garbage offsets": (
        "GarbageOffsets",
        "garbage_offsets_medium",
        {},
        "Majorants",
        ["offsets of shape"],
    ),
}


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_faulty_medium_fails_its_job_naming_itself_and_the_call(
    fault: str,
    client: Client,
    unix_address: str,
    assert_still_renders: Callable[[], None],
) -> None:
    target, class_name, options, call, words = FAULTS[fault]
    scene = orthographic_scene()
    with ComponentProcess.python([f"{FAULTY}:{target}"], unix_address) as process:
        set_medium(scene, class_name, process.address, sigma_a=rgb(*SIGMA_A), sigma_s=rgb(*SIGMA_S))
        started = time.monotonic()
        job_id = client.submit(
            scene, 16, 1, name=f"faulty medium: {fault}", transport=component("volpath"), **options
        )
        status = client.wait(job_id, timeout=120)
        assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
        assert f"component '{class_name}' at {process.address}" in status.error, status.error
        assert f"Medium.{call}" in status.error, status.error
        for word in words:
            assert word in status.error, status.error
        assert time.monotonic() - started < 30
    assert_still_renders()


def test_a_medium_process_that_is_gone_before_the_job_fails_it_clearly(
    client: Client, unix_address: str, assert_still_renders: Callable[[], None]
) -> None:
    scene = orthographic_scene()
    with ComponentProcess.python([HOMOGENEOUS], unix_address) as process:
        address = process.address
    set_medium(scene, "py_homogeneous", address, sigma_s=rgb(1.0))
    job_id = client.submit(scene, 4, 1, name="medium gone", transport=component("volpath"))
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.FAILED
    assert f"component 'py_homogeneous' at {address}" in status.error, status.error
    assert "medium 'fog'" in status.error, status.error
    assert_still_renders()
