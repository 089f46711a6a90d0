"""A damaged state folder never loses jobs silently: a lost, emptied or
garbled job database or a lost or damaged write-ahead log stops yarfd with
a clear message and nothing deleted; result and checkpoint files of the
wrong job or with changed bytes are discarded with a log line, never
served or resumed; jobs that merely shared the server at a crash are never
failed for it.

Every test starts its own yarfd processes on a private state folder.
"""

from __future__ import annotations

import shutil
import struct
import time
from collections.abc import Callable
from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import small_scene
from test_durable_queue import (
    checkpoint_samples,
    start_server,  # noqa: F401 (a fixture)
    state_dir,  # noqa: F401 (a fixture)
    submit,
    wait_until,
)

from yarf import LocalServer, ServerError
from yarf.v1 import render_pb2


def finished_jobs(server: LocalServer, seeds: tuple[int, ...]) -> list[str]:
    """Jobs rendered to the end, each with its own image."""
    with server.client() as client:
        ids = [submit(client, small_scene(), spp=4, seed=seed) for seed in seeds]
        for job_id in ids:
            assert client.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED
    return ids


def files_of(state: Path) -> dict[str, bytes]:
    return {
        f"{folder}/{path.name}": path.read_bytes()
        for folder in ("results", "checkpoints")
        for path in sorted((state / folder).iterdir())
    }


def refusal(start: Callable[..., LocalServer]) -> str:
    with pytest.raises(ServerError) as caught:
        start()
    message = str(caught.value)
    assert "code 0 " not in message and "code None" not in message, message
    return message


@pytest.mark.parametrize("damage", ["emptied", "deleted", "garbled"])
def test_a_lost_job_database_beside_results_stops_the_server_and_deletes_nothing(
    start_server: Callable[..., LocalServer],  # noqa: F811
    state_dir: Path,  # noqa: F811
    damage: str,
) -> None:
    first = start_server()
    finished_jobs(first, (1, 2))
    assert first.stop() == 0
    database = state_dir / "jobs.sqlite"
    if damage == "emptied":
        database.write_bytes(b"")
    elif damage == "deleted":
        database.unlink()
    else:
        database.write_bytes(b"this is no database" * 300)
    before = files_of(state_dir)
    assert len(before) == 2

    message = refusal(start_server)
    assert str(database) in message, message
    expected = {
        "emptied": "is empty",
        "deleted": "is missing",
        "garbled": "not a database",
    }[damage]
    assert expected in message, message
    assert "2 files in" in message and "results" in message, message
    assert "Nothing was changed" in message or "nothing was changed" in message, message
    assert files_of(state_dir) == before, "the refused server changed the files of jobs"
    assert damage != "deleted" or not database.exists(), "the refused server made a database"


def test_a_lost_or_damaged_log_after_a_crash_stops_the_server(
    start_server: Callable[..., LocalServer],  # noqa: F811
    state_dir: Path,  # noqa: F811
    tmp_path: Path,
) -> None:
    server = start_server()
    ids = finished_jobs(server, (1, 2, 3))
    # The acknowledged jobs are in the log: SQLite copies it into the
    # database only every thousand pages, or when it closes cleanly.
    server.kill()
    wal = state_dir / "jobs.sqlite-wal"
    assert wal.stat().st_size > 32
    saved = tmp_path / "saved"
    shutil.copytree(state_dir, saved)

    # A byte of the log's first frame: SQLite would drop every job after it.
    damaged = bytearray(wal.read_bytes())
    damaged[32 + 24 + 100] ^= 1
    wal.write_bytes(bytes(damaged))
    message = refusal(start_server)
    assert "jobs.sqlite-wal is damaged at frame 1" in message, message
    assert wal.read_bytes() == bytes(damaged)

    # The log deleted: the database alone lacks the acknowledged jobs.
    wal.unlink()
    message = refusal(start_server)
    assert "was not closed by the last yarfd" in message, message
    assert "jobs.sqlite-wal is missing" in message, message
    marker = state_dir / "jobs.sqlite-open"
    assert str(marker) in message, message
    before = files_of(state_dir)

    # Told to go on without it: the jobs the database never held are gone
    # from the table, but their files are not deleted.
    marker.unlink()
    bare = start_server()
    with bare.client() as client:
        listed = {job.job_id for job in client.list()}
    assert bare.stop() == 0
    assert not listed & set(ids), listed
    assert files_of(state_dir) == before
    assert "ever held; left as it is" in bare.log

    # The log put back: every job is there again, with its image.
    shutil.rmtree(state_dir)
    shutil.copytree(saved, state_dir)
    again = start_server()
    with again.client() as client:
        for job_id in ids:
            assert client.status(job_id).state == render_pb2.SUCCEEDED
            assert client.image(job_id).mean() > 0


def test_swapped_or_changed_results_are_not_served(
    start_server: Callable[..., LocalServer],  # noqa: F811
    state_dir: Path,  # noqa: F811
) -> None:
    first = start_server()
    a, b, c = finished_jobs(first, (1, 2, 3))
    with first.client() as client:
        image_a = client.image(a)
        image_b = client.image(b)
    assert not np.array_equal(image_a, image_b)
    assert first.stop() == 0
    results = state_dir / "results"
    path_a, path_b, path_c = (results / f"{job_id}.image" for job_id in (a, b, c))
    bytes_a, bytes_b = path_a.read_bytes(), path_b.read_bytes()
    path_a.write_bytes(bytes_b)
    path_b.write_bytes(bytes_a)
    changed = bytearray(path_c.read_bytes())
    changed[len(changed) // 2] ^= 0x10
    path_c.write_bytes(bytes(changed))

    again = start_server()
    with again.client() as client:
        for job_id in (a, b, c):
            assert client.status(job_id).state == render_pb2.SUCCEEDED
            for fetch in (client.image, client.raw):
                with pytest.raises(grpc.RpcError) as caught:
                    fetch(job_id)
                assert caught.value.code() == grpc.StatusCode.FAILED_PRECONDITION, job_id
                assert "has no image" in str(caught.value.details())
    log = again.log
    assert f"yarfd: job {a}: result discarded, not served: {path_a}" in log, log
    assert f"belongs to job number {int(b.split('-')[1])}, not {int(a.split('-')[1])}" in log
    assert f"yarfd: job {c}: result discarded, not served: {path_c} fails its checksum" in log
    # Kept for whoever looks into it.
    assert path_a.read_bytes() == bytes_b and path_c.read_bytes() == bytes(changed)


# Fewer samples than the film holds (resumed, it would weigh the film
# wrongly and add samples twice), or more than the job has.
@pytest.mark.parametrize("edited_samples", [10, 9000], ids=["fewer", "more than spp"])
def test_a_checkpoint_with_edited_samples_done_is_discarded_and_the_job_renders_anew(
    start_server: Callable[..., LocalServer],  # noqa: F811
    state_dir: Path,  # noqa: F811
    edited_samples: int,
) -> None:
    server = start_server("--checkpoint-seconds", "0.1")
    with server.client() as client:
        job_id = submit(client, small_scene(), spp=8000, seed=7)
        wait_until(lambda: checkpoint_samples(state_dir, job_id) >= 500, "a checkpoint")
    server.kill()
    checkpoint = state_dir / "checkpoints" / f"{job_id}.film"
    edited = bytearray(checkpoint.read_bytes())
    edited[8:12] = struct.pack("<I", edited_samples)
    checkpoint.write_bytes(bytes(edited))

    again = start_server()
    with again.client() as client:
        status = client.wait(job_id, timeout=120)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert status.samples_done == 8000
        # Rendered anew: every sample traced in this run.
        assert status.closest_hit_rays >= 16 * 16 * 8000
        reference = submit(client, small_scene(), spp=8000, seed=7)
        assert client.wait(reference, timeout=120).state == render_pb2.SUCCEEDED
        np.testing.assert_allclose(
            client.image(job_id), client.image(reference), rtol=1e-5, atol=1e-7
        )
    assert f"yarfd: job {job_id}: checkpoint {checkpoint} discarded, starting anew" in again.log
    assert "fails its checksum" in again.log


def running_jobs(server: LocalServer, ids: list[str]) -> set[str]:
    with server.client() as client:
        return {j for j in ids if client.status(j).state == render_pb2.RUNNING}


def test_jobs_that_shared_the_server_at_its_crashes_are_not_failed_for_them(
    start_server: Callable[..., LocalServer],  # noqa: F811
) -> None:
    # Checkpoints far apart: no progress clears the jobs between the crashes.
    args = ("--max-running-jobs", "2", "--checkpoint-seconds", "60")
    server = start_server(*args)
    with server.client() as client:
        ids = [submit(client, small_scene(32), spp=1_000_000, seed=s) for s in (1, 2)]
    wait_until(lambda: running_jobs(server, ids) == set(ids), "both jobs run")
    server.kill()
    for _ in range(2):
        server = start_server(*args)
        # Each now runs alone: one at a time, though two slots are free.
        wait_until(lambda s=server: len(running_jobs(s, ids)) == 1, "one job runs")
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline:
            assert len(running_jobs(server, ids)) == 1
        server.kill()

    server = start_server(*args)
    with server.client() as client:
        for job_id in ids:
            status = client.status(job_id)
            assert status.state in (render_pb2.QUEUED, render_pb2.RUNNING), status.error
            assert "times in a row" not in status.error
        for job_id in ids:
            client.cancel(job_id)
