"""The coordinator's jobs: stored in SQLite, split into tasks on JetStream, merged back.

Everything runs on one asyncio loop (the gRPC service too), so the job
table in memory needs no locks; every change is committed to SQLite
before anyone is told (a Submit reply, a result's ack).
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import json
import logging
import time
import uuid
from collections import OrderedDict, deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field

import numpy as np
from nats.aio.client import Client as Nats
from nats.aio.msg import Msg
from nats.js import JetStreamContext
from nats.js.errors import NotFoundError, ObjectNotFoundError
from nats.js.kv import KeyValue

from yarf.assets import scene_asset_hashes
from yarf.farm import job_log, streams
from yarf.farm.assets import FarmAssets
from yarf.farm.loops import Loops
from yarf.farm.merge import ImageMerge, TaskImage
from yarf.farm.messages import ResultMessage, TaskMessage
from yarf.farm.scene_summary import summarize_scene
from yarf.farm.store import JobRecord, JobStore
from yarf.farm.tasks import SplitPolicy, Task, split, task_options
from yarf.farm.validation import InvalidRequest, SubmitChecker
from yarf.v1 import render_pb2, scene_pb2

log = logging.getLogger("yarf.farm.coordinator")

FINAL_STATES = frozenset({render_pb2.SUCCEEDED, render_pb2.FAILED, render_pb2.CANCELLED})
# Merged images of finished jobs kept in memory (the others are rebuilt
# from the job table when asked for).
FINISHED_IMAGES_KEPT = 16
# Scene summaries kept in memory, by scene hash (the others are read back
# from the scene bucket when GetJob asks).
SCENE_SUMMARIES_KEPT = 256
# A task whose node reported within this many seconds is being rendered
# (nodes report every second; after the ack wait it goes to another node).
HEARTBEAT_FRESH_SECONDS = streams.TASK_ACK_WAIT


@dataclass(frozen=True)
class Retention:
    """How long ended jobs stay, as yarfd's --keep-finished-hours and --max-finished-jobs."""

    keep_finished_hours: float = 168.0
    max_finished_jobs: int = 1000


class UnknownJob(KeyError):
    """A job id the coordinator never gave (NOT_FOUND)."""


@dataclass
class Job:
    """A job in memory: its row, its tasks and what is known of their progress."""

    record: JobRecord
    tasks: list[Task]
    done: set[int]
    work_done: int = 0
    closest_hit_rays: int = 0
    shadow_rays: int = 0
    # Samples rendered so far of running tasks, from the nodes' heartbeats.
    progress: dict[int, int] = field(default_factory=dict)
    # When each running task's last heartbeat came (time.monotonic()).
    heartbeats: dict[int, float] = field(default_factory=dict)
    merge: ImageMerge | None = None
    # What this coordinator saw of the job and does not store, for its log.
    seen: deque[job_log.Event] = field(default_factory=lambda: deque(maxlen=job_log.MAX_LINES))
    # (task, node) pairs whose heartbeats were heard: each starts one log line.
    heard: set[tuple[int, str]] = field(default_factory=set)
    # Set (and replaced) at every change, waking the Watch streams.
    changed: asyncio.Event = field(default_factory=asyncio.Event)

    @property
    def final(self) -> bool:
        return self.record.state in FINAL_STATES

    @property
    def total_work(self) -> int:
        return sum(task.work for task in self.tasks)

    def pending_tasks(self) -> list[Task]:
        return [task for task in self.tasks if task.index not in self.done]

    def rendering(self) -> set[int]:
        """The tasks not done that a node reported on lately."""
        since = time.monotonic() - HEARTBEAT_FRESH_SECONDS
        return {
            index for index, at in self.heartbeats.items() if at >= since and index not in self.done
        }


class Coordinator:
    """Jobs in, tasks out, results merged: the farm's side of RenderService."""

    def __init__(
        self,
        nc: Nats,
        store: JobStore,
        buckets: streams.Buckets,
        policy: SplitPolicy,
        retention: Retention | None = None,
        checker: SubmitChecker | None = None,
    ) -> None:
        self._nc = nc
        self._checker = checker or SubmitChecker()
        self._js: JetStreamContext = nc.jetstream()
        self._store = store
        self._buckets = buckets
        # Served by the coordinator's AssetService; jobs may name only what it holds.
        self.assets = FarmAssets(buckets.assets)
        self._kv: KeyValue = buckets.jobs
        self._policy = policy
        self._retention = retention or Retention()
        self._jobs: dict[str, Job] = {}
        self._next_seq = store.last_seq() + 1
        self._scenes_stored: set[str] = set()
        self._scene_uploads: dict[str, asyncio.Task[None]] = {}
        self._finished_merges: OrderedDict[str, None] = OrderedDict()
        self._scene_summaries: OrderedDict[str, render_pb2.SceneSummary] = OrderedDict()
        self._loops = Loops()

    # Start and stop.

    async def start(self) -> None:
        """Loads the job table, queues again what is not done, starts consuming results."""
        for record in self._store.jobs():
            job = Job(record, self._store.tasks(record.id), self._store.done_tasks(record.id))
            totals = self._store.totals(record.id)
            job.work_done, job.closest_hit_rays, job.shadow_rays = (
                totals.work,
                totals.closest_hit_rays,
                totals.shadow_rays,
            )
            self._jobs[record.id] = job
        self._apply_retention()
        await self._resume()
        self._loops.start(
            self._consume(streams.RESULTS_STREAM, streams.RESULTS_DURABLE, self._handle_result),
            name="results",
        )
        # A durable consumer, not a subscription: advisories sent while
        # no coordinator ran are handled now (see streams.ADVISORIES_STREAM).
        self._loops.start(
            self._consume(
                streams.ADVISORIES_STREAM, streams.ADVISORIES_DURABLE, self._on_max_deliveries
            ),
            name="advisories",
        )
        self._loops.start(self._watch_progress(), name="progress")

    async def _resume(self) -> None:
        """Brings the streams in line with the job table after a restart.

        Tasks not done are published again: those still in the stream are
        dropped as duplicates, those lost with a node or never published are
        queued. Results delivered but not acked are redelivered by JetStream.
        """
        # A copy: a job that ends here may take older ones with it (retention).
        for job in list(self._jobs.values()):
            record = job.record
            if job.final:
                continue
            if not job.pending_tasks():
                await self._finish(job, render_pb2.SUCCEEDED)
                continue
            if await self._flagged(record.id):
                # Cancelled (or failed) just before the coordinator died.
                await self._finish(job, render_pb2.CANCELLED)
                continue
            if record.state == render_pb2.RUNNING:
                record.attempts += 1
                self._store.update_job(record)
            await self._publish_tasks(job, job.pending_tasks())
            tasks_left = len(job.pending_tasks())
            self._observe(
                job, job_log.status_fields("resumed", self.status(job), tasks_left=tasks_left)
            )
        log.info("resumed %d jobs", sum(not job.final for job in self._jobs.values()))

    async def _flagged(self, job_id: str) -> bool:
        try:
            await self._kv.get(streams.cancel_key(job_id))
        except NotFoundError:
            return False
        return True

    async def stop(self) -> None:
        await self._loops.stop()
        self._checker.close()

    # RenderService.

    async def submit(
        self, request: render_pb2.SubmitRequest, owner: str, *, admin: bool
    ) -> render_pb2.SubmitReply:
        """Stores and queues a job of ``owner``, and says what yarfd's checks
        warn of; raises InvalidRequest or AddressNotAllowed."""
        # yarfd's checks, which also fill in its defaults (spp, priority).
        checked = await asyncio.to_thread(self._checker.check, request, admin=admin)
        accepted = checked.accepted
        # As yarfd's Submit: every asset named is here already (nodes copy it from here).
        for digest in await self.assets.missing(scene_asset_hashes(request.scene)):
            raise InvalidRequest(
                f"asset {digest} is not on this farm; upload it with AssetService.Upload "
                "before submitting"
            )
        options = accepted.options
        tasks = split(accepted, checked.splits, self._policy)
        scene_bytes = request.scene.SerializeToString(deterministic=True)
        scene_hash = hashlib.sha256(scene_bytes).hexdigest()
        await self._store_scene(scene_hash, scene_bytes)
        self._keep_scene_summary(scene_hash, summarize_scene(request.scene))
        seq = self._next_seq
        self._next_seq += 1
        record = JobRecord(
            seq=seq,
            id=f"job-{seq:06d}",
            name=accepted.name,
            owner=owner,
            priority=accepted.priority,
            generation=0,
            state=render_pb2.QUEUED,
            error="",
            submitted_at=time.time(),
            started_at=None,
            finished_at=None,
            attempts=0,
            failures=0,
            max_retries=accepted.max_retries,
            scene_hash=scene_hash,
            options=options.SerializeToString(),
            width=request.scene.film.width,
            height=request.scene.film.height,
            spp=options.spp,
        )
        self._store.add_job(record, tasks)
        job = Job(record, tasks, set())
        self._jobs[record.id] = job
        log.info("job %s: %d tasks, priority %d", record.id, len(tasks), record.priority)
        try:
            await self._publish_tasks(job, tasks)
        except Exception as error:
            # The job is stored: it is queued once NATS answers again.
            log.warning("job %s: tasks not published yet: %s", record.id, error)
            self._loops.start(self._publish_until_done(job), name=f"publish {record.id}")
        return render_pb2.SubmitReply(job_id=record.id, warnings=checked.warnings)

    def job(self, job_id: str) -> Job:
        job = self._jobs.get(job_id)
        if job is None:
            raise UnknownJob(job_id)
        return job

    def status(self, job: Job) -> render_pb2.JobStatus:
        record = job.record
        first_sample = render_pb2.RenderOptions.FromString(record.options).first_sample
        total = max(job.total_work, 1)
        running = sum(
            job.tasks[index].window.pixels * min(samples, job.tasks[index].samples)
            for index, samples in job.progress.items()
            if index not in job.done
        )
        fraction = min(1.0, (job.work_done + running) / total)
        samples_done = first_sample + (record.spp - first_sample) * job.work_done // total
        now = time.time()
        elapsed = 0.0
        if record.started_at is not None:
            elapsed = max(0.0, (record.finished_at or now) - record.started_at)
        eta = 0.0
        if not job.final and fraction > 0:
            eta = elapsed * (1 - fraction) / fraction
        if record.state == render_pb2.SUCCEEDED:
            samples_done, fraction = record.spp, 1.0
        return render_pb2.JobStatus(
            job_id=record.id,
            name=record.name,
            state=record.state,  # type: ignore[arg-type]
            samples_done=samples_done,
            samples_total=record.spp,
            percent=100.0 * fraction,
            elapsed_seconds=elapsed,
            eta_seconds=eta,
            error=record.error,
            closest_hit_rays=job.closest_hit_rays,
            shadow_rays=job.shadow_rays,
            priority=record.priority,
            owner=record.owner,
            attempts=record.attempts,
            submitted_at=record.submitted_at,
        )

    def list(self) -> list[render_pb2.JobStatus]:
        jobs = sorted(self._jobs.values(), key=lambda job: -job.record.seq)
        return [self.status(job) for job in jobs]

    def log(self, job: Job) -> list[str]:
        """The job's event lines, oldest first (see yarf.farm.job_log)."""
        record = job.record
        return job_log.job_log(
            self.status(job),
            first_sample=render_pb2.RenderOptions.FromString(record.options).first_sample,
            submitted_at=record.submitted_at,
            started_at=record.started_at,
            tasks=job.tasks,
            results=self._store.results(record.id),
            seen=job.seen,
        )

    async def scene_summary(self, job: Job) -> render_pb2.SceneSummary | None:
        """A summary of the job's scene; None if the scene bucket lost it."""
        scene_hash = job.record.scene_hash
        summary = self._scene_summaries.get(scene_hash)
        if summary is None:
            try:
                data = (await self._buckets.scenes.get(scene_hash)).data or b""
            except ObjectNotFoundError:
                return None
            scene = await asyncio.to_thread(scene_pb2.Scene.FromString, bytes(data))
            summary = summarize_scene(scene)
        self._keep_scene_summary(scene_hash, summary)
        return summary

    def _keep_scene_summary(self, scene_hash: str, summary: render_pb2.SceneSummary) -> None:
        self._scene_summaries[scene_hash] = summary
        self._scene_summaries.move_to_end(scene_hash)
        while len(self._scene_summaries) > SCENE_SUMMARIES_KEPT:
            self._scene_summaries.popitem(last=False)

    def image(self, job: Job) -> tuple[np.ndarray, np.ndarray] | None:
        """The merged pixels and variances, or None before any task has finished."""
        if not job.done:
            return None
        if job.merge is None:
            merge = ImageMerge(job.record.width, job.record.height)
            for image in self._store.images(job.record.id):
                merge.add(image)
            job.merge = merge
        if job.final:
            self._keep_finished_merge(job)
        return job.merge.result()

    def _keep_finished_merge(self, job: Job) -> None:
        self._finished_merges[job.record.id] = None
        self._finished_merges.move_to_end(job.record.id)
        while len(self._finished_merges) > FINISHED_IMAGES_KEPT:
            evicted, _ = self._finished_merges.popitem(last=False)
            if evicted in self._jobs:
                self._jobs[evicted].merge = None

    async def cancel(self, job: Job) -> None:
        if not job.final:
            log.info("job %s: cancelled", job.record.id)
            await self._finish(job, render_pb2.CANCELLED)

    async def set_priority(self, job: Job, priority: int) -> None:
        """Moves the job's queued tasks to the tier of ``priority``."""
        record = job.record
        moves = not job.final and streams.tier_of(priority) != streams.tier_of(record.priority)
        record.priority = priority
        if moves:
            # New message ids: the old ones are still in the duplicate window.
            record.generation += 1
        self._store.update_job(record)
        if moves:
            # Tasks a node is rendering keep their message (its lease) and tier:
            # queued again they would be rendered twice. The rest move; one a
            # node takes meanwhile may still render twice (the second result
            # is discarded).
            rendering = job.rendering()
            await self._delete_queued(record.id, keep=rendering)
            moved = [task for task in job.pending_tasks() if task.index not in rendering]
            await self._publish_tasks(job, moved)
        self._notify(job)

    async def _delete_queued(self, job_id: str, keep: set[int]) -> None:
        """Deletes the job's task messages from the stream but those of tasks in ``keep``."""
        sequence = 1
        while True:
            try:
                stored = await self._js.get_msg(
                    streams.TASKS_STREAM, sequence, streams.job_tasks_filter(job_id), next=True
                )
            except NotFoundError:
                return
            assert stored.seq is not None
            sequence = stored.seq + 1
            try:
                index = TaskMessage.decode(stored.data or b"").task
            except (ValueError, KeyError, TypeError):
                index = -1
            if index not in keep:
                with contextlib.suppress(NotFoundError):
                    await self._js.delete_msg(streams.TASKS_STREAM, stored.seq)

    # Tasks out.

    async def _store_scene(self, scene_hash: str, scene_bytes: bytes) -> None:
        """Puts the scene into the object store once, however many jobs submit it at once."""
        if scene_hash in self._scenes_stored:
            return
        upload = self._scene_uploads.get(scene_hash)
        if upload is None:
            upload = asyncio.create_task(self._upload_scene(scene_hash, scene_bytes))
            self._scene_uploads[scene_hash] = upload
            upload.add_done_callback(lambda _: self._scene_uploads.pop(scene_hash, None))
        await asyncio.shield(upload)
        self._scenes_stored.add(scene_hash)

    async def _upload_scene(self, scene_hash: str, scene_bytes: bytes) -> None:
        try:
            await self._buckets.scenes.get_info(scene_hash)
            return
        except ObjectNotFoundError:
            pass
        await self._buckets.scenes.put(scene_hash, scene_bytes)

    def _task_message(self, job: Job, task: Task) -> TaskMessage:
        options = render_pb2.RenderOptions.FromString(job.record.options)
        return TaskMessage(
            farm=self._store.farm_id,
            job_id=job.record.id,
            task=task.index,
            scene_hash=job.record.scene_hash,
            options=task_options(options, task),
            window=task.window,
            name=job.record.name,
        )

    async def _publish_tasks(self, job: Job, tasks: list[Task], *, again: str = "") -> None:
        record = job.record
        subject = streams.task_subject(streams.tier_of(record.priority), record.id)
        for task in tasks:
            message = self._task_message(job, task)
            await self._js.publish(
                subject,
                message.encode(),
                headers={"Nats-Msg-Id": message.msg_id(record.generation, again)},
            )

    async def _publish_until_done(self, job: Job) -> None:
        while not job.final and self._loops.running:
            await asyncio.sleep(1.0)
            try:
                # Tasks published before the failure are dropped as duplicates.
                await self._publish_tasks(job, job.pending_tasks())
                return
            except Exception as error:
                log.warning("job %s: tasks not published yet: %s", job.record.id, error)

    # State changes.

    def _observe(self, job: Job, fields: job_log.Fields) -> None:
        """Adds a line the job table cannot rebuild to the job's log."""
        job.seen.append(job_log.Event(time.time(), fields))

    def _notify(self, job: Job) -> None:
        job.changed.set()
        job.changed = asyncio.Event()

    def _mark_running(self, job: Job) -> None:
        record = job.record
        if record.state == render_pb2.QUEUED:
            record.state = render_pb2.RUNNING
            record.started_at = time.time()
            record.attempts += 1

    async def _finish(self, job: Job, state: int, error: str = "") -> None:
        record = job.record
        # Ended in memory before the first await: a heartbeat or result handled
        # meanwhile sees a final job and adds nothing to it.
        record.state = state
        record.error = error
        record.finished_at = time.time()
        if state != render_pb2.SUCCEEDED:
            # Nodes watch the flag and stop the job's running tasks: first,
            # before the disk. A restart reads the flag back (see _resume).
            await self._kv.put(streams.cancel_key(record.id), b"1")
        if record.started_at is None:
            record.started_at = record.finished_at
        self._store.update_job(record)
        # Before anyone hears the job ended: they then see the job table as it stays.
        self._apply_retention()
        self._notify(job)
        if state != render_pb2.SUCCEEDED:
            # The job's queued tasks go at once.
            await self._js.purge_stream(
                streams.TASKS_STREAM, subject=streams.job_tasks_filter(record.id)
            )

    def _apply_retention(self) -> None:
        """Deletes the ended jobs beyond the retention limits, with their task images.

        Runs at start and whenever a job ends, as yarfd does. A Watch still
        holding a deleted job sees its last state; new calls get NOT_FOUND.
        """
        cutoff = time.time() - self._retention.keep_finished_hours * 3600
        deleted = self._store.delete_ended(cutoff, self._retention.max_finished_jobs)
        for job_id in deleted:
            self._jobs.pop(job_id, None)
            self._finished_merges.pop(job_id, None)
        if deleted:
            log.info("deleted %d ended jobs: %s", len(deleted), " ".join(deleted))

    async def _task_failed(self, job: Job, task: int, error: str, node: str = "") -> None:
        if job.final or task in job.done:
            return
        record = job.record
        record.failures += 1
        failed = job_log.task_fields(
            "task_failed",
            record.id,
            job.tasks[task],
            node,
            failures=record.failures,
            max_retries=record.max_retries,
            error=error,
        )
        self._observe(job, failed)
        # Its next try starts a line of its own, on whichever node.
        job.heard = {heard for heard in job.heard if heard[0] != task}
        if record.failures <= record.max_retries:
            log.warning("job %s task %d failed, queued again: %s", record.id, task, error)
            self._store.update_job(record)
            await self._publish_tasks(job, [job.tasks[task]], again=f"retry{record.failures}")
            return
        log.warning("job %s failed: task %d: %s", record.id, task, error)
        await self._finish(job, render_pb2.FAILED, f"task {task}: {error}")

    # Results in.

    async def _consume(
        self, stream: str, durable: str, handle: Callable[[Msg], Awaitable[None]]
    ) -> None:
        subscription = await self._js.pull_subscribe_bind(durable, stream=stream)
        while self._loops.running:
            try:
                messages = await subscription.fetch(32, timeout=1.0)
            except TimeoutError:
                continue
            except Exception:
                log.exception("fetching results")
                await asyncio.sleep(1.0)
                continue
            for message in messages:
                try:
                    await handle(message)
                except Exception:
                    # Not acked: redelivered after the ack wait.
                    log.exception("handling a message of %s", stream)

    async def _handle_result(self, message: Msg) -> None:
        try:
            result = ResultMessage.decode(message.data)
        except (ValueError, TypeError):
            log.warning("a malformed result message: %r", message.data[:200])
            await message.term()
            return
        job = self._jobs.get(result.job_id)
        if result.farm != self._store.farm_id or job is None or result.task >= len(job.tasks):
            # Another job table's (a state folder started afresh).
            await message.ack()
            return
        if not result.ok:
            await self._task_failed(job, result.task, result.error, result.node)
            await message.ack()
            return
        if result.task in job.done:
            await message.ack()
            await self._delete_image(result.image_object)
            return
        await message.in_progress()
        try:
            data = (await self._buckets.results.get(result.image_object)).data
        except ObjectNotFoundError:
            # Expired from the bucket while the coordinator was away.
            log.warning("job %s task %d: image missing, queued again", job.record.id, result.task)
            again = f"lost{uuid.uuid4().hex[:8]}"
            await self._publish_tasks(job, [job.tasks[result.task]], again=again)
            await message.ack()
            return
        task = job.tasks[result.task]
        try:
            image = TaskImage.decode(bytes(data or b""))
            if image.window != task.window or image.samples != task.samples:
                raise ValueError(f"an image of {image.window}, {image.samples} samples")
        except ValueError as error:
            await self._task_failed(
                job, task.index, f"node {result.node} sent a bad image: {error}", result.node
            )
            await message.ack()
            return
        self._mark_running(job)
        job.done.add(task.index)
        job.work_done += task.work
        job.closest_hit_rays += result.closest_hit_rays
        job.shadow_rays += result.shadow_rays
        job.progress.pop(task.index, None)
        job.heartbeats.pop(task.index, None)
        record = job.record
        finished = not job.final and len(job.done) == len(job.tasks)
        if finished:
            record.state = render_pb2.SUCCEEDED
            record.finished_at = time.time()
        self._store.add_result(
            record,
            task,
            node=result.node,
            image=data,
            closest_hit_rays=result.closest_hit_rays,
            shadow_rays=result.shadow_rays,
            finished_at=time.time(),
        )
        if job.merge is not None:
            job.merge.add(image)
        if finished:
            log.info("job %s: succeeded", record.id)
            self._apply_retention()
        self._notify(job)
        await message.ack()
        await self._delete_image(result.image_object)

    async def _delete_image(self, name: str) -> None:
        with contextlib.suppress(NotFoundError):
            await self._buckets.results.delete(name)

    async def _watch_progress(self) -> None:
        """Follows the nodes' heartbeats: a job runs once a node reports a task of it."""
        while self._loops.running:
            try:
                watcher = await self._kv.watch("progress.>")
                async for entry in watcher:
                    if entry is not None:
                        self._on_progress(entry.key, entry.value, entry.operation)
            except asyncio.CancelledError:
                raise
            except Exception:
                log.exception("watching progress")
                await asyncio.sleep(1.0)

    def _on_progress(self, key: str, value: bytes | None, operation: str | None) -> None:
        parts = key.split(".")
        job = self._jobs.get(parts[1]) if len(parts) == 3 else None
        if job is None or not parts[2].isdigit():
            return
        job_id, task = parts[1], int(parts[2])
        if operation in ("DEL", "PURGE") or not value:
            job.progress.pop(task, None)
            job.heartbeats.pop(task, None)
            return
        if job.final or task in job.done or task >= len(job.tasks):
            return
        try:
            progress = json.loads(value)
            job.progress[task] = int(progress.get("samples", 0))
            node = str(progress.get("node", ""))
        except (ValueError, AttributeError):
            return
        job.heartbeats[task] = time.monotonic()
        if job.record.state == render_pb2.QUEUED:
            self._mark_running(job)
            self._store.update_job(job.record)
            log.info("job %s: running", job_id)
        if (task, node) not in job.heard:
            # After the job's start (same heartbeat): its line comes first.
            job.heard.add((task, node))
            started = job_log.task_fields("task_started", job_id, job.tasks[task], node)
            self._observe(job, started)
        self._notify(job)

    async def _on_max_deliveries(self, advisory: Msg) -> None:
        """A task JetStream gave up on (its nodes kept dying or stalling): retry or fail.

        The retry is published before the spent message is deleted and the
        advisory acked: a coordinator dying in between is redelivered the
        advisory and at worst counts the failure twice, never loses the task.
        """
        try:
            event = json.loads(advisory.data)
            sequence = int(event["stream_seq"])
        except (ValueError, KeyError, TypeError):
            log.warning("a malformed advisory: %r", advisory.data[:200])
            await advisory.term()
            return
        try:
            stored = await self._js.get_msg(streams.TASKS_STREAM, sequence)
            assert stored.data is not None
            task = TaskMessage.decode(stored.data)
        except NotFoundError:
            # Handled before (deleted), or purged with its job.
            await advisory.ack()
            return
        job = self._jobs.get(task.job_id)
        if job is not None and task.farm == self._store.farm_id:
            await self._task_failed(
                job,
                task.task,
                f"delivered {event.get('deliveries')} times without finishing "
                "(its nodes died or stalled)",
            )
        with contextlib.suppress(NotFoundError):
            await self._js.delete_msg(streams.TASKS_STREAM, sequence)
        await advisory.ack()
