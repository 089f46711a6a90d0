"""The coordinator's job table: SQLite in the state folder.

A job, its tasks and every task result are committed here before anyone
is told about them (Submit's reply, a result's ack), so a coordinator that
was killed resumes from this file and the streams alone.
"""

from __future__ import annotations

import sqlite3
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, fields
from pathlib import Path

from yarf.farm.job_log import TaskResult
from yarf.farm.merge import TaskImage
from yarf.farm.tasks import Task, Window
from yarf.v1 import render_pb2

# The states of an ended job, which retention may delete.
_ENDED = (render_pb2.SUCCEEDED, render_pb2.FAILED, render_pb2.CANCELLED)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS jobs (
    seq INTEGER PRIMARY KEY,
    id TEXT UNIQUE NOT NULL,
    name TEXT NOT NULL,
    owner TEXT NOT NULL,
    priority INTEGER NOT NULL,
    generation INTEGER NOT NULL,
    state INTEGER NOT NULL,
    error TEXT NOT NULL,
    submitted_at REAL NOT NULL,
    started_at REAL,
    finished_at REAL,
    attempts INTEGER NOT NULL,
    failures INTEGER NOT NULL,
    max_retries INTEGER NOT NULL,
    scene_hash TEXT NOT NULL,
    options BLOB NOT NULL,
    width INTEGER NOT NULL,
    height INTEGER NOT NULL,
    spp INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS tasks (
    job TEXT NOT NULL,
    task INTEGER NOT NULL,
    first_sample INTEGER NOT NULL,
    end_sample INTEGER NOT NULL,
    x0 INTEGER NOT NULL, y0 INTEGER NOT NULL, x1 INTEGER NOT NULL, y1 INTEGER NOT NULL,
    crop INTEGER NOT NULL,
    PRIMARY KEY (job, task)
);
CREATE TABLE IF NOT EXISTS results (
    job TEXT NOT NULL,
    task INTEGER NOT NULL,
    node TEXT NOT NULL,
    work INTEGER NOT NULL,
    closest_hit_rays INTEGER NOT NULL,
    shadow_rays INTEGER NOT NULL,
    finished_at REAL NOT NULL,
    image BLOB NOT NULL,
    PRIMARY KEY (job, task)
);
"""


@dataclass
class JobRecord:
    """One row of the job table; ``options`` is the serialized RenderOptions after defaults."""

    seq: int
    id: str
    name: str
    owner: str
    priority: int
    # Bumped when the job's queued tasks move to another tier, so that
    # their new messages are not taken for duplicates of the old ones.
    generation: int
    state: int
    error: str
    submitted_at: float
    started_at: float | None
    finished_at: float | None
    attempts: int
    failures: int
    max_retries: int
    scene_hash: str
    options: bytes
    width: int
    height: int
    spp: int


_JOB_COLUMNS = [f.name for f in fields(JobRecord)]
_MUTABLE_COLUMNS = [
    "priority",
    "generation",
    "state",
    "error",
    "started_at",
    "finished_at",
    "attempts",
    "failures",
]


@dataclass(frozen=True)
class ResultTotals:
    tasks: int
    work: int
    closest_hit_rays: int
    shadow_rays: int


class JobStore:
    """Jobs, tasks and task results in ``<state_dir>/jobs.sqlite3`` (WAL)."""

    def __init__(self, state_dir: Path) -> None:
        state_dir.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(state_dir / "jobs.sqlite3", isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        # In WAL mode, NORMAL makes every commit survive the process being
        # killed (a reply or an ack follows each one); only a power loss
        # may take back the last ones.
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.executescript(_SCHEMA)
        row = self._db.execute("SELECT value FROM meta WHERE key = 'farm'").fetchone()
        if row is None:
            # Names this job table in message ids, so that messages of
            # another table (a state folder started afresh) never pass for ours.
            self.farm_id = uuid.uuid4().hex[:12]
            self._db.execute("INSERT INTO meta VALUES ('farm', ?)", (self.farm_id,))
        else:
            self.farm_id = str(row[0])

    def close(self) -> None:
        self._db.close()

    def last_seq(self) -> int:
        """The highest job number ever given, deleted jobs' included."""
        row = self._db.execute(
            "SELECT MAX(COALESCE((SELECT MAX(seq) FROM jobs), 0),"
            " COALESCE((SELECT CAST(value AS INTEGER) FROM meta WHERE key = 'last_seq'), 0))"
        ).fetchone()
        return int(row[0] or 0)

    def add_job(self, job: JobRecord, tasks: list[Task]) -> None:
        with self._transaction():
            self._db.execute(
                f"INSERT INTO jobs ({', '.join(_JOB_COLUMNS)}) "
                f"VALUES ({', '.join('?' * len(_JOB_COLUMNS))})",
                [getattr(job, column) for column in _JOB_COLUMNS],
            )
            self._db.executemany(
                "INSERT INTO tasks VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                [
                    (
                        job.id,
                        t.index,
                        t.first_sample,
                        t.end_sample,
                        t.window.x0,
                        t.window.y0,
                        t.window.x1,
                        t.window.y1,
                        int(t.crop),
                    )
                    for t in tasks
                ],
            )

    def update_job(self, job: JobRecord) -> None:
        with self._transaction():
            self._update(job)

    def _update(self, job: JobRecord) -> None:
        self._db.execute(
            f"UPDATE jobs SET {', '.join(f'{c} = ?' for c in _MUTABLE_COLUMNS)} WHERE id = ?",
            [*(getattr(job, c) for c in _MUTABLE_COLUMNS), job.id],
        )

    def jobs(self) -> list[JobRecord]:
        rows = self._db.execute(f"SELECT {', '.join(_JOB_COLUMNS)} FROM jobs ORDER BY seq")
        return [JobRecord(*row) for row in rows]

    def tasks(self, job_id: str) -> list[Task]:
        rows = self._db.execute(
            "SELECT task, first_sample, end_sample, x0, y0, x1, y1, crop FROM tasks "
            "WHERE job = ? ORDER BY task",
            (job_id,),
        )
        return [Task(r[0], r[1], r[2], Window(r[3], r[4], r[5], r[6]), bool(r[7])) for r in rows]

    def done_tasks(self, job_id: str) -> set[int]:
        rows = self._db.execute("SELECT task FROM results WHERE job = ?", (job_id,))
        return {int(row[0]) for row in rows}

    def totals(self, job_id: str) -> ResultTotals:
        row = self._db.execute(
            "SELECT COUNT(*), SUM(work), SUM(closest_hit_rays), SUM(shadow_rays) "
            "FROM results WHERE job = ?",
            (job_id,),
        ).fetchone()
        return ResultTotals(*(int(value or 0) for value in row))

    def add_result(
        self,
        job: JobRecord,
        task: Task,
        *,
        node: str,
        image: bytes,
        closest_hit_rays: int,
        shadow_rays: int,
        finished_at: float,
    ) -> bool:
        """Stores a task's result and the job's new state together; False: a duplicate."""
        with self._transaction():
            cursor = self._db.execute(
                "INSERT OR IGNORE INTO results VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    job.id,
                    task.index,
                    node,
                    task.work,
                    closest_hit_rays,
                    shadow_rays,
                    finished_at,
                    image,
                ),
            )
            if cursor.rowcount == 0:
                return False
            self._update(job)
        return True

    def delete_ended(self, finished_before: float, keep: int) -> list[str]:
        """Deletes the ended jobs, with their tasks and task images, that finished
        before ``finished_before`` or are not among the ``keep`` that finished last.

        Returns their ids.
        """
        states = ", ".join(str(int(state)) for state in _ENDED)
        with self._transaction():
            rows = self._db.execute(
                f"SELECT id FROM jobs WHERE state IN ({states}) AND (finished_at < ? OR seq NOT IN"
                f" (SELECT seq FROM jobs WHERE state IN ({states})"
                "  ORDER BY finished_at DESC, seq DESC LIMIT ?))",
                (finished_before, max(0, keep)),
            ).fetchall()
            ids = [str(row[0]) for row in rows]
            if not ids:
                return []
            # Job ids are never given twice, even once the newest job is deleted:
            # a client or a node may still hold the old one.
            self._db.execute(
                "INSERT OR REPLACE INTO meta VALUES ('last_seq', ?)", (str(self.last_seq()),)
            )
            for table, column in (("results", "job"), ("tasks", "job"), ("jobs", "id")):
                self._db.executemany(
                    f"DELETE FROM {table} WHERE {column} = ?", [(job_id,) for job_id in ids]
                )
        return ids

    def results(self, job_id: str) -> list[TaskResult]:
        """The job's task results without their images, in task order."""
        rows = self._db.execute(
            "SELECT task, node, closest_hit_rays + shadow_rays, finished_at FROM results "
            "WHERE job = ? ORDER BY task",
            (job_id,),
        )
        return [TaskResult(int(r[0]), str(r[1]), int(r[2]), float(r[3])) for r in rows]

    def images(self, job_id: str) -> Iterator[TaskImage]:
        rows = self._db.execute("SELECT image FROM results WHERE job = ? ORDER BY task", (job_id,))
        for (image,) in rows:
            yield TaskImage.decode(image)

    @contextmanager
    def _transaction(self) -> Iterator[None]:
        self._db.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            self._db.execute("ROLLBACK")
            raise
        self._db.execute("COMMIT")
