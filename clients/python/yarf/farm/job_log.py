"""A farm job's event log as GetJob returns it: yarfd's ``key=value`` lines.

yarfd keeps the lines it logs for a job (server/src/service/job_events.cc).
The coordinator keeps no log of its own: it rebuilds the lines from its
job table (submitted, started, every task's result, the end), so they
outlive a restart, and adds what it saw but does not store (a node
starting a task, a task failing, a restart resuming the job).

Job lines carry yarfd's fields (``event job owner attempt spp spp_total
seconds rays``, then ``queue_seconds`` or ``error`` where they apply);
task lines name the task, its node, its samples [first_sample,
end_sample) and its pixel window ``x0,y0,x1,y1``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from yarf.farm.tasks import Task
from yarf.v1 import render_pb2

# As yarfd: the last lines of a job, at most.
MAX_LINES = 200

Value = str | int | float
Fields = tuple[tuple[str, Value], ...]

_END_EVENTS = {
    render_pb2.SUCCEEDED: "finished",
    render_pb2.FAILED: "failed",
    render_pb2.CANCELLED: "cancelled",
}


@dataclass(frozen=True)
class Event:
    """One line's fields, and when it happened (``time.time()``) to place it among the others."""

    at: float
    fields: Fields


@dataclass(frozen=True)
class TaskResult:
    """A task's stored result, as its line needs it."""

    task: int
    node: str
    rays: int
    finished_at: float


def _quoted(text: str) -> str:
    """``text`` as a JSON string, escaped as yarfd escapes it."""
    out = ['"']
    for c in text:
        if c in '"\\':
            out.append("\\" + c)
        elif c == "\n":
            out.append("\\n")
        elif ord(c) < 0x20:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(c)
    out.append('"')
    return "".join(out)


def format_line(fields: Iterable[tuple[str, Value]]) -> str:
    """``event=started job=job-000001 ...``: a text that is empty or holds a space, a quote,
    ``=``, a backslash or a line break is quoted; a float has three decimals."""
    parts = []
    for key, value in fields:
        if isinstance(value, float):
            text = f"{value:.3f}"
        elif isinstance(value, int):
            text = str(value)
        else:
            plain = value and not any(c in value for c in ' "=\\\t\n\r')
            text = value if plain else _quoted(value)
        parts.append(f"{key}={text}")
    return " ".join(parts)


def job_fields(
    event: str,
    job_id: str,
    owner: str,
    *,
    attempt: int,
    spp: int,
    spp_total: int,
    seconds: float,
    rays: int,
    **extra: Value,
) -> Fields:
    """A job line's fields in yarfd's order; empty extras are left out."""
    fields: list[tuple[str, Value]] = [
        ("event", event),
        ("job", job_id),
        ("owner", owner),
        ("attempt", attempt),
        ("spp", spp),
        ("spp_total", spp_total),
        ("seconds", float(seconds)),
        ("rays", rays),
    ]
    fields += [(key, value) for key, value in extra.items() if value != ""]
    return tuple(fields)


def status_fields(event: str, status: render_pb2.JobStatus, **extra: Value) -> Fields:
    """A job line's fields as ``status`` tells them (its error included)."""
    return job_fields(
        event,
        status.job_id,
        status.owner,
        attempt=status.attempts,
        spp=status.samples_done,
        spp_total=status.samples_total,
        seconds=status.elapsed_seconds,
        rays=status.closest_hit_rays + status.shadow_rays,
        **extra,
        error=status.error,
    )


def task_fields(event: str, job_id: str, task: Task, node: str = "", **extra: Value) -> Fields:
    """A task line's fields; an empty node (a task JetStream gave up on) is left out."""
    w = task.window
    fields: list[tuple[str, Value]] = [("event", event), ("job", job_id), ("task", task.index)]
    if node:
        fields.append(("node", node))
    fields += [
        ("first_sample", task.first_sample),
        ("end_sample", task.end_sample),
        ("window", f"{w.x0},{w.y0},{w.x1},{w.y1}"),
    ]
    fields += [(key, value) for key, value in extra.items() if value != ""]
    return tuple(fields)


def job_log(
    status: render_pb2.JobStatus,
    *,
    first_sample: int,
    submitted_at: float,
    started_at: float | None,
    tasks: Sequence[Task],
    results: Iterable[TaskResult],
    seen: Iterable[Event],
) -> list[str]:
    """The job's lines, oldest first, the last MAX_LINES of them.

    ``status`` is the job's now; ``results`` its stored task results;
    ``seen`` what the coordinator saw of it and did not store.
    """
    submitted = job_fields(
        "submitted",
        status.job_id,
        status.owner,
        attempt=0,
        spp=first_sample,
        spp_total=status.samples_total,
        seconds=0.0,
        rays=0,
    )
    events = list(seen)
    # A job cancelled in the queue has a start time too, but no attempt.
    if started_at is not None and status.attempts > 0:
        started = job_fields(
            "started",
            status.job_id,
            status.owner,
            attempt=1,
            spp=first_sample,
            spp_total=status.samples_total,
            seconds=0.0,
            rays=0,
            queue_seconds=max(0.0, started_at - submitted_at),
        )
        # Before what was seen at the same moment (the heartbeat that started the job).
        events.insert(0, Event(started_at, started))
    events += [
        Event(
            result.finished_at,
            task_fields(
                "task_finished", status.job_id, tasks[result.task], result.node, rays=result.rays
            ),
        )
        for result in results
        if result.task < len(tasks)
    ]
    # Stable: of two lines at the same time, the one added first stays first.
    events.sort(key=lambda event: event.at)
    # A job's first and last lines stay first and last whatever the clocks say.
    lines = [submitted, *(event.fields for event in events)]
    end = _END_EVENTS.get(status.state)
    if end is not None:
        lines.append(status_fields(end, status))
    return [format_line(fields) for fields in lines[-MAX_LINES:]]
