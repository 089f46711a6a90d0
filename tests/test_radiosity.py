"""Progressive refinement radiosity: energy balance, convergence, refusals.

The radiosity transport solves in Prepare and, with ``report`` set,
prints one line of energy totals to the server's log: emitted, absorbed
(by the shots' bookkeeping and again from the final radiosities), escaped
(shot power that no element received) and still unshot, each RGB in W.
Its images are compared with the path tracer's through means of 8×8-pixel
blocks: flat or Gouraud shaded patches cannot match a path tracer pixel
for pixel near edges and shadow boundaries, but their block means must
approach it as the mesh is refined.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import small_scene
from imagestats import block_means

from yarf import Client, LocalServer, component, properties, rgb
from yarf.v1 import render_pb2, scene_pb2

WIDTH = 48
BLOCK = 8
REFERENCE_SPP = 1024
REPORT = re.compile(r"^radiosity: (.*)$", re.MULTILINE)


def closed(scene: scene_pb2.Scene) -> scene_pb2.Scene:
    """The Cornell box with a white wall over its open front (z = 0)."""
    result = scene_pb2.Scene()
    result.CopyFrom(scene)
    front = result.shapes.add(name="front", material="white")
    front.mesh.positions.extend([-10, -10, 0, 570, -10, 0, 570, 560, 0, -10, 560, 0])
    front.mesh.indices.extend([0, 1, 2, 0, 2, 3])
    return result


def radiosity(**props: object) -> scene_pb2.ComponentSpec:
    return component("radiosity", **props)


def last_report(server: LocalServer) -> dict[str, np.ndarray]:
    """The totals of the last solve: each key of the report line and its numbers."""
    lines = REPORT.findall(server.log)
    assert lines, "no radiosity report in the server's log"
    totals: dict[str, list[float]] = {}
    key = ""
    for token in lines[-1].split():
        if re.fullmatch(r"[a-z_]+", token):
            key = token
            totals[key] = []
        else:
            totals[key].append(float(token))
    return {name: np.array(values) for name, values in totals.items()}


def solve(
    client: Client, server: LocalServer, scene: scene_pb2.Scene, **props: object
) -> dict[str, np.ndarray]:
    client.render(scene, spp=1, seed=1, transport=radiosity(report=True, **props), timeout=120)
    return last_report(server)


def block_error(image: np.ndarray, reference: np.ndarray) -> float:
    """Mean over 8×8 blocks of |Δ| summed over channels, relative to the reference's sum."""
    blocks, reference_blocks = block_means(image, BLOCK), block_means(reference, BLOCK)
    return float(
        (np.abs(blocks - reference_blocks).sum(axis=2) / reference_blocks.sum(axis=2)).mean()
    )


@pytest.fixture(scope="module")
def scene(cornell_box: scene_pb2.Scene) -> scene_pb2.Scene:
    small = scene_pb2.Scene()
    small.CopyFrom(cornell_box)
    small.film.width = small.film.height = WIDTH
    return small


@pytest.fixture(scope="module")
def reference(client: Client, scene: scene_pb2.Scene) -> np.ndarray:
    result = client.render(
        scene, spp=REFERENCE_SPP, seed=1, transport=component("path"), timeout=300
    )
    return result.pixels


def test_energy_is_balanced_in_the_open_cornell_box(
    client: Client, server: LocalServer, scene: scene_pb2.Scene
) -> None:
    totals = solve(client, server, scene, subdivision=2)
    emitted, absorbed, escaped = totals["emitted"], totals["absorbed"], totals["escaped"]
    assert totals["unshot"].sum() <= 1e-3 * emitted.sum()
    np.testing.assert_allclose(absorbed + escaped, emitted, rtol=0.01)
    # The bookkeeping of the shots agrees with the radiosities they left.
    np.testing.assert_allclose(totals["absorbed_by_solution"], absorbed, rtol=0.005)
    # A third or so of the light leaves through the open front.
    assert 0.2 < escaped.sum() / emitted.sum() < 0.5


def test_form_factors_of_a_closed_box_sum_to_nearly_one(
    client: Client, server: LocalServer, scene: scene_pb2.Scene
) -> None:
    """Closed, the box lets nothing out: what escapes is the form factors' shortfall."""
    totals = solve(client, server, closed(scene), subdivision=2)
    emitted, absorbed, escaped = totals["emitted"], totals["absorbed"], totals["escaped"]
    np.testing.assert_allclose(absorbed + escaped, emitted, rtol=0.01)
    assert escaped.sum() < 0.05 * emitted.sum(), f"escaped {escaped} of {emitted}"


def test_error_falls_as_the_mesh_is_refined(
    client: Client, scene: scene_pb2.Scene, reference: np.ndarray
) -> None:
    """Block errors fall with each level of subdivision (measured 0.146, 0.069, 0.029)."""
    errors, means = [], []
    for level in (1, 2, 3):
        image = client.render(
            scene, spp=4, seed=1, transport=radiosity(subdivision=level), timeout=120
        ).pixels
        errors.append(block_error(image, reference))
        means.append(float(image.mean()))
    assert errors[0] > errors[1] > errors[2], f"block errors by level: {errors}"
    assert errors[2] < 0.05, f"block errors by level: {errors}"
    assert abs(means[2] / reference.mean() - 1) < 0.02, f"means {means} vs {reference.mean()}"


def test_final_gather_is_closer_to_the_path_tracer(
    client: Client, scene: scene_pb2.Scene, reference: np.ndarray
) -> None:
    """At level 2, gathering at the visible points (measured 0.028 against 0.069)."""
    plain = client.render(scene, spp=4, seed=1, transport=radiosity(subdivision=2), timeout=120)
    gathered = client.render(
        scene, spp=64, seed=1, transport=radiosity(subdivision=2, final_gather=True), timeout=120
    )
    plain_error = block_error(plain.pixels, reference)
    gathered_error = block_error(gathered.pixels, reference)
    assert gathered_error < 0.7 * plain_error and gathered_error < 0.045, (
        f"block error {gathered_error:.4f} with final gather, {plain_error:.4f} without"
    )


def test_ambient_term_stands_in_for_unshot_light(
    client: Client, scene: scene_pb2.Scene, reference: np.ndarray
) -> None:
    """Stopped after 20 shots, the image is nearer the answer with the ambient term."""
    early = {
        ambient: client.render(
            scene,
            spp=1,
            seed=1,
            transport=radiosity(subdivision=3, max_shots=20, ambient=ambient),
            timeout=120,
        ).pixels.mean()
        for ambient in (True, False)
    }
    target = reference.mean()
    assert abs(early[True] - target) < 0.6 * abs(early[False] - target), (
        f"means {early} vs {target}"
    )


def failure(client: Client, scene: scene_pb2.Scene) -> str:
    job_id = client.submit(scene, spp=1, seed=1, transport=radiosity())
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
    return str(status.error)


def test_a_sphere_is_refused(client: Client) -> None:
    assert "is a sphere" in failure(client, small_scene())


def test_a_specular_material_is_refused(client: Client, scene: scene_pb2.Scene) -> None:
    glassy = scene_pb2.Scene()
    glassy.CopyFrom(scene)
    glassy.materials.add(name="glass", class_name="dielectric", properties=properties())
    glassy.shapes[-1].material = "glass"
    assert "not diffuse" in failure(client, glassy)


def test_a_point_light_is_refused(client: Client, scene: scene_pb2.Scene) -> None:
    lit = scene_pb2.Scene()
    lit.CopyFrom(scene)
    lit.lights.add(name="bulb", emitter=component("point", intensity=rgb(1.0)))
    assert "point, spot, directional and environment lights are not supported" in failure(
        client, lit
    )
