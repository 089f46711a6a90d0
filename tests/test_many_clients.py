"""One yarfd serving many clients at once: each submits a tiny job and watches it to the end."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from concurrent import futures

import pytest
from conftest import small_scene

from yarf import LocalServer
from yarf.v1 import render_pb2

CLIENTS = 200


@pytest.fixture(scope="module")
def busy_server() -> Iterator[LocalServer]:
    """A yarfd of its own, so that the jobs listed are this test's and the session's
    server is not crowded for the tests after it."""
    with LocalServer() as local:
        yield local
        assert local.is_running(), f"yarfd died under the load:\n{local.log[-4000:]}"


def test_two_hundred_clients_submit_and_watch_jobs_to_success(busy_server: LocalServer) -> None:
    scene = small_scene(8)
    # All clients connect first, then submit together.
    start = threading.Barrier(CLIENTS, timeout=30)

    def one_client(index: int) -> tuple[str, render_pb2.JobStatus]:
        with busy_server.client(timeout=60) as client:
            client.is_serving(timeout=10)
            start.wait()
            job_id = client.submit(scene, spp=4, seed=index, name=f"client-{index}")
            return job_id, client.wait(job_id, timeout=60)

    with futures.ThreadPoolExecutor(max_workers=CLIENTS) as pool:
        outcomes = list(pool.map(one_client, range(CLIENTS)))

    failures = [
        f"{job_id}: {render_pb2.JobState.Name(status.state)} {status.error}"
        for job_id, status in outcomes
        if status.state != render_pb2.SUCCEEDED
    ]
    assert not failures, failures
    job_ids = {job_id for job_id, _ in outcomes}
    assert len(job_ids) == CLIENTS, "two clients were given the same job id"
    assert all(status.samples_done == 4 for _, status in outcomes)

    with busy_server.client() as client:
        listed = {job.job_id: job for job in client.list()}
    assert job_ids <= listed.keys(), sorted(job_ids - listed.keys())[:10]
    assert {listed[job_id].name for job_id in job_ids} == {f"client-{i}" for i in range(CLIENTS)}
