"""yarfd's SceneView service: the kernel's view of a running job's scene, for
transports in other processes.

A probe transport asks every question SceneView answers while a job
prepares and reports the answers; they are checked against the scene that
was submitted (areas, densities, emitted radiance, the camera's round trip
from film to scene and back, media). A light tracer written in Python against
the service renders the Cornell box as the C++ light tracer does (block
z-test)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import CORNELL_BOX, REPO
from imagestats import block_z_test
from test_media import SIGMA_A, SIGMA_S, medium, orthographic_scene

from yarf import Client, LocalServer, component, load_scene, rgb
from yarf.v1 import render_pb2, scene_pb2

EXAMPLES = REPO / "components" / "python" / "examples"
PROBE = Path(__file__).resolve().parent / "components" / "scene_probe.py"
NONE = 0xFFFFFFFF
LUMINAIRE_RADIANCE = (18.387, 10.9873, 2.75357)


@pytest.fixture(scope="module")
def transports(tmp_path_factory: pytest.TempPathFactory, server: LocalServer) -> Iterator[str]:
    socket = tmp_path_factory.mktemp("scene_view") / "t.sock"
    targets = [f"{EXAMPLES / 'light.py'}:LightTracer", f"{PROBE}:SceneProbe"]
    with ComponentProcess.python(targets, f"unix:{socket}", "--server", server.address) as process:
        yield process.address


def at(address: str, class_name: str, **values: object) -> scene_pb2.ComponentSpec:
    spec = component(class_name, **values)
    spec.address = address
    return spec


def probe(client: Client, transports: str, scene: scene_pb2.Scene, report: Path) -> dict:
    job_id = client.submit(scene, 1, 1, transport=at(transports, "scene_probe", report=str(report)))
    status = client.wait(job_id, timeout=300)
    assert status.state == render_pb2.SUCCEEDED, status.error
    return json.loads(report.read_text())


@pytest.fixture(scope="module")
def cornell(client: Client, transports: str, tmp_path_factory: pytest.TempPathFactory) -> dict:
    scene = load_scene(CORNELL_BOX)
    scene.film.width, scene.film.height = 40, 30
    return probe(client, transports, scene, tmp_path_factory.mktemp("probe") / "cornell.json")


def test_layout_describes_the_scene_submitted(cornell: dict) -> None:
    layout = cornell["layout"]
    assert (layout["width"], layout["height"]) == (40, 30)
    # The luminaire is shape 0 and the only emitter; nothing else emits.
    assert layout["shape_emitters"][0] == 0
    assert all(e == NONE for e in layout["shape_emitters"][1:])
    assert layout["has_lights"] and not layout["has_environment"]
    assert layout["light_count"] == 1 and layout["emitters"] == 1
    assert layout["media"] == 0 and layout["camera_medium"] == NONE
    assert not any(layout["media_boundaries"])
    assert not layout["camera_has_lens"] and layout["camera_unreachable_reason"] == ""
    assert all(count > 0 for count in layout["primitive_counts"])


def test_triangles_cover_each_shape_area(cornell: dict) -> None:
    np.testing.assert_allclose(cornell["triangle_areas"], cornell["shape_areas"], rtol=1e-4)


def test_light_points_are_uniform_on_the_luminaire(cornell: dict) -> None:
    area = cornell["shape_areas"][0]
    pdf_area = np.array(cornell["light_pdf_area"])
    assert pdf_area[0] == pytest.approx(1 / area, rel=1e-4)
    assert np.all(pdf_area[1:] == 0)
    starts = cornell["light_points"]
    np.testing.assert_allclose(starts["pdf"], 1 / area, rtol=1e-4)
    assert set(starts["flags"]) == {0} and set(starts["emitters"]) == {0}
    assert set(starts["shape_ids"]) == {0}
    positions, normals = np.array(starts["positions"]), np.array(starts["normals"])
    # The luminaire is a horizontal rectangle facing down (float rounding aside).
    assert np.ptp(positions[:, 1]) < 1e-6 * np.abs(positions).max()
    np.testing.assert_allclose(normals, np.tile([0, -1, 0], (len(normals), 1)), atol=1e-5)
    # Gathered into one point, the light is its centroid: the mean of points
    # uniform in its area.
    gathered = cornell["gathered"]
    assert gathered["emitters"] == [0] and gathered["pdf"][0] > 0
    spread = positions.std(axis=0) / np.sqrt(len(positions))
    assert np.all(np.abs(positions.mean(axis=0) - gathered["positions"][0]) <= 4 * spread + 1e-3)


def test_emitters_are_served_as_the_scene_declares_them(cornell: dict) -> None:
    # Along its normal the luminaire's local +z: its radiance.
    for row in cornell["emitter_radiance"]:
        np.testing.assert_allclose(row, LUMINAIRE_RADIANCE, rtol=1e-5)


def test_camera_connections_land_where_the_camera_rays_left(cornell: dict) -> None:
    camera = cornell["camera"]
    assert len(camera["film"]) > 200 and all(camera["connected"])
    np.testing.assert_allclose(camera["raster"], camera["film"], atol=2e-3)
    # A pinhole's importance is its directions' density over the film.
    np.testing.assert_allclose(camera["importance"], camera["direction_pdf"], rtol=1e-3)
    assert all(s > 0 for s in camera["spacing"])
    times = camera["shutter"]
    assert all(0 <= t <= 1 for t in times) and times == sorted(times)


def test_cross_sections_list_every_hit_in_order(cornell: dict) -> None:
    cross = cornell["cross_section"]
    for k, (t, shapes) in enumerate(cross["rays"][:64]):
        assert t == sorted(t)
        if cross["closest_shape"][k] == NONE:
            assert not t
        else:
            assert t[0] == pytest.approx(cross["closest_t"][k], rel=1e-5)
            assert shapes[0] == cross["closest_shape"][k]
    # Straight down through the middle of the box from y = 5000: the ceiling
    # (y = 548.8), the luminaire hanging under it (y = 548.3), the floor (y = 0).
    t, shapes = cross["rays"][64]
    assert shapes == [2, 0, 1], shapes
    np.testing.assert_allclose(t, [5000 - 548.8, 5000 - 548.3, 5000], atol=0.01)


def test_every_ray_from_infinity_starts_on_a_disk_of_one_density(cornell: dict) -> None:
    pdf = np.array(cornell["infinite"]["pdf"])
    assert np.all(pdf > 0) and np.ptp(pdf) <= 1e-6 * pdf.max()


def test_bad_questions_are_refused_with_what_was_wrong(cornell: dict) -> None:
    errors = cornell["errors"]
    assert "INVALID_ARGUMENT" in errors["shape"] and "1000000" in errors["shape"]
    assert "INVALID_ARGUMENT" in errors["direction"] and "direction 0" in errors["direction"]
    assert "lens 0" in errors["lens"] and "[0, 1)" in errors["lens"]
    assert "light 1000000" in errors["light"]


def test_media_and_an_unreachable_camera_are_described(
    client: Client, transports: str, tmp_path: Path
) -> None:
    scene = orthographic_scene()
    medium(scene, "fog", sigma_a=rgb(*SIGMA_A), sigma_s=rgb(*SIGMA_S))
    answers = probe(client, transports, scene, tmp_path / "fog.json")
    layout = answers["layout"]
    assert layout["media"] == 1 and "orthographic" in layout["camera_unreachable_reason"]
    boundary = layout["media_boundaries"].index(True)
    assert layout["interior_media"][boundary] == 0 and layout["exterior_media"][boundary] == NONE
    np.testing.assert_allclose(answers["medium"]["sigma_a"], SIGMA_A, rtol=1e-6)
    np.testing.assert_allclose(answers["medium"]["sigma_s"], SIGMA_S, rtol=1e-6)
    # Homogeneous: one segment per ray, σ_t itself, over the ray's whole length;
    # isotropic: 1/4π both ways.
    fog = answers["medium"]
    assert not fog["emits"] and fog["offsets"] == [0, 1]
    np.testing.assert_allclose(
        fog["segments"][0], [0, 10, *np.add(SIGMA_A, SIGMA_S)], rtol=1e-6, atol=1e-6
    )
    np.testing.assert_allclose(fog["phase"] + fog["phase_pdf"], [1 / (4 * np.pi)] * 2, rtol=1e-5)
    assert not any(answers["camera"]["connected"])


def test_python_light_tracer_renders_the_cornell_box_as_the_cpp_one(
    client: Client, transports: str
) -> None:
    scene = load_scene(CORNELL_BOX)
    scene.film.width = scene.film.height = 32

    def render(spec: scene_pb2.ComponentSpec, seed: int):  # noqa: ANN202
        job_id = client.submit(scene, 64, seed, transport=spec, name=spec.class_name)
        status = client.wait(job_id, timeout=600)
        assert status.state == render_pb2.SUCCEEDED, status.error
        return client.raw(job_id)

    python = render(at(transports, "py_light", max_depth=4), 1)
    cpp = render(component("light", max_depth=4), 2)
    test = block_z_test(
        python.pixels, python.variance, cpp.pixels, cpp.variance, block=4, family_alpha=1e-3
    )
    assert not test.failing.size, f"py_light vs light:\n{test.report()}"
    assert np.allclose(python.pixels.mean(), cpp.pixels.mean(), rtol=0.03)
