"""Soak: many concurrent clients against one yarfd, about 1% of calls hostile.

yarfd runs with its defaults on loopback. Each of --clients threads (500)
has its own channel and, for --seconds (120), loops: Submit a tiny job
(8×8 pixels, 1–2 spp), follow it by Watch or by polling its status, fetch
its pixels with GetResult, List the jobs. Before each call, one time in a
hundred (--hostile), the client makes a hostile call instead, drawn from
requests that once crashed, stalled or overreached yarfd: non-finite or
huge camera origins, a singular instance, a 5 MiB or a non-UTF-8 job
name, PLY headers declaring 2⁶⁴−1 elements or 2·10⁹ vertices in a few
bytes, 10¹⁰ photons, a cache file outside its folder, an 80 MiB request,
Describe and Release of random instance handles. Each must be refused
with a gRPC error or end in a FAILED job with an error; anything else
counts as accepted wrongly (UNAVAILABLE is no refusal: it counts as
unanswered). A normal call counts as an error when it raises, or when its
job does not succeed with a finite 8×8 image. Should yarfd end, the
clients stop.

Reported: calls made, errors, hostile calls refused or accepted wrongly,
p50/p99 latency (ms, measured by the clients, Python's GIL included) of
Submit, status, GetResult and List, and yarfd's resident memory and thread
count (/proc/PID/status, sampled every 0.5 s) before the load, at its peak
and after 10 s of quiet, and whether yarfd still runs. The clients run at
a lower scheduling priority than yarfd, so that they share the cores
without starving it. Results also go to out/bench/soak.json and, as one
JSON object, to the last line printed after "RESULT ".
"""

from __future__ import annotations

import argparse
import collections
import math
import os
import random
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import grpc
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from bench_report import cpu_model, print_log_tail, write_result
from conftest import small_scene

from yarf import Client, LocalServer, component, transform
from yarf.client import FINAL_STATES
from yarf.v1 import render_pb2, scene_pb2

SIZE = 8
# Seconds between two status polls of a client that polls.
POLL_SECONDS = 0.1
# Seconds a job may take from Submit to its end before the client gives up.
JOB_TIMEOUT = 120.0
SAMPLE_SECONDS = 0.5
QUIET_SECONDS = 10.0
LATENCY_KINDS = ("submit", "status", "get_result", "list")


def request(scene: scene_pb2.Scene, name: str = "soak") -> render_pb2.SubmitRequest:
    options = render_pb2.RenderOptions(spp=1, seed=1)
    return render_pb2.SubmitRequest(scene=scene, options=options, name=name)


@dataclass
class ProcessSample:
    rss_kib: int
    threads: int


def sample_process(pid: int) -> ProcessSample | None:
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    fields = dict(line.split(":", 1) for line in text.splitlines() if ":" in line)
    if "VmRSS" not in fields:  # a zombie: the process has ended
        return None
    return ProcessSample(
        rss_kib=int(fields["VmRSS"].split()[0]), threads=int(fields["Threads"].strip())
    )


class Sampler(threading.Thread):
    """Samples a process every SAMPLE_SECONDS and keeps the peaks."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid = pid
        self.peak = ProcessSample(0, 0)
        self.done = threading.Event()
        self.started = time.monotonic()
        # Seconds from the start to the first sample that found the process ended.
        self.ended_after: float | None = None
        self.gone = threading.Event()

    def run(self) -> None:
        while not self.done.is_set():
            sample = sample_process(self.pid)
            if sample is not None:
                self.peak.rss_kib = max(self.peak.rss_kib, sample.rss_kib)
                self.peak.threads = max(self.peak.threads, sample.threads)
            elif self.ended_after is None:
                self.ended_after = time.monotonic() - self.started
                self.gone.set()
            self.done.wait(SAMPLE_SECONDS)


@dataclass
class Tally:
    """What the clients saw; appends and counter updates happen under ``lock``."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    calls: int = 0
    normal_calls: int = 0
    errors: collections.Counter[str] = field(default_factory=collections.Counter)
    refused: collections.Counter[str] = field(default_factory=collections.Counter)
    failed_jobs: collections.Counter[str] = field(default_factory=collections.Counter)
    accepted: collections.Counter[str] = field(default_factory=collections.Counter)
    # Hostile calls the server did not answer at all (UNAVAILABLE: it had gone).
    unanswered: collections.Counter[str] = field(default_factory=collections.Counter)
    # The first refusal code or job error seen for each kind of hostile call.
    examples: dict[str, str] = field(default_factory=dict)
    latencies: dict[str, list[float]] = field(
        default_factory=lambda: {kind: [] for kind in LATENCY_KINDS}
    )

    def call(self, kind: str, seconds: float) -> None:
        with self.lock:
            self.calls += 1
            self.normal_calls += 1
            self.latencies[kind].append(seconds)

    def error(self, what: str) -> None:
        with self.lock:
            self.errors[what[:160]] += 1

    def hostile(self, kind: str, outcome: str, detail: str = "") -> None:
        with self.lock:
            self.calls += 1
            if outcome == "refused" and detail.startswith("UNAVAILABLE"):
                self.unanswered[kind] += 1
                return
            self.examples.setdefault(kind, detail[:100])
            if outcome == "refused":
                self.refused[kind] += 1
            elif outcome == "failed":
                self.failed_jobs[kind] += 1
            else:
                self.accepted[f"{kind}: {detail}"[:200]] += 1


# Hostile requests. Each returns ("refused" | "failed" | "accepted", detail).
Outcome = tuple[str, str]


def end_of(client: Client, job_id: str) -> Outcome:
    """How a hostile job that Submit took ended: FAILED with an error, or wrongly."""
    try:
        status = client.wait(job_id, timeout=JOB_TIMEOUT)
    except grpc.RpcError as error:
        return "accepted", f"{job_id}: Watch failed: {error.code().name}"
    if status.state == render_pb2.FAILED and status.error:
        return "failed", status.error
    state = render_pb2.JobState.Name(status.state)
    return "accepted", f"{job_id} ended {state} {status.error!r}"


def submitted(client: Client, submit_request: render_pb2.SubmitRequest) -> Outcome:
    try:
        reply = client.render_service.Submit(submit_request, timeout=client.timeout)
    except grpc.RpcError as error:
        return "refused", f"{error.code().name}: {error.details()}"
    return end_of(client, reply.job_id)


def submitted_bytes(client: Client, wire: bytes) -> Outcome:
    """Submits an already serialized request, bytes as they are."""
    submit = client.channel.unary_unary(
        "/yarf.v1.RenderService/Submit",
        request_serializer=lambda raw: raw,
        response_deserializer=render_pb2.SubmitReply.FromString,
    )
    try:
        reply = submit(wire, timeout=client.timeout)
    except grpc.RpcError as error:
        return "refused", f"{error.code().name}: {error.details()}"
    return end_of(client, reply.job_id)


def bad_camera(client: Client) -> Outcome:
    scene = small_scene(SIZE)
    scene.camera.origin.x = random.choice([math.nan, math.inf, -math.inf, 1e39])
    return submitted(client, request(scene))


def singular_instance(client: Client) -> Outcome:
    scene = small_scene(SIZE)
    ball = scene.shapes.pop()
    group = scene.groups.add(name="balls")
    group.shapes.add().CopyFrom(ball)
    placed = scene.instances.add(group="balls")
    placed.to_world.CopyFrom(transform(np.diag([0.0, 0.0, 0.0, 1.0])))
    return submitted(client, request(scene))


def mesh_scene(data: bytes) -> scene_pb2.Scene:
    scene = small_scene(SIZE)
    mesh = scene.shapes.add(name="hostile", material="grey").mesh
    mesh.data = data
    mesh.format = "ply"
    return scene


# A header declaring an element of 2⁶⁴−1 entries without properties: 66 bytes.
ENDLESS_PLY = b"ply\nformat ascii 1.0\nelement void 18446744073709551615\nend_header\n"
# 2·10⁹ vertices declared, a few bytes of them present: 120 bytes.
HUGE_PLY = (
    b"ply\nformat ascii 1.0\nelement vertex 2000000000\n"
    b"property float x\nproperty float y\nproperty float z\nend_header\n"
).ljust(120, b"0")
assert len(ENDLESS_PLY) == 66 and len(HUGE_PLY) == 120


def endless_ply(client: Client) -> Outcome:
    return submitted(client, request(mesh_scene(ENDLESS_PLY)))


def huge_ply(client: Client) -> Outcome:
    return submitted(client, request(mesh_scene(HUGE_PLY)))


def many_photons(client: Client) -> Outcome:
    submit_request = request(small_scene(SIZE))
    submit_request.options.transport.CopyFrom(component("photon_map", photons=10**10))
    return submitted(client, submit_request)


def cache_file_outside(client: Client) -> Outcome:
    submit_request = request(small_scene(SIZE))
    transport = component("irradiance_cache", cache_file="../../tokens")
    submit_request.options.transport.CopyFrom(transport)
    return submitted(client, submit_request)


MARKER = "MARKERNAME"
NOT_UTF8 = b"\xff\xfeBAD\xc3\x28\xed\xa0\x80"


def not_utf8_name(client: Client) -> Outcome:
    wire = request(small_scene(SIZE), name=MARKER).SerializeToString()
    return submitted_bytes(client, wire.replace(MARKER.encode(), NOT_UTF8))


_big_requests: dict[str, bytes] = {}
_big_requests_lock = threading.Lock()


def big_request(kind: str, make: Callable[[], render_pb2.SubmitRequest]) -> bytes:
    """A large serialized request, made once and sent by every client that draws it."""
    with _big_requests_lock:
        if kind not in _big_requests:
            _big_requests[kind] = make().SerializeToString()
        return _big_requests[kind]


def long_name(client: Client) -> Outcome:
    wire = big_request("name", lambda: request(small_scene(SIZE), name="n" * (5 << 20)))
    return submitted_bytes(client, wire)


def huge_request(client: Client) -> Outcome:
    wire = big_request("80 MiB", lambda: request(mesh_scene(b"\0" * (80 << 20))))
    return submitted_bytes(client, wire)


def random_handle(client: Client) -> Outcome:
    handle = random.getrandbits(64) | 1
    try:
        if random.random() < 0.5:
            client.describe(handle=handle)
            return "accepted", f"Describe of handle {handle} answered"
        client.release(handle)
        return "accepted", f"Release of handle {handle} answered"
    except grpc.RpcError as error:
        return "refused", f"{error.code().name}: {error.details()}"


HOSTILE: dict[str, Callable[[Client], Outcome]] = {
    "camera origin NaN/Inf/1e39": bad_camera,
    "singular instance": singular_instance,
    "5 MiB name": long_name,
    "PLY of 2^64-1 elements": endless_ply,
    "PLY of 2e9 vertices": huge_ply,
    "10^10 photons": many_photons,
    "cache_file ../../tokens": cache_file_outside,
    "non-UTF-8 name": not_utf8_name,
    "80 MiB request": huge_request,
    "random instance handle": random_handle,
}


class Soaker:
    """One client's loop."""

    def __init__(
        self, address: str, tally: Tally, deadline: float, hostile: float, gone: threading.Event
    ) -> None:
        self.address = address
        self.tally = tally
        self.deadline = deadline
        self.hostile = hostile
        self.gone = gone

    def maybe_hostile(self, client: Client) -> None:
        if random.random() >= self.hostile:
            return
        kind = random.choice(list(HOSTILE))
        try:
            outcome, detail = HOSTILE[kind](client)
        except Exception as error:  # every surprise is an outcome
            outcome, detail = "accepted", f"raised {type(error).__name__}: {error}"
        self.tally.hostile(kind, outcome, detail)

    def timed(self, client: Client, kind: str, call: Callable[[], object]) -> object:
        self.maybe_hostile(client)
        start = time.monotonic()
        result = call()
        self.tally.call(kind, time.monotonic() - start)
        return result

    def run(self) -> None:
        with Client(self.address) as client:
            while time.monotonic() < self.deadline and not self.gone.is_set():
                try:
                    self.iteration(client)
                except grpc.RpcError as error:
                    self.tally.error(f"{error.code().name}: {error.details()}")
                    time.sleep(POLL_SECONDS)
                except Exception as error:  # every failure is counted
                    self.tally.error(f"{type(error).__name__}: {error}")
                    time.sleep(POLL_SECONDS)

    def iteration(self, client: Client) -> None:
        spp = random.randint(1, 2)
        job_id = str(
            self.timed(
                client,
                "submit",
                lambda: client.submit(small_scene(SIZE), spp, random.randrange(1000), name="soak"),
            )
        )
        if random.random() < 0.5:
            self.maybe_hostile(client)
            status = client.wait(job_id, timeout=JOB_TIMEOUT)
            with self.tally.lock:
                self.tally.calls += 1
                self.tally.normal_calls += 1
        else:
            give_up = time.monotonic() + JOB_TIMEOUT
            while True:
                status = self.timed(client, "status", lambda: client.status(job_id))
                assert isinstance(status, render_pb2.JobStatus)
                if status.state in FINAL_STATES or time.monotonic() > give_up:
                    break
                time.sleep(POLL_SECONDS)
        if status.state != render_pb2.SUCCEEDED:
            state = render_pb2.JobState.Name(status.state)
            self.tally.error(f"job {state}: {status.error}")
            return
        result = self.timed(client, "get_result", lambda: client.raw(job_id))
        pixels = getattr(result, "pixels", None)
        if not isinstance(pixels, np.ndarray) or pixels.shape != (SIZE, SIZE, 3):
            self.tally.error(f"image of shape {getattr(pixels, 'shape', None)}")
        elif not np.isfinite(pixels).all():
            self.tally.error("image not finite")
        self.timed(client, "list", client.list)


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q) * 1000) if values else math.nan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="length of the load")
    parser.add_argument("--clients", type=int, default=500, help="concurrent clients")
    parser.add_argument(
        "--hostile", type=float, default=0.01, help="share of the calls that are hostile"
    )
    args = parser.parse_args()

    # Every job's result stays fetchable: 500 clients end thousands of jobs
    # a minute, beyond the default retention of 1000 ended jobs.
    server = LocalServer(extra_args=["--max-finished-jobs", "1000000"])
    server.start()
    try:
        with server.client() as client:  # warm-up: plugins, caches
            client.wait(client.submit(small_scene(SIZE), 1, 0, name="warm-up"), timeout=60)
        # Clients, made after the server, run below it.
        os.nice(10)
        time.sleep(1.0)
        before = sample_process(server.pid)
        sampler = Sampler(server.pid)
        sampler.start()
        tally = Tally()
        start = time.monotonic()
        deadline = start + args.seconds
        with ThreadPoolExecutor(max_workers=args.clients) as pool:
            for _ in range(args.clients):
                soaker = Soaker(server.address, tally, deadline, args.hostile, sampler.gone)
                pool.submit(soaker.run)
        load_seconds = time.monotonic() - start
        time.sleep(QUIET_SECONDS)
        after = sample_process(server.pid)
        sampler.done.set()
        sampler.join()
        running = server.is_running()
    finally:
        # Negative: the signal that ended it.
        exit_code = server.stop()
    log_tail = server.log.splitlines()[-40:]

    hostile_total = sum(tally.refused.values()) + sum(tally.failed_jobs.values())
    hostile_total += sum(tally.accepted.values()) + sum(tally.unanswered.values())
    latency = {
        kind: {
            "calls": len(tally.latencies[kind]),
            "p50": round(percentile(tally.latencies[kind], 50), 1),
            "p99": round(percentile(tally.latencies[kind], 99), 1),
        }
        for kind in LATENCY_KINDS
    }
    rss = {
        "before": round(before.rss_kib / 1024, 1) if before else None,
        "peak": round(sampler.peak.rss_kib / 1024, 1),
        "after": round(after.rss_kib / 1024, 1) if after else None,
    }
    threads = {
        "before": before.threads if before else None,
        "peak": sampler.peak.threads,
        "after": after.threads if after else None,
    }
    report: dict[str, object] = {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "clients": args.clients,
        "seconds": args.seconds,
        "hostile_share": args.hostile,
        "load_seconds": round(load_seconds, 1),
        "calls": tally.calls,
        "normal_calls": tally.normal_calls,
        "normal_errors": sum(tally.errors.values()),
        "hostile_calls": hostile_total,
        "hostile_refused": sum(tally.refused.values()),
        "hostile_failed_jobs": sum(tally.failed_jobs.values()),
        "hostile_accepted_wrongly": sum(tally.accepted.values()),
        "hostile_unanswered": sum(tally.unanswered.values()),
        "latency_ms": latency,
        "yarfd_rss_mib": rss,
        "yarfd_threads": threads,
        "yarfd_running": running,
        "yarfd_exit_code_at_stop": exit_code,
        "yarfd_ended_after_seconds": sampler.ended_after,
        "errors": dict(tally.errors.most_common(10)),
        "hostile_refused_by_kind": dict(tally.refused),
        "hostile_failed_by_kind": dict(tally.failed_jobs),
        "hostile_accepted_wrongly_by_kind": dict(tally.accepted),
        "hostile_examples": tally.examples,
    }

    print(f"Soak on {report['cpu']} ({report['cores']} cores):")
    print(
        f"  {args.clients} clients for {args.seconds:.0f} s ({load_seconds:.1f} s with the last "
        f"jobs), {tally.calls} calls"
    )
    print(f"  normal calls {tally.normal_calls}, errors {report['normal_errors']}")
    for what, count in tally.errors.most_common(10):
        print(f"    {count:6d} × {what}")
    print(
        f"  hostile calls {hostile_total}: refused {report['hostile_refused']}, "
        f"failed their job {report['hostile_failed_jobs']}, "
        f"accepted wrongly {report['hostile_accepted_wrongly']}, "
        f"unanswered (UNAVAILABLE) {report['hostile_unanswered']}"
    )
    for kind in HOSTILE:
        print(
            f"    {kind:28s} refused {tally.refused[kind]:4d}  "
            f"failed their job {tally.failed_jobs[kind]:4d}  {tally.examples.get(kind, '')}"
        )
    for what, count in tally.accepted.items():
        print(f"    accepted wrongly {count:4d} × {what}")
    print("  latency (ms)        calls      p50      p99")
    for kind, figures in latency.items():
        print(f"    {kind:14s} {figures['calls']:9d} {figures['p50']:8.1f} {figures['p99']:8.1f}")
    print(f"  yarfd RSS (MiB)  before {rss['before']}  peak {rss['peak']}  after {rss['after']}")
    print(
        f"  yarfd threads    before {threads['before']}  peak {threads['peak']}  "
        f"after {threads['after']}"
    )
    if running:
        print("  yarfd still running: yes")
    else:
        print(
            f"  yarfd still running: NO (exit code {exit_code}, found ended about "
            f"{sampler.ended_after} s into the load)"
        )
    if not running:
        print_log_tail(log_tail)
    write_result("soak", report)


if __name__ == "__main__":
    main()
