"""How many of a process's threads did a job's work, from /proc's CPU ticks."""

from __future__ import annotations

from pathlib import Path

from yarf import Client
from yarf.v1 import render_pb2


def cpu_ticks_by_thread(pid: int) -> dict[int, int]:
    """User and system clock ticks each thread of process ``pid`` has used."""
    ticks = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            # After the command's ")": state is field 3, utime 14, stime 15.
            fields = (task / "stat").read_text().rpartition(")")[2].split()
        except OSError:
            continue  # the thread ended meanwhile
        ticks[int(task.name)] = int(fields[11]) + int(fields[12])
    return ticks


def threads_that_worked(pid: int, client: Client, job_id: str) -> int:
    """Waits for job ``job_id`` of yarfd ``pid``; how many of its threads each
    did at least a fifth of the work meanwhile (gRPC's threads do next to none)."""
    before = cpu_ticks_by_thread(pid)
    status = client.wait(job_id, timeout=300)
    assert status.state == render_pb2.SUCCEEDED, status.error
    after = cpu_ticks_by_thread(pid)
    used = [after[thread] - before.get(thread, 0) for thread in after]
    return sum(1 for ticks in used if ticks > 0.2 * sum(used))
