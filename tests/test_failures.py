"""Untrusted input gets a clear error, and the server goes on rendering.

Malformed scenes and absurd options are rejected by Submit (INVALID_ARGUMENT);
problems met while building the scene fail the job with a message; file
references never leave their folder; a broken plugin is reported, not fatal;
a cancelled job stops promptly without disturbing the others.
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import grpc
import pytest
from conftest import small_scene
from google.protobuf import json_format

from yarf import Client, LocalServer, SceneError, load_scene
from yarf.v1 import render_pb2, scene_pb2

StillRenders = Callable[[], None]


def rejection_or_failure(client: Client, scene: scene_pb2.Scene) -> str:
    """The error of a scene that must not render: Submit's, or the failed job's."""
    try:
        job_id = client.submit(scene, spp=1, seed=0)
    except grpc.RpcError as error:
        assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
        return str(error.details())
    status = client.wait(job_id, timeout=30)
    assert status.state == render_pb2.FAILED, (
        f"expected the job to fail, it ended {render_pb2.JobState.Name(status.state)}"
    )
    return str(status.error)


def submit_rejection(client: Client, scene: scene_pb2.Scene, spp: int = 1) -> grpc.RpcError:
    with pytest.raises(grpc.RpcError) as caught:
        client.submit(scene, spp=spp, seed=0)
    error = caught.value
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    return error


def test_shape_without_material_is_rejected_naming_it(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    orphan = scene.shapes.add(name="orphan")
    orphan.sphere.radius = 0.1
    details = str(submit_rejection(client, scene).details())
    assert "material" in details.lower() and "orphan" in details, details
    assert_still_renders()


def test_mesh_with_out_of_range_indices_is_an_error_naming_the_mesh(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    broken = scene.shapes.add(name="bad_indices", material="grey")
    broken.mesh.positions.extend([0, 0, 0, 1, 0, 0, 0, 1, 0])
    broken.mesh.indices.extend([0, 1, 7])
    message = rejection_or_failure(client, scene)
    assert "bad_indices" in message, message
    assert_still_renders()


def test_unknown_material_class_is_an_error_naming_the_class(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    scene.materials[0].class_name = "no_such_surface_model"
    message = rejection_or_failure(client, scene)
    assert "no_such_surface_model" in message, message
    assert_still_renders()


@pytest.mark.parametrize(
    ("misspell", "where", "meant"),
    [
        (
            lambda s: setattr(s.materials[0], "class_name", "lambertain"),
            "scene.materials[0] ('grey')",
            "lambertian",
        ),
        (
            lambda s: setattr(s.shapes[0].emitter, "class_name", "difuse_area"),
            "scene.shapes[0] ('light').emitter",
            "diffuse_area",
        ),
        (lambda s: setattr(s.transport, "class_name", "bpdt"), "scene.transport", "bdpt"),
        (lambda s: setattr(s.integrator, "class_name", "vegass"), "scene.integrator", "vegas"),
    ],
    ids=["material", "emitter", "transport", "integrator"],
)
def test_a_misspelt_class_is_refused_at_submit_naming_where_and_the_nearest_class(
    client: Client,
    scene: scene_pb2.Scene,
    misspell: Callable[[scene_pb2.Scene], None],
    where: str,
    meant: str,
) -> None:
    misspell(scene)
    with pytest.raises(grpc.RpcError) as error:
        client.submit(scene, 1)
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
    message = error.value.details()  # type: ignore[attr-defined]
    assert message.startswith(f"{where}.class_name: unknown component class"), message
    assert f"did you mean '{meant}'?" in message, message


def test_a_class_far_from_every_known_one_gets_no_suggestion(
    client: Client, scene: scene_pb2.Scene
) -> None:
    scene.sampler.class_name = "quasirandom_halton_leaped"
    with pytest.raises(grpc.RpcError) as error:
        client.submit(scene, 1)
    message = error.value.details()  # type: ignore[attr-defined]
    assert "scene.sampler.class_name: unknown component class" in message, message
    assert "did you mean" not in message, message


def test_an_integrator_without_an_image_mode_fails_the_job_saying_so(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    scene.integrator.class_name = "simpson"
    message = rejection_or_failure(client, scene)
    assert "simpson" in message and "does not render images" in message, message
    scene.integrator.class_name = "no_such_integrator"
    message = rejection_or_failure(client, scene)
    assert "no_such_integrator" in message, message
    assert_still_renders()


def test_bad_lights_are_rejected_naming_them(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    # A light without an emitter class; two skies; a moving lamp.
    nameless = scene_pb2.Scene()
    nameless.CopyFrom(scene)
    nameless.lights.add(name="bulb")
    assert "bulb" in str(submit_rejection(client, nameless).details())
    skies = scene_pb2.Scene()
    skies.CopyFrom(scene)
    for name in ("sky", "second_sky"):
        sky = skies.lights.add(name=name, kind=scene_pb2.Light.ENVIRONMENT)
        sky.emitter.class_name = "constant"
        sky.emitter.properties.values["radiance"].float_value = 1
    details = str(submit_rejection(client, skies).details())
    assert "second_sky" in details and "ENVIRONMENT" in details, details
    moving = scene_pb2.Scene()
    moving.CopyFrom(scene)
    light = next(s for s in moving.shapes if s.name == "light")
    light.to_world_end.CopyFrom(light.to_world)
    details = str(submit_rejection(client, moving).details())
    assert "light" in details and "moving lights" in details, details
    assert_still_renders()


def test_absurd_resolution_is_rejected_naming_it(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    scene.film.width = 100_000
    scene.film.height = 100_000
    details = str(submit_rejection(client, scene).details())
    assert "100000" in details, details
    assert_still_renders()


def test_a_filter_of_unknown_kind_or_bad_radius_is_rejected_naming_it(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    # Proto3 enums carry any number: the server must not index by it.
    scene.film.filter.kind = 1_000_000_000  # type: ignore[assignment]
    details = str(submit_rejection(client, scene).details())
    assert "film.filter.kind" in details and "1000000000" in details, details
    scene.film.filter.kind = scene_pb2.ReconstructionFilter.TENT
    for radius in (float("nan"), float("inf"), -1.0, 16.5, 1e30):
        scene.film.filter.radius = radius
        details = str(submit_rejection(client, scene).details())
        assert "film.filter.radius" in details, (radius, details)
    scene.film.filter.radius = 16.0
    job_id = client.submit(scene, spp=1, seed=0)
    assert client.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED
    assert_still_renders()


def test_absurd_samples_per_pixel_are_rejected_naming_them(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    details = str(submit_rejection(client, scene, spp=(1 << 20) + 1).details())
    assert "spp" in details.lower() or "samples" in details.lower(), details
    assert_still_renders()


def scene_file_with_mesh(folder: Path, mesh_file: str) -> Path:
    """A JSON scene file in ``folder`` whose extra shape references ``mesh_file``."""
    scene = small_scene()
    extra = scene.shapes.add(name="extra", material="grey")
    extra.mesh.file = mesh_file
    path = folder / "scene.json"
    path.write_text(json_format.MessageToJson(scene))
    return path


def test_scene_loader_inlines_mesh_files_next_to_the_scene(tmp_path: Path) -> None:
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tri.obj").write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    scene = load_scene(scene_file_with_mesh(tmp_path, "meshes/tri.obj"))
    mesh = scene.shapes[-1].mesh
    assert mesh.WhichOneof("source") == "data"
    assert mesh.data.startswith(b"v 0 0 0") and mesh.format == "obj"


def test_scene_loader_names_a_missing_mesh_file(tmp_path: Path) -> None:
    path = scene_file_with_mesh(tmp_path, "meshes/missing.obj")
    with pytest.raises(SceneError, match=re.escape("meshes/missing.obj")):
        load_scene(path)


def test_scene_loader_inlines_a_mesh_file_beside_the_scene_folder(tmp_path: Path) -> None:
    triangle = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    (tmp_path / "beside.obj").write_bytes(triangle)
    folder = tmp_path / "scene"
    folder.mkdir()
    scene = load_scene(scene_file_with_mesh(folder, "../beside.obj"))
    assert [s.mesh.data for s in scene.shapes if s.name == "extra"] == [triangle]


def test_cli_exits_with_an_error_naming_a_missing_mesh_file(
    server: LocalServer, tmp_path: Path
) -> None:
    scene_path = scene_file_with_mesh(tmp_path, "meshes/missing.obj")
    yarf = Path(sys.executable).parent / "yarf"
    command = [str(yarf), "render", str(scene_path), "-o", str(tmp_path / "out.exr")]
    command += ["--server", server.address, "--quiet"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert run.returncode != 0
    assert "meshes/missing.obj" in run.stderr, run.stderr
    assert not (tmp_path / "out.exr").exists()


def test_cli_exits_with_the_servers_message_when_the_job_fails(
    server: LocalServer, tmp_path: Path
) -> None:
    (tmp_path / "broken.obj").write_bytes(b"v zero 0 0\nf 1 2 3\n")
    scene_path = scene_file_with_mesh(tmp_path, "broken.obj")
    yarf = Path(sys.executable).parent / "yarf"
    command = [str(yarf), "render", str(scene_path), "-o", str(tmp_path / "out.png")]
    command += ["--server", server.address, "--quiet"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert run.returncode != 0
    assert "FAILED" in run.stderr and "extra" in run.stderr, run.stderr
    assert not (tmp_path / "out.png").exists()


def test_mesh_file_outside_the_asset_root_is_refused_naming_the_path(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    sneaky = scene.shapes.add(name="sneaky", material="grey")
    sneaky.mesh.file = "../../etc/passwd"
    sneaky.mesh.format = "obj"
    message = rejection_or_failure(client, scene)
    assert "../../etc/passwd" in message, message
    assert_still_renders()


def test_mesh_data_that_is_not_obj_fails_the_job_naming_the_mesh(
    client: Client, scene: scene_pb2.Scene, assert_still_renders: StillRenders
) -> None:
    garbage = scene.shapes.add(name="garbage_mesh", material="grey")
    garbage.mesh.data = b"v zero 0 0\nf 1 2 3\nthis is not an OBJ file\n"
    garbage.mesh.format = "obj"
    job_id = client.submit(scene, spp=1, seed=0)
    status = client.wait(job_id, timeout=30)
    assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
    assert "garbage_mesh" in status.error, status.error
    # GetResult shows the failure too: a FAILED status, or an error carrying the message.
    try:
        assert client.result(job_id).status.state == render_pb2.FAILED
    except grpc.RpcError as error:
        assert error.code() == grpc.StatusCode.FAILED_PRECONDITION, error
        assert "garbage_mesh" in str(error.details()), error.details()
    assert_still_renders()


def test_broken_plugin_is_reported_and_the_server_still_serves(
    server: LocalServer, tmp_path: Path
) -> None:
    plugins = tmp_path / "plugins"
    plugins.mkdir()
    broken = plugins / "libbroken.so"
    broken.write_bytes(b"\x7fELF this is not a shared library\n" * 16)
    # Name the build's plugin folder too, so that the second server has its
    # classes whether or not a --plugin-path replaces the default folder.
    build_plugins = server.binary.resolve().parent.parent / "plugins"
    plugin_paths = [build_plugins, plugins] if build_plugins.is_dir() else [plugins]
    with (
        LocalServer(plugin_paths=plugin_paths, extra_args=["--allow-load-plugin"]) as other,
        other.client() as client,
    ):
        listing = client.list_classes()
        errors = [error for error in listing.plugin_errors if "libbroken.so" in error.path]
        assert errors, f"plugin_errors does not name libbroken.so: {listing.plugin_errors}"
        assert errors[0].message

        with pytest.raises(grpc.RpcError) as caught:
            client.load_plugin(str(broken))
        assert caught.value.code() == grpc.StatusCode.FAILED_PRECONDITION, caught.value
        assert "libbroken.so" in str(caught.value.details())

        assert client.health() == "SERVING"
        assert client.list_classes().classes
        result = client.render(small_scene(), spp=2, seed=1, timeout=30)
        assert result.pixels.mean() > 0
        assert other.is_running()


def test_cancelled_job_ends_within_a_second_and_other_jobs_go_on(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    long_job = client.submit(cornell_box, spp=1 << 20, seed=1, name="long job to cancel")
    other_job = client.submit(small_scene(), spp=4, seed=2, name="job beside a cancelled one")

    seen: list[render_pb2.JobStatus] = []

    def follow() -> None:
        for status in client.watch(long_job, timeout=120):
            seen.append(status)

    watcher = threading.Thread(target=follow, daemon=True)
    watcher.start()
    deadline = time.monotonic() + 30
    while not any(status.state == render_pb2.RUNNING for status in seen):
        assert time.monotonic() < deadline, "the long job did not start running within 30 s"
        assert watcher.is_alive(), f"Watch ended before the job ran: {seen[-1:]}"
        time.sleep(0.01)

    cancelled_at = time.monotonic()
    client.cancel(long_job)
    while True:
        asked_at = time.monotonic()
        state = client.status(long_job).state
        if state == render_pb2.CANCELLED or asked_at - cancelled_at > 1.0:
            break
        time.sleep(0.02)
    took = asked_at - cancelled_at
    assert state == render_pb2.CANCELLED and took <= 1.0, (
        f"{took:.2f} s after Cancel the job is {render_pb2.JobState.Name(state)}"
    )

    watcher.join(timeout=2.0)
    assert not watcher.is_alive(), "Watch of the cancelled job did not end"
    assert seen[-1].state == render_pb2.CANCELLED

    status = client.wait(other_job, timeout=30)
    assert status.state == render_pb2.SUCCEEDED, status.error
