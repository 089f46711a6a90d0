"""A numerical integrator in another process renders images: yarfd lends
it the job's transport over each tile of the film as a Function (one
output per pixel and channel) and writes each pixel's estimate and its
error to the film. The Python VEGAS renders the Cornell box as yarfd's
mean_sample does; light paths, which splat, are refused; a component that
dies or hangs in the middle of a render fails the job, and yarfd goes on."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import REPO, small_scene
from imagestats import assert_renders_agree

from yarf import Client, component
from yarf.v1 import component_pb2, render_pb2, scene_pb2

VEGAS = REPO / "components" / "python" / "examples" / "vegas.py"
FAULTY = Path(__file__).resolve().parent / "components" / "faulty_math.py"
INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")
SIZE = 32


@pytest.fixture(scope="module")
def vegas(client: Client, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """py_vegas, registered with the session's yarfd."""
    socket = tmp_path_factory.mktemp("vegas") / "vegas.sock"
    with ComponentProcess.python([f"{VEGAS}:Vegas"], f"unix:{socket}") as process:
        request = component_pb2.RegisterRequest(address=process.address, lease_seconds=3600)
        client.registry.Register(request)
        yield process.address
        client.registry.Unregister(component_pb2.UnregisterRequest(address=process.address))


def small_box(cornell_box: scene_pb2.Scene) -> scene_pb2.Scene:
    scene = scene_pb2.Scene()
    scene.CopyFrom(cornell_box)
    scene.film.width = scene.film.height = SIZE
    return scene


def test_the_python_vegas_renders_the_cornell_box_as_mean_sample_does(
    client: Client, vegas: str, cornell_box: scene_pb2.Scene
) -> None:
    scene = small_box(cornell_box)
    reference = client.render(scene, spp=256, seed=1, sampler=INDEPENDENT)
    # 64 samples per pixel: 16384 points a 16 × 16 tile, four VEGAS
    # iterations, two to train its map and two averaged.
    remote = client.render(
        scene,
        spp=64,
        seed=2,
        sampler=INDEPENDENT,
        integrator=scene_pb2.ComponentSpec(class_name="py_vegas"),
        timeout=120,
    )
    assert remote.status.state == render_pb2.SUCCEEDED
    assert remote.status.samples_done == 64
    assert np.isfinite(remote.pixels).all() and remote.pixels.mean() > 0.05
    # Each pixel's variance is the integrator's error: none is 0 where the
    # pixel sees light.
    assert (remote.variance[remote.pixels > 1e-4] > 0).all()
    assert_renders_agree(remote, reference, "py_vegas against mean_sample")
    # The whole image's mean, within about 2% here, is a finer test of a bias.
    pixels = SIZE * SIZE
    difference = remote.pixels.mean(axis=(0, 1)) - reference.pixels.mean(axis=(0, 1))
    error = np.sqrt(remote.variance.sum(axis=(0, 1)) + reference.variance.sum(axis=(0, 1)))
    z = difference / (error / pixels)
    assert (np.abs(z) < 5).all(), f"image means differ: z = {z}"


def test_a_light_tracer_through_a_remote_integrator_is_refused(client: Client, vegas: str) -> None:
    job = client.submit(
        small_scene(),
        4,
        1,
        transport=scene_pb2.ComponentSpec(class_name="light"),
        integrator=scene_pb2.ComponentSpec(class_name="py_vegas"),
        sampler=INDEPENDENT,
    )
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED
    assert f"component 'py_vegas' at {vegas}" in status.error, status.error
    assert "transport 'light' splats its contributions" in status.error, status.error
    assert "cannot integrate pixel by pixel" in status.error, status.error


def test_a_remote_integrator_renders_only_with_samplers_it_can_name(
    client: Client, vegas: str
) -> None:
    # The rule of Integrate: yarfd's sobol cannot be lent to another process.
    spec = scene_pb2.ComponentSpec(class_name="py_vegas")
    job = client.submit(small_scene(), 4, 1, integrator=spec, sampler=component("sobol"))
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED
    assert "cannot draw its points from sampler 'sobol'" in status.error, status.error


# faulty_integrator "exit" answers the first tile and exits in the second;
# "hang" outlasts the job's one-second deadline in the first.
FAULTS = [
    ("exit", "Integrator.Integrate of pixels [16, 32) x [0, 16) failed: UNAVAILABLE"),
    ("hang", "Integrator.Integrate of pixels [0, 16) x [0, 16) failed: DEADLINE_EXCEEDED"),
]


@pytest.mark.parametrize(("fault", "words"), FAULTS)
def test_a_component_that_dies_or_hangs_mid_render_fails_the_job_and_yarfd_goes_on(
    client: Client, cornell_box: scene_pb2.Scene, tmp_path: Path, fault: str, words: str
) -> None:
    with ComponentProcess.python(
        [f"{FAULTY}:FaultyIntegrator"], f"unix:{tmp_path / 'faulty.sock'}"
    ) as process:
        request = component_pb2.RegisterRequest(address=process.address, lease_seconds=3600)
        client.registry.Register(request)
        try:
            job = client.submit(
                small_box(cornell_box),
                2,
                1,
                sampler=INDEPENDENT,
                integrator=component("faulty_integrator", fault=fault),
                component_timeout=1.0,
            )
            status = client.wait(job, timeout=60)
            assert process.is_running() == (fault == "hang")
        finally:
            client.registry.Unregister(component_pb2.UnregisterRequest(address=process.address))
            process.kill()  # a hanging call would hold up a gentle stop
    assert status.state == render_pb2.FAILED
    assert f"component 'faulty_integrator' at {process.address}: {words}" in status.error, (
        status.error
    )
    again = client.render(small_scene(), spp=2, seed=1)
    assert again.status.state == render_pb2.SUCCEEDED and again.pixels.mean() > 0
