"""A render node: pulls tasks, renders them on its yarfd, sends the images back.

One task at a time (yarfd uses every thread it has on it). While a task
renders the node sends an in-progress ack every second, so JetStream
redelivers the task elsewhere only if this node dies or stalls; it stops
the render within a second of the job's cancel flag.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import json
import logging
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import grpc
from nats.aio.client import Client as Nats
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription
from nats.js.errors import NotFoundError

from yarf.assets import scene_asset_hashes
from yarf.client import FINAL_STATES, MAX_MESSAGE_BYTES, array_to_numpy
from yarf.credentials import open_aio_channel
from yarf.farm import streams
from yarf.farm.assets import FarmAssets
from yarf.farm.cache import DEFAULT_CACHE_BYTES, SceneCache
from yarf.farm.loops import Loops
from yarf.farm.merge import TaskImage
from yarf.farm.messages import ResultMessage, TaskMessage
from yarf.v1 import asset_pb2_grpc, render_pb2, render_pb2_grpc, scene_pb2

log = logging.getLogger("yarf.farm.node")

HEARTBEAT_SECONDS = 1.0
# With nothing queued, the node looks again this often even without news
# (a task redelivered after a node died publishes nothing).
IDLE_POLL_SECONDS = 0.5
# Deadline of unary calls to yarfd.
CALL_TIMEOUT = 60.0
# How long a timed-out task's Cancel may take: its yarfd may be the one hanging.
TIMEOUT_CANCEL_SECONDS = 10.0
DEFAULT_TASK_TIMEOUT = 3600.0
# Deadline of the start-up call that proves yarfd accepts the node's credentials.
CHECK_TIMEOUT = 10.0
# A pull request is answered within milliseconds, with a task or "none".
PULL_TIMEOUT = 0.5
_NO_WAIT_PULL = json.dumps({"batch": 1, "no_wait": True}).encode()
# Waits 20 ms on the server for a task of its tier.
_SHORT_PULL = json.dumps({"batch": 1, "expires": 20_000_000}).encode()


def _event(kind: str, **fields: object) -> None:
    """A log line a test or an operator can parse: ``<kind> {json}``."""
    log.info("%s %s", kind, json.dumps(fields, sort_keys=True))


class TaskPuller:
    """Takes the next task from the highest tier that has one.

    First a no-wait pull request per tier, in priority order, answered at
    once with a task or "no messages"; nats-server 2.9 answers "no
    messages" for tasks published a moment before, so when every tier says
    so, each is asked again with a request that waits a little on the
    server. (A long-waiting request on a low tier would hold a low task
    while a high one arrives.)
    """

    def __init__(self, nc: Nats) -> None:
        self._nc = nc
        self._inbox = nc.new_inbox()
        self._subscription: Subscription | None = None

    async def start(self) -> None:
        self._subscription = await self._nc.subscribe(self._inbox)

    async def next(self) -> Msg | None:
        for request in (_NO_WAIT_PULL, _SHORT_PULL):
            for tier in streams.TIERS:
                message = await self._pull(tier, request)
                if message is not None:
                    return message
        return None

    async def _pull(self, tier: str, request: bytes) -> Msg | None:
        assert self._subscription is not None
        subject = f"$JS.API.CONSUMER.MSG.NEXT.{streams.TASKS_STREAM}.{streams.tier_durable(tier)}"
        await self._nc.publish(subject, request, reply=self._inbox)
        try:
            message = await self._subscription.next_msg(timeout=PULL_TIMEOUT)
        except TimeoutError:
            # An answer that comes late is taken by the next request.
            log.info("pull request to the %s tier unanswered", tier)
            return None
        # A status (404 no messages, 408 expired) is no task; a late answer
        # to an earlier request is still a task to render.
        if message.headers and "Status" in message.headers:
            return None
        return message


@dataclass
class RunningTask:
    task: TaskMessage
    message: Msg
    cancel: asyncio.Event
    samples: int = 0
    cancel_seen_at: float | None = None
    cancel_sent_at: float | None = None


class Node:
    """Renders the farm's tasks on the yarfd at ``yarfd_address``.

    ``task_timeout`` (seconds, 0: none) bounds a task's render: a yarfd that
    hangs while the node keeps its lease would hold the task forever.
    A yarfd that requires TLS and tokens takes ``token`` (the jobs the node
    submits are that token's user's) and ``tls_ca`` (its certificate or CA);
    "" means none.
    """

    def __init__(
        self,
        nc: Nats,
        buckets: streams.Buckets,
        yarfd_address: str,
        *,
        name: str,
        cache_dir: Path,
        cache_bytes: int = DEFAULT_CACHE_BYTES,
        task_timeout: float = DEFAULT_TASK_TIMEOUT,
        token: str = "",
        tls_ca: str = "",
    ) -> None:
        self.name = name
        self._nc = nc
        self._js = nc.jetstream()
        self._buckets = buckets
        self._cache = SceneCache(cache_dir, cache_bytes)
        self._task_timeout = task_timeout
        self._channel = open_aio_channel(
            yarfd_address,
            [
                ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
                ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
            ],
            token=token,
            tls_ca=tls_ca,
        )
        self._yarfd = render_pb2_grpc.RenderServiceStub(self._channel)
        self._yarfd_assets = asset_pb2_grpc.AssetServiceStub(self._channel)
        self._assets = FarmAssets(buckets.assets)
        self._puller = TaskPuller(nc)
        self._wake = asyncio.Event()
        self._cancelled: set[str] = set()
        self._running: RunningTask | None = None
        self._stopping = False
        self._scene: tuple[str, scene_pb2.Scene] | None = None
        self._loops = Loops()

    async def check_yarfd(self) -> None:
        """Fails at start, not task by task, when yarfd refuses the node's token or TLS.

        Raises ``PermissionError``; a yarfd that does not answer yet is only logged.
        """
        try:
            await self._yarfd.List(render_pb2.ListJobsRequest(), timeout=CHECK_TIMEOUT)
        except grpc.aio.AioRpcError as error:
            code = error.code()
            if code in (grpc.StatusCode.UNAUTHENTICATED, grpc.StatusCode.PERMISSION_DENIED):
                why = f"yarfd refuses the node: {code.name} {error.details()}"
                raise PermissionError(why) from None
            log.warning("yarfd does not answer yet: %s %s", code.name, error.details())

    async def run(self, stop: asyncio.Event) -> None:
        """Renders tasks until ``stop`` is set; a task in hand then goes back to the queue."""
        await self._puller.start()
        # Any task published wakes an idle node at once.
        await self._nc.subscribe("yarf.tasks.>", cb=self._on_task_published)
        self._loops.start(self._watch_cancels(), name="cancel flags")
        self._loops.start(self._stop_when(stop), name="stop")
        _event("node ready", node=self.name)
        try:
            while not stop.is_set():
                self._wake.clear()
                message = await self._puller.next()
                if message is None:
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(self._wake.wait(), IDLE_POLL_SECONDS)
                    continue
                try:
                    await self._run_task(message)
                except Exception:
                    # Not acked: redelivered after the ack wait.
                    log.exception("a task")
        finally:
            await self._loops.stop()
            await self._channel.close()

    async def _stop_when(self, stop: asyncio.Event) -> None:
        await stop.wait()
        self._stopping = True
        self._wake.set()
        if self._running is not None:
            self._running.cancel.set()

    async def _on_task_published(self, message: Msg) -> None:
        self._wake.set()

    # Cancel flags.

    async def _watch_cancels(self) -> None:
        """Follows the jobs bucket's cancel flags (a push stream, not polling)."""
        while self._loops.running:
            try:
                watcher = await self._buckets.jobs.watch("cancel.*")
                async for entry in watcher:
                    if entry is None or entry.operation is not None:
                        continue  # the end of the initial values, or a deletion
                    job_id = entry.key.split(".", 1)[1]
                    self._cancelled.add(job_id)
                    running = self._running
                    if running is not None and running.task.job_id == job_id:
                        running.cancel_seen_at = time.time()
                        running.cancel.set()
            except asyncio.CancelledError:
                raise
            except Exception:
                log.exception("watching cancel flags")
                await asyncio.sleep(1.0)

    async def _flagged(self, job_id: str) -> bool:
        """Whether the job is cancelled: the watch's view, checked against the bucket."""
        if job_id in self._cancelled:
            return True
        try:
            await self._buckets.jobs.get(streams.cancel_key(job_id))
        except NotFoundError:
            return False
        self._cancelled.add(job_id)
        return True

    # Tasks.

    async def _run_task(self, message: Msg) -> None:
        try:
            task = TaskMessage.decode(message.data)
        except (ValueError, KeyError, TypeError):
            log.warning("a malformed task message: %r", message.data[:200])
            await message.term()
            return
        delivered = message.metadata.num_delivered
        if await self._flagged(task.job_id):
            _event("task dropped", job=task.job_id, task=task.task, node=self.name)
            await message.ack()
            return
        _event(
            "task started",
            job=task.job_id,
            task=task.task,
            node=self.name,
            delivered=delivered,
            at=time.time(),
        )
        running = RunningTask(task, message, asyncio.Event())
        self._running = running
        heartbeat = asyncio.create_task(self._heartbeat(running))
        try:
            await self._render(running)
        except grpc.aio.AioRpcError as error:
            if error.code() == grpc.StatusCode.INVALID_ARGUMENT:
                # The renderer refuses the job itself: no other node would differ.
                await self._report_failure(running, error.details() or str(error))
            else:
                await self._give_back(running, f"yarfd: {error.code().name} {error.details()}")
        except Exception as error:
            # This node's trouble (NATS, the object store, the disk): another
            # node may do better; after max_deliver the coordinator fails the job.
            log.exception("task %s/%d", task.job_id, task.task)
            await self._give_back(running, str(error))
        finally:
            self._running = None
            heartbeat.cancel()
            with contextlib.suppress(Exception):
                await self._buckets.jobs.delete(streams.progress_key(task.job_id, task.task))

    async def _give_back(self, running: RunningTask, why: str) -> None:
        """Returns the task to the queue (redelivered at once, to any node)."""
        task = running.task
        log.warning("task %s/%d back to the queue: %s", task.job_id, task.task, why)
        with contextlib.suppress(Exception):
            await running.message.nak(delay=1.0)
        if not self._stopping:
            # Whatever went wrong here may take a moment to mend.
            await asyncio.sleep(1.0)

    async def _heartbeat(self, running: RunningTask) -> None:
        """In-progress acks (the lease) and the progress the coordinator shows."""
        key = streams.progress_key(running.task.job_id, running.task.task)
        # Ends with its task even if nats-py turns the cancel into an error.
        while self._running is running:
            try:
                await running.message.in_progress()
                progress = {"node": self.name, "samples": running.samples}
                await self._buckets.jobs.put(key, json.dumps(progress).encode())
            except Exception as error:
                log.warning("heartbeat: %s", error)
            await asyncio.sleep(HEARTBEAT_SECONDS)

    async def _render(self, running: RunningTask) -> None:
        task = running.task
        scene = await self._load_scene(task.scene_hash)
        # The mesh and texture files the scene names by hash, from the farm's bucket.
        await self._assets.copy_to(self._yarfd_assets, scene_asset_hashes(scene), CALL_TIMEOUT)
        request = render_pb2.SubmitRequest(
            scene=scene, options=task.options, name=f"{task.job_id}/{task.task} {task.name}"
        )
        reply = await self._yarfd.Submit(request, timeout=CALL_TIMEOUT)
        if task.job_id in self._cancelled or self._stopping:
            running.cancel.set()
        canceller = asyncio.create_task(self._cancel_when_flagged(running, reply.job_id))
        try:
            final = await asyncio.wait_for(
                self._watch_final(running, reply.job_id), self._task_timeout or None
            )
        except TimeoutError:
            await self._time_out(running, reply.job_id)
            return
        finally:
            canceller.cancel()
        if final is None:
            raise RuntimeError(f"yarfd's Watch of {reply.job_id} ended without a final state")
        if final.state == render_pb2.SUCCEEDED:
            await self._send_result(running, reply.job_id, final)
        elif final.state == render_pb2.CANCELLED:
            if task.job_id not in self._cancelled:
                # Not the job's cancel: this node stops, or its yarfd was told to stop.
                await self._give_back(running, "yarfd cancelled the task")
                return
            _event(
                "task cancelled",
                job=task.job_id,
                task=task.task,
                node=self.name,
                cancel_seen_at=running.cancel_seen_at,
                cancel_sent_at=running.cancel_sent_at,
                stopped_at=time.time(),
            )
            await running.message.ack()
        else:
            error = final.error or f"yarfd ended the task {render_pb2.JobState.Name(final.state)}"
            await self._report_failure(running, error)

    async def _watch_final(
        self, running: RunningTask, yarfd_job: str
    ) -> render_pb2.JobStatus | None:
        """Follows the render to its final status (None: the Watch ended before it)."""
        first_sample = running.task.options.first_sample
        async for status in self._yarfd.Watch(render_pb2.WatchRequest(job_id=yarfd_job)):
            running.samples = max(0, status.samples_done - first_sample)
            if status.state in FINAL_STATES:
                return status
        return None

    async def _time_out(self, running: RunningTask, yarfd_job: str) -> None:
        """Stops a render that ran past --task-timeout and reports the task failed.

        A failure, as for a render yarfd fails: the coordinator's retry rule
        (the job's max_retries) decides, and the job's error names the
        timeout. A nak would instead pass a task too slow for the limit from
        node to node, each holding it the whole timeout.
        """
        task = running.task
        with contextlib.suppress(Exception):
            await self._yarfd.Cancel(
                render_pb2.CancelRequest(job_id=yarfd_job), timeout=TIMEOUT_CANCEL_SECONDS
            )
        _event("task timed out", job=task.job_id, task=task.task, node=self.name)
        error = f"timed out after {self._task_timeout:g} s on node {self.name} (--task-timeout)"
        await self._report_failure(running, error)

    async def _cancel_when_flagged(self, running: RunningTask, yarfd_job: str) -> None:
        await running.cancel.wait()
        running.cancel_sent_at = time.time()
        await self._yarfd.Cancel(render_pb2.CancelRequest(job_id=yarfd_job), timeout=CALL_TIMEOUT)

    async def _load_scene(self, scene_hash: str) -> scene_pb2.Scene:
        """The scene from the disk cache, else from the object store (then cached)."""
        if self._scene is not None and self._scene[0] == scene_hash:
            return self._scene[1]
        data = self._cache.get(scene_hash)
        if data is None:
            fetched = (await self._buckets.scenes.get(scene_hash)).data
            assert fetched is not None
            data = bytes(fetched)
            if hashlib.sha256(data).hexdigest() != scene_hash:
                raise ValueError(f"scene {scene_hash} in the object store has another hash")
            self._cache.put(scene_hash, data)
        scene = scene_pb2.Scene.FromString(data)
        self._scene = (scene_hash, scene)
        return scene

    async def _send_result(
        self, running: RunningTask, yarfd_job: str, final: render_pb2.JobStatus
    ) -> None:
        """Image to the object store, a message to the results stream, then the ack."""
        task = running.task
        reply = await self._yarfd.GetResult(
            render_pb2.GetResultRequest(job_id=yarfd_job), timeout=CALL_TIMEOUT
        )
        w = task.window
        pixels = array_to_numpy(reply.pixels)[w.y0 : w.y1, w.x0 : w.x1]
        variance = array_to_numpy(reply.variance)[w.y0 : w.y1, w.x0 : w.x1]
        samples = task.options.spp - task.options.first_sample
        image = TaskImage(w, samples, pixels, variance).encode()
        name = ResultMessage.image_object_name(
            task.farm, task.job_id, task.task, f"{self.name}-{uuid.uuid4().hex[:8]}"
        )
        await self._buckets.results.put(name, image)
        result = ResultMessage(
            farm=task.farm,
            job_id=task.job_id,
            task=task.task,
            node=self.name,
            ok=True,
            image_object=name,
            closest_hit_rays=final.closest_hit_rays,
            shadow_rays=final.shadow_rays,
            render_seconds=final.elapsed_seconds,
        )
        await self._js.publish(
            streams.result_subject(task.job_id),
            result.encode(),
            headers={"Nats-Msg-Id": f"{task.farm}/{task.job_id}/{task.task}"},
        )
        await running.message.ack_sync()
        _event(
            "task finished",
            job=task.job_id,
            task=task.task,
            node=self.name,
            seconds=round(final.elapsed_seconds, 3),
        )

    async def _report_failure(self, running: RunningTask, error: str) -> None:
        task = running.task
        log.warning("task %s/%d failed: %s", task.job_id, task.task, error)
        result = ResultMessage(
            farm=task.farm,
            job_id=task.job_id,
            task=task.task,
            node=self.name,
            ok=False,
            error=error,
        )
        await self._js.publish(streams.result_subject(task.job_id), result.encode())
        await running.message.ack()
