"""GetJob on the farm's coordinator, with real processes on loopback.

A farm job tells the options and scene summary a yarfd tells of the same
request, and a log in yarfd's ``key=value`` lines: the job's own lines
(submitted, started, its end) with a line per task between them. The
coordinator rebuilds the log from its job table, so the stored lines
outlive a restart. GetJob follows GetResult's access rule.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator

import grpc
import pytest
from conftest import CORNELL_BOX, grouped_scene, small_scene
from farm_processes import Farm, two_node_farm
from test_access import ALICE, BOB, ROOT, Secrets

from yarf import LocalServer, load_scene
from yarf.farm.job_log import format_line
from yarf.farm.scene_summary import summarize_scene
from yarf.v1 import render_pb2

# Four sample shares per job, even of small images.
COORDINATOR_ARGS = ["--shares", "4", "--min-task-work", "256"]
SHARES = 4
SEED = 7
# A line's `key=value` pairs; a quoted value is a JSON string.
FIELD = re.compile(r'(\w+)=("(?:[^"\\]|\\.)*"|[^ "]+)(?: |$)')
# Lines the coordinator does not store: gone after a restart.
SEEN_ONLY = ("task_started", "task_failed", "resumed")


def fields_of(line: str) -> dict[str, str]:
    """The line's fields, each value as text; the whole line must parse."""
    pairs = FIELD.findall(line)
    assert " ".join(f"{key}={value}" for key, value in pairs) == line, line
    return {key: json.loads(value) if value[0] == '"' else value for key, value in pairs}


def events_of(log: list[str]) -> list[str]:
    return [fields_of(line)["event"] for line in log]


@pytest.fixture(scope="module")
def farm(request: pytest.FixtureRequest) -> Iterator[Farm]:
    """A coordinator and two nodes of one render thread each."""
    with two_node_farm(request.session, COORDINATOR_ARGS) as running:
        yield running


def test_the_scene_summary_counts_what_the_scene_holds() -> None:
    summary = summarize_scene(grouped_scene())
    assert (summary.width, summary.height) == (24, 12)
    # Two world shapes and the group's one, counted once however often placed;
    # the emitting square is the light.
    assert (summary.shapes, summary.instances, summary.materials) == (3, 2, 1)
    assert (summary.lights, summary.textures, summary.media) == (1, 1, 0)
    assert summary.camera == "thin_lens"


def test_log_lines_quote_values_as_yarfd_does() -> None:
    fields = (("event", "failed"), ("job", "job-000001"), ("seconds", 1.5), ("rays", 12))
    error = 'task 2: no "bsdf"\n\tthere=1 \\'
    line = format_line((*fields, ("error", error), ("owner", "")))
    assert line == (
        "event=failed job=job-000001 seconds=1.500 rays=12 "
        r'error="task 2: no \"bsdf\"\n\u0009there=1 \\" owner=""'
    )
    assert fields_of(line)["error"] == error


def test_a_farm_job_tells_the_options_and_scene_a_yarfd_tells(farm: Farm) -> None:
    scene = grouped_scene()
    with LocalServer(threads=1) as server, server.client() as single, farm.client() as client:
        details = {}
        for name, target in (("farm", client), ("yarfd", single)):
            job_id = target.submit(scene, 8, SEED, name="details", aovs=["albedo"], threads=1)
            assert target.wait(job_id, timeout=120).state == render_pb2.SUCCEEDED
            details[name] = target.details(job_id)
    farm_job, yarfd_job = details["farm"], details["yarfd"]
    assert farm_job.options == yarfd_job.options
    assert (farm_job.options.spp, farm_job.options.threads) == (8, 1)
    assert farm_job.scene == yarfd_job.scene == summarize_scene(scene)
    # The job's own lines carry yarfd's fields in yarfd's order.
    for event in ("submitted", "started", "finished"):
        (farm_line,) = (line for line in farm_job.log if f"event={event} " in line)
        (yarfd_line,) = (line for line in yarfd_job.log if f"event={event} " in line)
        assert list(fields_of(farm_line)) == list(fields_of(yarfd_line)), (farm_line, yarfd_line)


def test_the_log_has_a_line_per_task_between_the_jobs_start_and_end(farm: Farm) -> None:
    scene = load_scene(CORNELL_BOX)
    scene.film.width = scene.film.height = 32
    with farm.client() as client:
        job_id = client.submit(scene, 64, SEED, name="logged")
        status = client.wait(job_id, timeout=120)
        assert status.state == render_pb2.SUCCEEDED, status
        log = list(client.details(job_id).log)
    lines = [fields_of(line) for line in log]
    assert all(line["job"] == job_id for line in lines), log
    events = events_of(log)
    assert events[:2] == ["submitted", "started"] and events[-1] == "finished", log
    assert lines[0]["owner"] == "local" and lines[0]["spp_total"] == "64"
    assert (lines[-1]["spp"], lines[-1]["spp_total"]) == ("64", "64")
    finished = [line for line in lines if line["event"] == "task_finished"]
    assert sorted(int(line["task"]) for line in finished) == list(range(SHARES)), log
    # The shares cover the samples [0, 64) of the whole film once.
    samples = sorted((int(line["first_sample"]), int(line["end_sample"])) for line in finished)
    assert [first for first, _ in samples[1:]] == [end for _, end in samples[:-1]]
    assert samples[0][0] == 0 and samples[-1][1] == 64
    assert {line["window"] for line in finished} == {"0,0,32,32"}
    assert {line["node"] for line in finished} <= {node.name for node in farm.nodes}
    assert sum(int(line["rays"]) for line in finished) == int(lines[-1]["rays"])
    assert int(lines[-1]["rays"]) == status.closest_hit_rays + status.shadow_rays
    # A node's task starts before it ends, on the node that ended it or before a retry.
    for index, line in enumerate(lines):
        if line["event"] == "task_started":
            ended = [i for i, later in enumerate(lines) if later.get("task") == line["task"]]
            assert max(ended) > index and lines[max(ended)]["event"] == "task_finished", log


def test_a_failed_task_and_the_jobs_failure_are_logged(farm: Farm) -> None:
    scene = small_scene()
    scene.materials[0].class_name = "no_such_surface_model"
    with farm.client() as client:
        job_id = client.submit(scene, 4, SEED, name="refused")
        assert client.wait(job_id, timeout=60).state == render_pb2.FAILED
        log = list(client.details(job_id).log)
    events = events_of(log)
    assert events[0] == "submitted" and events[-2:] == ["task_failed", "failed"], log
    failed_task, failed_job = fields_of(log[-2]), fields_of(log[-1])
    assert failed_task["node"] in {node.name for node in farm.nodes}
    assert "no_such_surface_model" in failed_task["error"]
    assert (failed_task["failures"], failed_task["max_retries"]) == ("1", "0")
    assert failed_job["error"].startswith(f"task {failed_task['task']}: ")


def test_the_stored_lines_and_the_summary_outlive_a_restart(farm: Farm) -> None:
    with farm.client() as client:
        job_id = client.submit(small_scene(16), 16, SEED, name="restarted")
        assert client.wait(job_id, timeout=60).state == render_pb2.SUCCEEDED
        before = client.details(job_id)
    assert farm.coordinator is not None
    farm.coordinator.stop()
    farm.start_coordinator()
    with farm.client() as client:
        after = client.details(job_id)
    stored = [line for line in before.log if fields_of(line)["event"] not in SEEN_ONLY]
    assert list(after.log) == stored
    # Read back from the scene bucket: nothing of it was in the new coordinator's memory.
    assert after.scene == before.scene == summarize_scene(small_scene(16))
    assert after.options == before.options and after.status == before.status


@pytest.fixture(scope="module")
def secured_farm(
    tmp_path_factory: pytest.TempPathFactory, request: pytest.FixtureRequest
) -> Iterator[Farm]:
    """A coordinator with TLS and tokens (alice and bob submit, root is admin), no node."""
    secrets = Secrets(tmp_path_factory.mktemp("secrets"))
    failed_before = request.session.testsfailed
    with Farm(coordinator_args=secrets.args(), tls_ca=secrets.cert) as running:
        running.start_coordinator()
        yield running
        if request.session.testsfailed > failed_before:
            print(running.log_tail())


def test_a_job_is_told_only_to_who_may_act_on_it(secured_farm: Farm) -> None:
    with (
        secured_farm.client(token=ALICE) as alice,
        secured_farm.client(token=BOB) as bob,
        secured_farm.client(token=ROOT) as root,
    ):
        job_id = alice.submit(small_scene(), 4, SEED, name="alice's")
        assert alice.details(job_id).status.owner == "alice"
        assert root.details(job_id).status.job_id == job_id
        with pytest.raises(grpc.RpcError) as denied:
            bob.details(job_id)
        assert denied.value.code() == grpc.StatusCode.PERMISSION_DENIED  # type: ignore[attr-defined]
        with pytest.raises(grpc.RpcError) as unknown:
            alice.details("job-999999")
        assert unknown.value.code() == grpc.StatusCode.NOT_FOUND  # type: ignore[attr-defined]
        # No node: the job never starts; cancelled in the queue it logs no start.
        alice.cancel(job_id)
        log = list(alice.details(job_id).log)
    assert events_of(log) == ["submitted", "cancelled"], log
    assert fields_of(log[-1])["owner"] == "alice"
