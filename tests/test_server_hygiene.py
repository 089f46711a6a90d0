"""yarfd as an operator runs it: one server per port, a health check any
gRPC tool can call through reflection, a log line per job event (key=value
or JSON) and Prometheus metrics on an opt-in HTTP port.
"""

from __future__ import annotations

import json
import re
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from typing import Any

import grpc
import pytest
from conftest import small_scene
from google.protobuf import descriptor_pool, message_factory
from grpc_reflection.v1alpha.proto_reflection_descriptor_database import (
    ProtoReflectionDescriptorDatabase,
)

from yarf import LocalServer
from yarf.server import find_yarfd
from yarf.v1 import render_pb2

LogEvent = dict[str, Any]


@pytest.fixture(scope="module")
def text_log_server() -> Iterator[LocalServer]:
    """A yarfd with the default (key=value) job log, a checkpoint after every
    sample pass, and metrics on a free port."""
    args = ["--metrics", "127.0.0.1:0", "--checkpoint-seconds", "0"]
    with LocalServer(extra_args=args) as local:
        yield local


@pytest.fixture(scope="module")
def json_log_server() -> Iterator[LocalServer]:
    with LocalServer(extra_args=["--log-json"]) as local:
        yield local


def run_yarfd(*args: str) -> subprocess.CompletedProcess[str]:
    """A yarfd that is expected to stop at once, with a state folder of its own."""
    state = tempfile.mkdtemp(prefix="yarfd-state-")
    try:
        return subprocess.run(
            [str(find_yarfd()), "--state-dir", state, *args],
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            timeout=30,
        )
    finally:
        shutil.rmtree(state, ignore_errors=True)


def assert_refused(run: subprocess.CompletedProcess[str], address: str) -> None:
    assert run.returncode != 0, f"yarfd started on {address}, held by another process"
    lines = [line for line in run.stderr.splitlines() if address in line]
    assert len(lines) == 1, run.stderr
    assert "in use" in lines[0] and "cannot listen" in lines[0], lines[0]
    assert run.stderr.strip() == lines[0], f"more than the one line:\n{run.stderr}"


def test_second_yarfd_on_the_port_of_a_running_one_refuses_to_start(
    text_log_server: LocalServer,
) -> None:
    address = text_log_server.address
    assert_refused(run_yarfd("--listen", address), address)
    assert text_log_server.is_running()
    with text_log_server.client() as client:
        assert client.is_serving()


def test_yarfd_refuses_a_port_any_process_holds() -> None:
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        address = f"127.0.0.1:{holder.getsockname()[1]}"
        assert_refused(run_yarfd("--listen", address), address)


def test_yarfd_refuses_a_metrics_port_another_process_holds() -> None:
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        address = f"127.0.0.1:{holder.getsockname()[1]}"
        assert_refused(run_yarfd("--listen", "127.0.0.1:0", "--metrics", address), address)


def test_health_check_is_callable_with_descriptors_resolved_through_reflection(
    text_log_server: LocalServer,
) -> None:
    # As grpcurl does: nothing compiled in, every type from the server.
    with grpc.insecure_channel(text_log_server.address) as channel:
        pool = descriptor_pool.DescriptorPool(ProtoReflectionDescriptorDatabase(channel))
        service = pool.FindServiceByName("grpc.health.v1.Health")
        check = service.methods_by_name["Check"]
        request_class = message_factory.GetMessageClass(check.input_type)
        response_class = message_factory.GetMessageClass(check.output_type)
        call = channel.unary_unary(
            f"/{service.full_name}/{check.name}",
            request_serializer=request_class.SerializeToString,
            response_deserializer=response_class.FromString,
        )
        response = call(request_class(service=""), timeout=10)
    status = check.output_type.fields_by_name["status"].enum_type
    assert status.values_by_number[response.status].name == "SERVING"


@pytest.mark.skipif(shutil.which("grpcurl") is None, reason="grpcurl is not installed")
def test_grpcurl_calls_the_health_check(text_log_server: LocalServer) -> None:
    run = subprocess.run(
        ["grpcurl", "-plaintext", text_log_server.address, "grpc.health.v1.Health/Check"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout) == {"status": "SERVING"}


KEY_VALUE = re.compile(r'(\w+)=("(?:[^"\\]|\\.)*"|\S+)')


def text_events(log: str) -> list[LogEvent]:
    """The key=value job event lines of a yarfd log, numbers as numbers."""
    events = []
    for line in log.splitlines():
        if not line.startswith("event="):
            continue
        event: LogEvent = {}
        for key, value in KEY_VALUE.findall(line):
            event[key] = json.loads(value) if value.startswith('"') else value
            if re.fullmatch(r"\d+", value):
                event[key] = int(value)
            elif re.fullmatch(r"\d+\.\d+", value):
                event[key] = float(value)
        events.append(event)
    return events


def json_events(log: str) -> list[LogEvent]:
    return [json.loads(line) for line in log.splitlines() if line.startswith('{"event":')]


def events_of(
    server: LocalServer, parse: Callable[[str], list[LogEvent]], job_id: str, last: str
) -> list[LogEvent]:
    """The job's events once its `last` event is logged (it follows the state by a moment)."""
    deadline = time.monotonic() + 10
    while True:
        events = [event for event in parse(server.log) if event.get("job") == job_id]
        if any(event["event"] == last for event in events) or time.monotonic() > deadline:
            return events
        time.sleep(0.05)


def render_one_that_succeeds_and_one_that_fails(server: LocalServer) -> tuple[str, str]:
    with server.client() as client:
        good = client.submit(small_scene(), spp=4, seed=1, name="hygiene good")
        assert client.wait(good, timeout=60).state == render_pb2.SUCCEEDED
        scene = small_scene()
        broken = scene.shapes.add(name="broken_mesh", material="grey")
        broken.mesh.data = b"v zero 0 0\nf 1 2 3\n"
        broken.mesh.format = "obj"
        bad = client.submit(scene, spp=4, seed=1)
        assert client.wait(bad, timeout=60).state == render_pb2.FAILED
    return good, bad


def check_job_events(
    server: LocalServer, parse: Callable[[str], list[LogEvent]], good: str, bad: str
) -> None:
    events = events_of(server, parse, good, "finished")
    checkpoints = [event for event in events if event["event"] == "checkpoint"]
    events = [event for event in events if event["event"] != "checkpoint"]
    assert [event["event"] for event in events] == ["submitted", "started", "finished"], events
    submitted, started, finished = events
    # Only the text server checkpoints (after every pass but the last).
    if checkpoints:
        assert [event["spp"] for event in checkpoints] == sorted({e["spp"] for e in checkpoints})
        assert 0 < checkpoints[-1]["spp"] < 4
    assert submitted["owner"] == finished["owner"] != ""
    assert submitted["spp"] == 0 and submitted["spp_total"] == 4
    assert started["attempt"] == 1 and started["queue_seconds"] >= 0
    assert finished["spp"] == 4 and finished["rays"] > 0 and finished["seconds"] > 0
    assert "error" not in finished

    events = events_of(server, parse, bad, "failed")
    assert [event["event"] for event in events] == ["submitted", "started", "failed"], events
    assert "broken_mesh" in events[-1]["error"], events[-1]


def test_job_events_are_logged_as_key_value_lines(text_log_server: LocalServer) -> None:
    good, bad = render_one_that_succeeds_and_one_that_fails(text_log_server)
    check_job_events(text_log_server, text_events, good, bad)
    # Values with spaces are quoted: a line still splits into its fields.
    failed = events_of(text_log_server, text_events, bad, "failed")[-1]
    line = next(
        line
        for line in text_log_server.log.splitlines()
        if f"job={bad} " in line and "failed" in line
    )
    assert 'error="' in line and set(failed) >= {"event", "job", "owner", "spp", "seconds", "rays"}


def test_job_events_are_logged_as_json_lines_with_log_json(json_log_server: LocalServer) -> None:
    good, bad = render_one_that_succeeds_and_one_that_fails(json_log_server)
    check_job_events(json_log_server, json_events, good, bad)
    assert not any(e["event"] == "checkpoint" for e in json_events(json_log_server.log))
    assert not text_events(json_log_server.log)


def test_checkpoints_are_logged_with_the_samples_they_hold(text_log_server: LocalServer) -> None:
    good, _ = render_one_that_succeeds_and_one_that_fails(text_log_server)
    events = events_of(text_log_server, text_events, good, "finished")
    assert any(event["event"] == "checkpoint" for event in events), events


def test_a_cancelled_job_is_logged_cancelled(json_log_server: LocalServer) -> None:
    with json_log_server.client() as client:
        job = client.submit(small_scene(64), spp=100_000, seed=1, name="to cancel")
        client.cancel(job)
        assert client.wait(job, timeout=60).state == render_pb2.CANCELLED
    events = events_of(json_log_server, json_events, job, "cancelled")
    assert events[0]["event"] == "submitted" and events[-1]["event"] == "cancelled", events
    assert events[-1]["spp"] < 100_000


def metrics_port(server: LocalServer) -> int:
    found = re.search(r"yarfd metrics on \S+ \(port (\d+)\)", server.log)
    assert found, server.log
    return int(found.group(1))


SAMPLE = re.compile(r"^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[^}]*\})? (\S+)$")


def scrape(port: int) -> dict[str, float]:
    """The samples of an exposition, keyed by name and labels as written."""
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=10) as response:
        assert response.headers["Content-Type"].startswith("text/plain; version=0.0.4")
        text = response.read().decode()
    samples: dict[str, float] = {}
    for line in text.splitlines():
        if not line or line.startswith("#"):
            continue
        found = SAMPLE.match(line)
        assert found, f"not an exposition line: {line!r}"
        samples[found.group(1) + (found.group(2) or "")] = float(found.group(3))
    return samples


def test_metrics_are_served_over_http_and_follow_a_render(text_log_server: LocalServer) -> None:
    port = metrics_port(text_log_server)
    before = scrape(port)
    for state in ("QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED"):
        assert f'yarf_jobs{{state="{state}"}}' in before, before

    with text_log_server.client() as client:
        job = client.submit(small_scene(), spp=8, seed=2, name="metrics")
        assert client.wait(job, timeout=60).state == render_pb2.SUCCEEDED
    events_of(text_log_server, text_events, job, "finished")
    after = scrape(port)

    def grew(name: str) -> float:
        return after.get(name, 0) - before.get(name, 0)

    assert grew('yarf_jobs{state="SUCCEEDED"}') == 1
    assert grew("yarf_pixel_samples_total") >= 8 * 16 * 16
    assert grew("yarf_rays_total") > 0
    assert grew('yarf_job_events_total{event="finished"}') == 1
    assert grew("yarf_job_queue_wait_seconds_count") == 1
    submit = 'yarf_rpc_duration_seconds_count{method="/yarf.v1.RenderService/Submit",code="OK"}'
    assert grew(submit) >= 1, sorted(after)
    # A histogram's buckets are cumulative, up to its count.
    assert (
        after['yarf_job_queue_wait_seconds_bucket{le="+Inf"}']
        == after["yarf_job_queue_wait_seconds_count"]
    )


def test_metrics_endpoint_answers_only_metrics(text_log_server: LocalServer) -> None:
    with pytest.raises(urllib.error.HTTPError) as caught:
        urllib.request.urlopen(f"http://127.0.0.1:{metrics_port(text_log_server)}/", timeout=10)
    assert caught.value.code == 404


def test_metrics_are_off_by_default(json_log_server: LocalServer) -> None:
    assert "metrics" not in json_log_server.log.lower()


def test_yarfd_usage_names_the_new_options() -> None:
    run = run_yarfd("--help")
    assert "--log-json" in run.stderr and "--metrics HOST:PORT" in run.stderr


def test_yarfd_started_for_a_process_that_has_ended_stops_at_once() -> None:
    # --parent-pid names the process yarfd stops with; one that is not its
    # parent any more (here: never was) has ended as far as yarfd can tell.
    run = run_yarfd("--parent-pid", "999999999")
    assert run.returncode == 1
    assert "the process 999999999 that started it has ended" in run.stderr
