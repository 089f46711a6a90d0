"""GetJob (the job page's data) and RenderOptions.threads, against a real yarfd."""

from __future__ import annotations

from pathlib import Path

import grpc
import pytest
from conftest import grouped_scene, small_scene
from thread_ticks import threads_that_worked

from yarf import Client, LocalServer
from yarf.v1 import render_pb2, scene_pb2


def event_names(log: list[str]) -> list[str]:
    """The `event=` values of log lines, in order."""
    return [line.split()[0].removeprefix("event=") for line in log]


def test_a_finished_job_tells_its_options_scene_and_log(client: Client) -> None:
    scene = grouped_scene()
    job_id = client.submit(scene, 4, 7, name="details", aovs=["albedo", "depth"], threads=1)
    assert client.wait(job_id, timeout=120).state == render_pb2.SUCCEEDED

    details = client.details(job_id)
    assert details.status.job_id == job_id and details.status.state == render_pb2.SUCCEEDED
    options = details.options
    assert (options.spp, options.seed, options.threads) == (4, 7, 1)
    assert list(options.aovs) == ["albedo", "depth"]
    summary = details.scene
    assert (summary.width, summary.height) == (24, 12)
    # Two world shapes and the group's one, counted once however often placed.
    assert (summary.shapes, summary.instances, summary.materials, summary.textures) == (3, 2, 1, 1)
    assert summary.lights == 1 and summary.camera == "thin_lens"
    assert event_names(list(details.log)) == ["submitted", "started", "finished"]
    assert all(f"job={job_id}" in line for line in details.log), details.log
    assert "spp=4 spp_total=4" in details.log[-1], details.log[-1]


def test_a_failed_job_logs_its_error(client: Client, tmp_path: Path) -> None:
    # A material served by a component process that is not there.
    scene = small_scene()
    scene.materials[0].address = f"unix:{tmp_path / 'nobody.sock'}"
    job_id = client.submit(scene, 1)
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.FAILED
    log = list(client.details(job_id).log)
    assert event_names(log) == ["submitted", "started", "failed"]
    assert "nobody.sock" in log[-1], log[-1]


def test_an_unknown_job_is_not_found(client: Client) -> None:
    with pytest.raises(grpc.RpcError) as error:
        client.details("job-999999")
    assert error.value.code() == grpc.StatusCode.NOT_FOUND  # type: ignore[attr-defined]


def threads_that_rendered(server: LocalServer, client: Client, threads: int) -> int:
    """Renders a job of a few CPU seconds with ``threads``; how many of yarfd's threads did it."""
    job_id = client.submit(small_scene(128), 128, threads=threads)
    return threads_that_worked(server.pid, client, job_id)


def test_threads_bounds_the_render_threads_of_a_job(server: LocalServer, client: Client) -> None:
    assert threads_that_rendered(server, client, 1) == 1
    # 0: every thread of the server's (two or more here).
    assert threads_that_rendered(server, client, 0) >= 2


def test_threads_do_not_change_the_image(client: Client) -> None:
    scene: scene_pb2.Scene = small_scene(16)
    one = client.raw(client.wait(client.submit(scene, 8, 3, threads=1)).job_id)
    many = client.raw(client.wait(client.submit(scene, 8, 3, threads=64)).job_id)
    assert (one.pixels == many.pixels).all()
