"""Kill loop: yarfd killed with SIGKILL at random moments while clients submit.

One state folder (--state-dir, else a temporary one) serves a yarfd that
is killed --kills times (40), each a random 0.2–3 s after it began to
serve, and started again on the same folder at once. Throughout, client
threads submit small jobs (16×16 pixels) of a mix of spp, from 1 to 8192
(the longest take seconds, so that jobs are running at most kills), each
under a name of its own. Every job id a Submit returned is recorded as
acknowledged. After the last restart the bench waits (at most --timeout
seconds) until every acknowledged job has ended, then counts:

- lost: acknowledged ids the server does not know;
- duplicated: names held by more than one job, or by a job of another id
  than its Submit returned;
- wrong: SUCCEEDED jobs whose image differs from a render of the same
  scene, spp and seed by a separate server on a clean state folder
  (renders are deterministic per seed, resumed from checkpoints or not);
- failed by the crash rule ("... times in a row"), other FAILED jobs
  (with their errors), and jobs that did not end in time.

The target is 0 of each. The server checkpoints every 0.2 s and keeps all
ended jobs. Results also go to out/bench/kill_loop.json and, as one JSON
object, to the last line printed after "RESULT ".
"""

from __future__ import annotations

import argparse
import collections
import os
import random
import secrets
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import grpc
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from bench_report import cpu_model, print_log_tail, write_result
from conftest import small_scene

from yarf import Client, LocalServer
from yarf.client import FINAL_STATES
from yarf.v1 import render_pb2

SIZE = 16
# Samples per pixel of the jobs, drawn uniformly: most kills find jobs running.
SPPS = (1, 16, 256, 2048, 2048, 8192, 8192)
SEEDS = (1, 2, 3)
SERVER_ARGS = ("--checkpoint-seconds", "0.2", "--max-finished-jobs", "1000000")
# Seconds from a server's start to its kill.
KILL_AFTER = (0.2, 3.0)
# Seconds a submitter waits between two Submits.
SUBMIT_EVERY = (0.3, 1.5)
CRASH_RULE = "times in a row"


@dataclass(frozen=True)
class Submission:
    job_id: str
    spp: int
    seed: int


class Current:
    """The address of the server now serving, and how many servers came before."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.address = ""
        self.generation = 0

    def set(self, address: str) -> None:
        with self.lock:
            self.address = address
            self.generation += 1

    def get(self) -> tuple[str, int]:
        with self.lock:
            return self.address, self.generation


class Submitter(threading.Thread):
    """Submits jobs to whichever server serves, each under a new name."""

    def __init__(
        self,
        index: int,
        prefix: str,
        current: Current,
        acknowledged: dict[str, Submission],
        unacknowledged: list[str],
        stop: threading.Event,
    ) -> None:
        super().__init__(daemon=True)
        self.index = index
        self.prefix = prefix
        self.current = current
        self.acknowledged = acknowledged
        self.unacknowledged = unacknowledged
        self.stop = stop
        self.scene = small_scene(SIZE)

    def run(self) -> None:
        client: Client | None = None
        seen = -1
        count = 0
        while not self.stop.is_set():
            address, generation = self.current.get()
            if generation != seen:
                if client is not None:
                    client.close()
                client = Client(address, timeout=10)
                seen = generation
            assert client is not None
            count += 1
            name = f"{self.prefix}-{self.index}-{count:05d}"
            spp, seed = random.choice(SPPS), random.choice(SEEDS)
            try:
                job_id = client.submit(self.scene, spp, seed, name=name)
            except grpc.RpcError as error:
                # Down, or killed during the call: nothing was promised.
                self.unacknowledged.append(f"{name} {error.code().name}")
                self.wait_for_restart(generation)
                continue
            self.acknowledged[name] = Submission(job_id, spp, seed)
            self.stop.wait(random.uniform(*SUBMIT_EVERY))
        if client is not None:
            client.close()

    def wait_for_restart(self, generation: int) -> None:
        """Until the next server serves (at most 10 s: the failure may be another)."""
        deadline = time.monotonic() + 10
        while self.current.get()[1] == generation and time.monotonic() < deadline:
            if self.stop.wait(0.02):
                return


def start_server(server: LocalServer) -> None:
    """Starts the server, waiting out a binary being replaced by a build (at most 60 s)."""
    for _ in range(60):
        try:
            server.start()
            return
        except OSError:
            time.sleep(1.0)
    server.start()


def running_jobs(address: str) -> int:
    """Jobs RUNNING on the server now (-1 when it does not answer)."""
    try:
        with Client(address, timeout=2) as client:
            return sum(status.state == render_pb2.RUNNING for status in client.list())
    except grpc.RpcError:
        return -1


def wait_until_ended(client: Client, ids: set[str], timeout: float) -> list[render_pb2.JobStatus]:
    """The server's list once every job of ``ids`` it knows has ended, or at the timeout."""
    deadline = time.monotonic() + timeout
    while True:
        jobs = client.list()
        pending = [job for job in jobs if job.job_id in ids and job.state not in FINAL_STATES]
        if not pending or time.monotonic() > deadline:
            return jobs
        time.sleep(1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=40, help="SIGKILLs of yarfd")
    parser.add_argument("--state-dir", type=Path, help="the state folder (default: a new one)")
    parser.add_argument("--submitters", type=int, default=2, help="client threads submitting")
    parser.add_argument(
        "--timeout", type=float, default=600.0, help="seconds to wait for the jobs to end"
    )
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="yarf-kill-loop-") as folder:
        state_dir = args.state_dir or Path(folder) / "state"
        run(args, state_dir)


def run(args: argparse.Namespace, state_dir: Path) -> None:
    prefix = f"kill-loop-{secrets.token_hex(4)}"
    acknowledged: dict[str, Submission] = {}
    unacknowledged: list[str] = []
    current = Current()
    stop = threading.Event()
    server = LocalServer(state_dir=state_dir, extra_args=list(SERVER_ARGS))
    start_server(server)
    current.set(server.address)
    submitters = [
        Submitter(index, prefix, current, acknowledged, unacknowledged, stop)
        for index in range(args.submitters)
    ]
    for submitter in submitters:
        submitter.start()
    running_at_kill: list[int] = []
    restart_seconds: list[float] = []
    crashes: list[str] = []
    began = time.monotonic()
    try:
        for _ in range(args.kills):
            time.sleep(random.uniform(*KILL_AFTER))
            running_at_kill.append(running_jobs(server.address))
            if not server.is_running():
                # It ended before its kill: a crash of its own.
                crashes.append("\n".join(server.log.splitlines()[-15:]))
            server.kill()
            restarted = time.monotonic()
            start_server(server)
            restart_seconds.append(time.monotonic() - restarted)
            current.set(server.address)
        stop.set()
        for submitter in submitters:
            submitter.join()
        loop_seconds = time.monotonic() - began
        ids = {submission.job_id for submission in acknowledged.values()}
        with server.client() as client:
            jobs = wait_until_ended(client, ids, args.timeout)
            by_id = {job.job_id: job for job in jobs}
            images = {
                job.job_id: client.image(job.job_id)
                for job in jobs
                if job.job_id in ids and job.state == render_pb2.SUCCEEDED
            }
            lost = []
            for name, submission in acknowledged.items():
                if submission.job_id in by_id:
                    continue
                try:
                    client.status(submission.job_id)
                except grpc.RpcError as error:
                    if error.code() == grpc.StatusCode.NOT_FOUND:
                        lost.append(f"{name} ({submission.job_id})")
                        continue
                    raise
    finally:
        stop.set()
        server.stop()
    log_tail = server.log.splitlines()[-30:]

    names = collections.Counter(job.name for job in jobs if job.name.startswith(prefix))
    duplicated = sorted(name for name, count in names.items() if count > 1)
    for job in jobs:
        submission = acknowledged.get(job.name)
        if submission is not None and job.job_id != submission.job_id:
            duplicated.append(f"{job.name}: acknowledged {submission.job_id}, held by {job.job_id}")
    stored_unacknowledged = sum(names[entry.split()[0]] > 0 for entry in unacknowledged)
    cut_off = collections.Counter(entry.split()[1] for entry in unacknowledged)

    crash_rule: list[str] = []
    other_failed: list[str] = []
    cancelled: list[str] = []
    not_ended: list[str] = []
    resumed = 0
    for name, submission in sorted(acknowledged.items()):
        job = by_id.get(submission.job_id)
        if job is None:
            continue
        resumed += job.attempts > 1
        if job.state == render_pb2.FAILED:
            failure = f"{name} ({job.job_id}, {submission.spp} spp): {job.error}"
            (crash_rule if CRASH_RULE in job.error else other_failed).append(failure)
        elif job.state == render_pb2.CANCELLED:
            cancelled.append(f"{name} ({job.job_id})")
        elif job.state not in FINAL_STATES:
            state = render_pb2.JobState.Name(job.state)
            not_ended.append(f"{name} ({job.job_id}) {state}")

    # References: the same scene, spp and seed on a clean server.
    wrong: list[str] = []
    succeeded = {
        name: submission for name, submission in acknowledged.items() if submission.job_id in images
    }
    combos = sorted({(submission.spp, submission.seed) for submission in succeeded.values()})
    with LocalServer() as clean, clean.client() as client:
        scene = small_scene(SIZE)
        references = {
            (spp, seed): client.render(scene, spp, seed, name="reference", timeout=600).pixels
            for spp, seed in combos
        }
    for name, submission in sorted(succeeded.items()):
        image = images[submission.job_id]
        reference = references[(submission.spp, submission.seed)]
        if image.shape != reference.shape or not np.allclose(
            image, reference, rtol=1e-5, atol=1e-6
        ):
            difference = (
                float(np.abs(image - reference).max()) if image.shape == reference.shape else None
            )
            wrong.append(
                f"{name} ({submission.job_id}, {submission.spp} spp, seed {submission.seed}): "
                f"largest difference {difference}"
            )

    answered = [count for count in running_at_kill if count >= 0]
    details = {
        "lost": lost,
        "duplicated": duplicated,
        "wrong": wrong,
        "failed_by_crash_rule": crash_rule,
        "other_failed": other_failed,
        "cancelled": cancelled,
        "not_ended": not_ended,
    }
    report: dict[str, object] = {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "kills": len(running_at_kill),
        "kills_with_jobs_running": sum(count > 0 for count in answered),
        "loop_seconds": round(loop_seconds, 1),
        "restart_seconds_mean": round(float(np.mean(restart_seconds)), 3),
        "restart_seconds_max": round(max(restart_seconds), 3),
        "ended_before_their_kill": len(crashes),
        "submissions": len(acknowledged) + len(unacknowledged),
        "acknowledged": len(acknowledged),
        "unacknowledged": len(unacknowledged),
        "unacknowledged_but_stored": stored_unacknowledged,
        "unacknowledged_by_code": dict(cut_off),
        "succeeded": len(succeeded),
        "resumed_after_a_kill": resumed,
        "lost": len(lost),
        "duplicated": len(duplicated),
        "wrong": len(wrong),
        "failed_by_crash_rule": len(crash_rule),
        "other_failed": len(other_failed),
        "cancelled": len(cancelled),
        "not_ended": len(not_ended),
        "details": details,
        "crash_log_tails": crashes,
    }

    print(f"Kill loop on {report['cpu']} ({report['cores']} cores):")
    print(
        f"  {report['kills']} kill -9s in {loop_seconds:.0f} s, "
        f"{report['kills_with_jobs_running']} of them with jobs running; restart "
        f"{report['restart_seconds_mean']} s mean, {report['restart_seconds_max']} s max"
    )
    print(
        f"  submissions {report['submissions']}: acknowledged {len(acknowledged)}, "
        f"failed or cut off by a kill {len(unacknowledged)} {dict(cut_off)} "
        f"({stored_unacknowledged} of them stored)"
    )
    print(
        f"  acknowledged jobs: succeeded {len(succeeded)} "
        f"({resumed} of all ran again after a kill), compared against "
        f"{len(combos)} reference renders"
    )
    for label, items in details.items():
        print(f"  {label.replace('_', ' '):22s} {len(items)}")
        for item in items[:20]:
            print(f"    {item}")
    if crashes:
        print(f"  yarfd ended on its own before {len(crashes)} of the kills; log tails:")
        for tail in crashes:
            for line in tail.splitlines():
                print(f"    {line}")
            print("    --")
    if any(details.values()):
        print_log_tail(log_tail)
    write_result("kill_loop", report)


if __name__ == "__main__":
    main()
