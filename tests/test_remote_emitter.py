"""A light written in Python: the Cornell box lit by py_area_light, an
Emitter in another process, renders as the C++ diffuse_area lights it,
both when paths find the light (path tracing: Radiance) and when they
start at it (light tracing: SampleDirection); the path tracers call it
once or twice a bounce however many materials their paths meet; a light
its process refuses to make fails its job with an error naming it and
the property."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import CORNELL_BOX, REPO
from imagestats import assert_renders_agree

from yarf import Client, load_scene
from yarf.v1 import render_pb2, scene_pb2

EXAMPLES = REPO / "components" / "python" / "examples"
COMPONENTS = REPO / "tests" / "components"
SIZE = 32
SPP = 64


def cornell_box(transport: str, address: str = "") -> scene_pb2.Scene:
    """The Cornell box at SIZE²; with an address, its light is py_area_light there."""
    scene = load_scene(CORNELL_BOX)
    scene.film.width = scene.film.height = SIZE
    scene.transport.class_name = transport
    for shape in scene.shapes:
        if shape.HasField("emitter") and address:
            shape.emitter.class_name = "py_area_light"
            shape.emitter.address = address
    return scene


def rendered(client: Client, scene: scene_pb2.Scene, seed: int) -> render_pb2.JobStatus:
    return client.wait(client.submit(scene, SPP, seed, name="remote light"), timeout=300)


@pytest.fixture
def python_light(tmp_path: Path) -> Iterator[ComponentProcess]:
    with ComponentProcess.python(
        [f"{EXAMPLES / 'area_light.py'}:AreaLight"], f"unix:{tmp_path / 'light.sock'}"
    ) as process:
        yield process


@pytest.mark.parametrize("transport", ["path", "light"])
def test_a_python_light_renders_the_cornell_box_as_the_cpp_one(
    client: Client, python_light: ComponentProcess, transport: str
) -> None:
    status = rendered(client, cornell_box(transport, python_light.address), seed=1)
    assert status.state == render_pb2.SUCCEEDED, status.error
    remote = client.raw(status.job_id)
    reference = client.raw(rendered(client, cornell_box(transport), seed=2).job_id)
    assert_renders_agree(remote, reference, f"py_area_light vs diffuse_area ({transport})")
    assert np.allclose(remote.pixels.mean(), reference.pixels.mean(), rtol=0.03)


def test_a_python_light_gives_the_same_path_traced_image_for_the_same_seed(
    client: Client, python_light: ComponentProcess
) -> None:
    """Radiance is a constant, and the path tracer's sample points do not
    depend on the light's process: the images agree to float rounding."""
    remote = rendered(client, cornell_box("path", python_light.address), seed=3)
    local = rendered(client, cornell_box("path"), seed=3)
    np.testing.assert_allclose(
        client.raw(remote.job_id).pixels, client.raw(local.job_id).pixels, rtol=1e-5, atol=1e-6
    )


@pytest.mark.parametrize("transport", ["path", "volpath"])
def test_path_tracers_call_a_python_light_at_most_twice_a_bounce(
    client: Client, tmp_path: Path, transport: str
) -> None:
    """Once for the paths that hit the light and once for the light samples
    of every material's vertices together: a call per bounce, not per
    material (the box has five). The film is one batch: 32² pixels at 4
    samples, one tile of a job that calls another process."""
    log = tmp_path / "calls.txt"
    max_depth = 4
    with ComponentProcess.python(
        [f"{COMPONENTS / 'counting_light.py'}:CountingLight"], f"unix:{tmp_path / 'light.sock'}"
    ) as process:
        scene = cornell_box(transport, process.address)
        for shape in scene.shapes:
            if shape.HasField("emitter"):
                shape.emitter.class_name = "py_counting_light"
                shape.emitter.properties.values["log"].string_value = str(log)
        scene.transport.properties.values["max_depth"].int_value = max_depth
        assert len({shape.material for shape in scene.shapes}) >= 4
        status = client.wait(client.submit(scene, 4, 1, name="counted light"), timeout=300)
    assert status.state == render_pb2.SUCCEEDED, status.error
    rows = [int(line) for line in log.read_text().split()]
    # One call estimates the light's power as the scene is built (lights
    # are chosen by power); the last bounce only gathers what its rays
    # hit, with no light samples.
    assert 0 < len(rows) <= 1 + 2 * max_depth - 1, rows


def test_a_light_with_a_negative_radiance_fails_its_job_naming_it(
    client: Client, python_light: ComponentProcess
) -> None:
    scene = cornell_box("path", python_light.address)
    for shape in scene.shapes:
        if shape.HasField("emitter"):
            shape.emitter.properties.values["radiance"].rgb_value.r = -1
    status = rendered(client, scene, seed=1)
    assert status.state == render_pb2.FAILED
    assert "py_area_light" in status.error and "radiance" in status.error, status.error
