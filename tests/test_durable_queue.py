"""The durable job queue: jobs outlive their server, run in priority order,
retry, resume from checkpoints and are pruned; one server per state folder.

Every test starts its own yarfd processes on a private state folder.
"""

from __future__ import annotations

import os
import sqlite3
import struct
import time
from collections.abc import Callable, Iterator
from contextlib import closing
from pathlib import Path

import grpc
import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import REPO, small_scene

from yarf import Client, LocalServer, ServerError, component
from yarf.v1 import render_pb2, scene_pb2

ENDED = {render_pb2.SUCCEEDED, render_pb2.FAILED, render_pb2.CANCELLED}
AMBIENT_OCCLUSION = REPO / "components" / "python" / "examples" / "ambient_occlusion.py"


def submit(
    client: Client,
    scene: scene_pb2.Scene,
    *,
    spp: int,
    seed: int = 1,
    priority: int = 0,
    max_retries: int = 0,
    integrator: str = "",
    name: str = "",
    component_timeout: float = 0.0,
) -> str:
    options = render_pb2.RenderOptions(
        spp=spp, seed=seed, component_timeout_seconds=component_timeout
    )
    if integrator:
        options.integrator.CopyFrom(component(integrator))
    request = render_pb2.SubmitRequest(
        scene=scene, options=options, name=name, priority=priority, max_retries=max_retries
    )
    return str(client.render_service.Submit(request, timeout=client.timeout).job_id)


def state_of(client: Client, job_id: str) -> str:
    return render_pb2.JobState.Name(client.status(job_id).state)


def wait_until(condition: Callable[[], bool], what: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting until {what}")
        time.sleep(0.02)


def wait_for_state(client: Client, job_id: str, state: str) -> None:
    wait_until(lambda: state_of(client, job_id) == state, f"{job_id} is {state}")


def wait_all(
    client: Client, job_ids: list[str], timeout: float = 60.0
) -> dict[str, render_pb2.JobStatus]:
    return {job_id: client.wait(job_id, timeout=timeout) for job_id in job_ids}


def checkpoint_samples(state_dir: Path, job_id: str) -> int:
    """The sample count a checkpoint file was written after (0: no checkpoint)."""
    try:
        head = (state_dir / "checkpoints" / f"{job_id}.film").read_bytes()[:12]
    except OSError:
        return 0
    assert head[:8] == b"YARFCKP2", head
    return int(struct.unpack("<I", head[8:12])[0])


def wait_for_new_checkpoint(state_dir: Path, job_id: str) -> None:
    seen = checkpoint_samples(state_dir, job_id)
    wait_until(lambda: checkpoint_samples(state_dir, job_id) > seen, f"{job_id} checkpoints")


def stored_state(state_dir: Path, job_id: str) -> str:
    """The state of a job's row in the job store of a server that has stopped."""
    with closing(sqlite3.connect(state_dir / "jobs.sqlite")) as db:
        row = db.execute(
            "SELECT state FROM jobs WHERE number = ?", (int(job_id.split("-")[1]),)
        ).fetchone()
    return render_pb2.JobState.Name(row[0])


def refuse_to_store(state_dir: Path, states: tuple[int, ...]) -> None:
    """Makes a running server's job store fail to store a job in ``states``, like a full disk."""
    listed = ", ".join(str(state) for state in states)
    with closing(sqlite3.connect(state_dir / "jobs.sqlite")) as db:
        db.execute(
            f"CREATE TRIGGER refuse BEFORE UPDATE ON jobs WHEN NEW.state IN ({listed})"
            " BEGIN SELECT RAISE(ABORT, 'database or disk is full'); END"
        )
        db.commit()


def store_again(state_dir: Path) -> None:
    with closing(sqlite3.connect(state_dir / "jobs.sqlite")) as db:
        db.execute("DROP TRIGGER refuse")
        db.commit()


@pytest.fixture
def state_dir(tmp_path: Path) -> Path:
    return tmp_path / "state"


@pytest.fixture
def start_server(state_dir: Path) -> Iterator[Callable[..., LocalServer]]:
    """Starts yarfd processes on the test's state folder; stops them at the end."""
    started: list[LocalServer] = []

    def start(*args: str, state: Path | None = None) -> LocalServer:
        local = LocalServer(state_dir=state or state_dir, extra_args=list(args))
        started.append(local)
        local.start()
        return local

    yield start
    for local in started:
        local.stop()


def test_a_killed_server_resumes_running_jobs_from_checkpoints_and_runs_queued_ones(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    args = ("--max-running-jobs", "2", "--checkpoint-seconds", "0.1")
    first = start_server(*args)
    with first.client() as client:
        resumable = submit(client, small_scene(), spp=8000, seed=7, name="resumable")
        wait_until(
            lambda: checkpoint_samples(state_dir, resumable) >= 2000,
            "the resumable job has a checkpoint of a quarter of its samples",
        )
        # A second running job that must start over, and two that wait.
        restarted = submit(client, small_scene(), spp=3000, seed=3, integrator="vegas")
        queued = [submit(client, small_scene(), spp=16, seed=s) for s in (1, 2)]
        wait_until(lambda: client.status(restarted).samples_done > 0, "the vegas job renders")
        assert state_of(client, resumable) == "RUNNING"
        assert state_of(client, restarted) == "RUNNING"
        assert [state_of(client, j) for j in queued] == ["QUEUED", "QUEUED"]
    first.kill()
    checkpointed = checkpoint_samples(state_dir, resumable)
    assert 2000 <= checkpointed < 8000

    second = start_server(*args)
    with second.client() as client:
        # Before it goes on, the job shows what its checkpoint holds.
        assert client.status(resumable).samples_done >= checkpointed
        final = wait_all(client, [resumable, restarted, *queued])
        for job_id, status in final.items():
            assert status.state == render_pb2.SUCCEEDED, (job_id, status)
        assert final[resumable].attempts == 2 and final[restarted].attempts == 2
        assert [final[j].attempts for j in queued] == [1, 1]
        assert final[resumable].samples_done == 8000

        # The same job, never interrupted: the same image.
        reference = submit(client, small_scene(), spp=8000, seed=7)
        reference_status = client.wait(reference, timeout=60)
        assert reference_status.state == render_pb2.SUCCEEDED
        resumed_image, reference_image = client.image(resumable), client.image(reference)
        assert reference_image.mean() > 0
        np.testing.assert_allclose(resumed_image, reference_image, rtol=1e-5, atol=1e-7)
        # ...for less work: the resumed run traced only the samples after its checkpoint.
        share_left = (8000 - checkpointed) / 8000
        assert final[resumable].closest_hit_rays < (share_left + 0.05) * (
            reference_status.closest_hit_rays
        )
        assert not list((state_dir / "checkpoints").iterdir()), "checkpoints of ended jobs remain"


def test_queued_jobs_start_by_priority_then_in_submission_order_and_set_priority_moves_them(
    start_server: Callable[..., LocalServer],
) -> None:
    server = start_server("--max-running-jobs", "1")
    with server.client() as client:
        blocker = submit(client, small_scene(16), spp=1_000_000, priority=100)
        wait_for_state(client, blocker, "RUNNING")
        priorities = {"a": 10, "b": 90, "c": 50, "d": 90, "e": 10, "f": 0}  # 0: the default, 50
        ids = {
            key: submit(client, small_scene(32), spp=200, priority=p, name=key)
            for key, p in priorities.items()
        }
        assert client.status(ids["f"]).priority == 50
        moved = client.render_service.SetPriority(
            render_pb2.SetPriorityRequest(job_id=ids["e"], priority=95)
        )
        assert moved.priority == 95 and moved.state == render_pb2.QUEUED
        for bad in (0, 101):
            with pytest.raises(grpc.RpcError) as caught:
                client.render_service.SetPriority(
                    render_pb2.SetPriorityRequest(job_id=ids["a"], priority=bad)
                )
            assert caught.value.code() == grpc.StatusCode.INVALID_ARGUMENT, bad
        with pytest.raises(grpc.RpcError) as caught:
            client.render_service.SetPriority(
                render_pb2.SetPriorityRequest(job_id="job-999999", priority=5)
            )
        assert caught.value.code() == grpc.StatusCode.NOT_FOUND

        expected = [ids[k] for k in ("e", "b", "d", "c", "f", "a")]
        client.cancel(blocker)
        # One runs at a time, so at any moment the jobs that have left the
        # queue are a prefix of the start order.
        snapshots = 0
        while True:
            states = {job.job_id: job.state for job in client.list()}
            started = [j for j in expected if states[j] != render_pb2.QUEUED]
            assert started == expected[: len(started)], [
                (k, render_pb2.JobState.Name(states[i])) for k, i in ids.items()
            ]
            running = [j for j in expected if states[j] == render_pb2.RUNNING]
            assert len(running) <= 1
            snapshots += 1
            if len(started) == len(expected) and all(states[j] in ENDED for j in expected):
                break
            time.sleep(0.01)
        assert snapshots > 5
        assert all(client.status(j).state == render_pb2.SUCCEEDED for j in expected)
        assert client.status(blocker).state == render_pb2.CANCELLED


def test_a_failing_job_is_attempted_max_retries_plus_one_times_then_fails(
    start_server: Callable[..., LocalServer],
) -> None:
    server = start_server()
    scene = small_scene()
    # A material served at an address where nothing listens.
    scene.materials[0].address = "127.0.0.1:1"
    with server.client() as client:
        job_id = submit(client, scene, spp=4, max_retries=2, component_timeout=2.0)
        status = client.wait(job_id, timeout=60)
        assert status.state == render_pb2.FAILED, status
        assert status.attempts == 3
        assert "grey" in status.error or "127.0.0.1:1" in status.error, status.error
        no_retry = client.wait(submit(client, scene, spp=4, component_timeout=2.0), timeout=60)
        assert no_retry.state == render_pb2.FAILED and no_retry.attempts == 1
        for request in (
            render_pb2.SubmitRequest(scene=small_scene(), max_retries=11),
            render_pb2.SubmitRequest(scene=small_scene(), priority=101),
        ):
            with pytest.raises(grpc.RpcError) as caught:
                client.render_service.Submit(request)
            assert caught.value.code() == grpc.StatusCode.INVALID_ARGUMENT


def test_only_the_newest_finished_jobs_are_kept(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    server = start_server("--max-finished-jobs", "2")
    with server.client() as client:
        ids = []
        for seed in range(4):
            ids.append(submit(client, small_scene(), spp=2, seed=seed))
            assert client.wait(ids[-1], timeout=30).state == render_pb2.SUCCEEDED
        # Pruned right after a job ends.
        wait_until(lambda: len(client.list()) == 2, "two jobs are left")
        assert [job.job_id for job in client.list()] == ids[:1:-1]
        with pytest.raises(grpc.RpcError) as caught:
            client.image(ids[0])
        assert caught.value.code() == grpc.StatusCode.NOT_FOUND
        assert client.image(ids[3]).shape == (16, 16, 3)
    kept = sorted(path.name for path in (state_dir / "results").iterdir())
    assert kept == [f"{ids[2]}.image", f"{ids[3]}.image"]


def test_results_ids_and_queued_jobs_survive_a_clean_restart(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    server = start_server("--max-running-jobs", "1", "--checkpoint-seconds", "0.1")
    with server.client() as client:
        done = [submit(client, small_scene(), spp=8, seed=s, priority=70) for s in (1, 2)]
        before = {j: client.wait(j, timeout=30) for j in done}
        images = {j: client.raw(j) for j in done}
        running = submit(client, small_scene(32), spp=100_000)
        waiting = submit(client, small_scene(), spp=4)
        wait_until(lambda: checkpoint_samples(state_dir, running) > 0, "a checkpoint is written")
    assert server.stop() == 0

    again = start_server("--max-running-jobs", "1")
    with again.client() as client:
        listed = {job.job_id: job for job in client.list()}
        for job_id, status in before.items():
            after = listed[job_id]
            assert after.state == render_pb2.SUCCEEDED
            assert (after.priority, after.owner, after.attempts) == (70, "local", 1)
            assert after.submitted_at == status.submitted_at
            assert after.samples_done == 8
            result = client.raw(job_id)
            np.testing.assert_array_equal(result.pixels, images[job_id].pixels)
            np.testing.assert_array_equal(result.variance, images[job_id].variance)
        # A stop is not a crash: the running job waits, with its progress, to go on.
        assert listed[running].state in (render_pb2.QUEUED, render_pb2.RUNNING)
        assert listed[running].samples_done > 0
        client.cancel(running)
        assert client.wait(waiting, timeout=30).state == render_pb2.SUCCEEDED
        newest = submit(client, small_scene(), spp=1)
        assert int(newest.split("-")[1]) == int(waiting.split("-")[1]) + 1


def test_a_job_the_server_died_under_three_times_in_a_row_fails(
    start_server: Callable[..., LocalServer],
) -> None:
    poison = ""
    for crash in range(3):
        server = start_server()
        with server.client() as client:
            if not poison:
                poison = submit(client, small_scene(32), spp=1_000_000)
            wait_for_state(client, poison, "RUNNING")
            assert client.status(poison).attempts == crash + 1
        server.kill()
    server = start_server()
    with server.client() as client:
        status = client.status(poison)
        assert status.state == render_pb2.FAILED
        assert "3 times in a row" in status.error, status.error
        assert status.attempts == 3
        assert client.wait(submit(client, small_scene(), spp=2), timeout=30).state == (
            render_pb2.SUCCEEDED
        )


def test_a_second_server_on_the_same_state_folder_refuses_to_start(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    first = start_server()
    # A temporary file of an upload, old enough for a starting server to drop.
    upload = state_dir / "assets" / "tmp" / "upload-in-progress"
    upload.write_bytes(b"part of an asset")
    two_hours_ago = time.time() - 7200
    os.utime(upload, (two_hours_ago, two_hours_ago))
    with pytest.raises(ServerError) as caught:
        start_server()
    assert "another yarfd" in str(caught.value) and str(state_dir) in str(caught.value)
    assert "code 0" not in str(caught.value)
    assert first.is_running()
    assert upload.exists(), "the refused server removed a file of the running one"


def test_an_unusable_state_folder_stops_the_server_with_a_clear_error(
    start_server: Callable[..., LocalServer], tmp_path: Path
) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    with pytest.raises(ServerError) as caught:
        start_server(state=blocker / "state")
    assert str(blocker) in str(caught.value) and "code 0" not in str(caught.value)

    damaged = tmp_path / "damaged"
    damaged.mkdir()
    (damaged / "jobs.sqlite").write_bytes(b"this is no database" * 300)
    with pytest.raises(ServerError) as caught:
        start_server(state=damaged)
    message = str(caught.value)
    assert "jobs.sqlite" in message and "not a database" in message, message


def test_a_job_whose_transport_calls_the_server_back_waits_queued_after_a_plain_stop(
    start_server: Callable[..., LocalServer], state_dir: Path, tmp_path: Path
) -> None:
    server = start_server()
    target = f"{AMBIENT_OCCLUSION}:AmbientOcclusion"
    socket = f"unix:{tmp_path / 'transport.sock'}"
    with ComponentProcess.python([target], socket, "--server", server.address) as process:
        transport = component("py_ambient_occlusion")
        transport.address = process.address
        with server.client() as client:
            job_id = client.submit(small_scene(8), spp=1_000_000, seed=1, transport=transport)
            wait_until(lambda: client.status(job_id).samples_done > 0, "the transport renders")
        # The transport calls the server until its run stops: the server
        # must still answer it, so that the job stops rather than fails.
        assert server.stop() == 0
    assert stored_state(state_dir, job_id) == "QUEUED"


def test_only_crashes_without_progress_between_them_fail_a_job(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    job_id = ""
    for _ in range(3):
        server = start_server("--checkpoint-seconds", "0.1")
        with server.client() as client:
            if not job_id:
                job_id = submit(client, small_scene(32), spp=1_000_000)
            wait_for_new_checkpoint(state_dir, job_id)
            # And the next one: the previous one's row is stored by now.
            wait_for_new_checkpoint(state_dir, job_id)
        server.kill()
    server = start_server()
    with server.client() as client:
        assert state_of(client, job_id) in ("QUEUED", "RUNNING"), client.status(job_id).error
        client.cancel(job_id)
    server.stop()

    # Neither does a clean stop between crashes count toward the limit.
    job_id = ""
    for how in ("kill", "kill", "stop", "kill"):
        server = start_server()
        with server.client() as client:
            if not job_id:
                job_id = submit(client, small_scene(32), spp=1_000_000)
            wait_for_state(client, job_id, "RUNNING")
        if how == "kill":
            server.kill()
        else:
            assert server.stop() == 0
    server = start_server()
    with server.client() as client:
        status = client.status(job_id)
        assert status.state in (render_pb2.QUEUED, render_pb2.RUNNING), status.error
        client.cancel(job_id)


def test_a_job_cancelled_while_it_runs_stays_cancelled_after_a_crash(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    server = start_server("--checkpoint-seconds", "0.1")
    with server.client() as client:
        job_id = submit(client, small_scene(256), spp=1_000_000)
        wait_until(lambda: checkpoint_samples(state_dir, job_id) > 0, "a checkpoint")
        client.cancel(job_id)
    # At once: the run has not ended yet, only the cancel is stored.
    server.kill()

    again = start_server()
    with again.client() as client:
        status = client.status(job_id)
        assert status.state == render_pb2.CANCELLED, render_pb2.JobState.Name(status.state)
        # With the image of its last checkpoint (or of its run, had it ended).
        image = client.image(job_id)
        assert image.shape == (256, 256, 3) and image.mean() > 0
        time.sleep(0.5)
        assert client.status(job_id).state == render_pb2.CANCELLED
    assert not list((state_dir / "checkpoints").iterdir())


def test_a_job_database_of_the_previous_schema_is_upgraded(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    state_dir.mkdir()
    request = render_pb2.SubmitRequest(
        scene=small_scene(), options=render_pb2.RenderOptions(spp=4, seed=1), priority=50
    )
    with closing(sqlite3.connect(state_dir / "jobs.sqlite")) as db:
        db.executescript(
            """
            CREATE TABLE jobs (
              number INTEGER PRIMARY KEY AUTOINCREMENT, request BLOB NOT NULL,
              name TEXT NOT NULL, owner TEXT NOT NULL, state INTEGER NOT NULL,
              priority INTEGER NOT NULL, max_retries INTEGER NOT NULL,
              attempts INTEGER NOT NULL, failures INTEGER NOT NULL, crashes INTEGER NOT NULL,
              samples_done INTEGER NOT NULL, samples_total INTEGER NOT NULL,
              error TEXT NOT NULL, submitted_at REAL NOT NULL, finished_at REAL NOT NULL,
              elapsed_seconds REAL NOT NULL, closest_hit_rays INTEGER NOT NULL,
              shadow_rays INTEGER NOT NULL);
            PRAGMA user_version = 1;
            """
        )
        db.execute(
            "INSERT INTO jobs VALUES (7, ?, 'old', 'local', ?, 50, 0, 0, 0, 0, 0, 4, '',"
            " 1.0, 0, 0, 0, 0)",
            (request.SerializeToString(), render_pb2.QUEUED),
        )
        db.commit()
    server = start_server()
    with server.client() as client:
        status = client.wait("job-000007", timeout=30)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert client.wait(submit(client, small_scene(), spp=2), timeout=30).state == (
            render_pb2.SUCCEEDED
        )


def test_a_job_whose_end_cannot_be_stored_fails_until_a_restart_resumes_it(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    server = start_server()
    refuse_to_store(state_dir, (render_pb2.SUCCEEDED, render_pb2.FAILED, render_pb2.CANCELLED))
    with server.client() as client:
        job_id = submit(client, small_scene(), spp=4, seed=1)
        # Watchers see it end, though the store could not record it.
        status = client.wait(job_id, timeout=30)
        assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
        assert "could not be stored" in status.error, status.error
        assert "database or disk is full" in status.error, status.error
        assert stored_state(state_dir, job_id) == "RUNNING"
        store_again(state_dir)
        other = submit(client, small_scene(), spp=2)
        assert client.wait(other, timeout=30).state == render_pb2.SUCCEEDED
    assert server.stop() == 0
    assert "cannot be stored" in server.log

    # Stored as RUNNING: the next start takes it for a crash and runs it again.
    again = start_server()
    with again.client() as client:
        status = client.wait(job_id, timeout=30)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert status.attempts == 2
        assert client.image(job_id).mean() > 0


def test_a_job_whose_start_cannot_be_stored_waits_queued_until_it_can_be(
    start_server: Callable[..., LocalServer], state_dir: Path
) -> None:
    server = start_server()
    refuse_to_store(state_dir, (render_pb2.RUNNING,))
    with server.client() as client:
        job_id = submit(client, small_scene(), spp=4)
        wait_until(lambda: "database or disk is full" in server.log, "a start is refused")
        status = client.status(job_id)
        assert (status.state, status.attempts) == (render_pb2.QUEUED, 0)
        store_again(state_dir)
        status = client.wait(job_id, timeout=30)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert status.attempts == 1
