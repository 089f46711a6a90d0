"""The JetStream resources the coordinator and the nodes share, and their names.

Both sides create what is missing at start, with the same configuration,
so either may start first.
"""

from __future__ import annotations

from dataclasses import dataclass

from nats.js import JetStreamContext
from nats.js.api import (
    AckPolicy,
    ConsumerConfig,
    KeyValueConfig,
    ObjectStoreConfig,
    RetentionPolicy,
    StorageType,
    StreamConfig,
)
from nats.js.errors import BadRequestError, NotFoundError
from nats.js.kv import KeyValue
from nats.js.object_store import ObjectStore

# Tasks: yarf.tasks.<tier>.<job id>. The job token lets Cancel and
# SetPriority purge a job's queued tasks with one subject filter.
TASKS_STREAM = "YARF_TASKS"
# Task results (small JSON messages; the images go to RESULTS_BUCKET):
# yarf.results.<job id>.
RESULTS_STREAM = "YARF_RESULTS"
# Scenes, keyed by the sha256 of the serialized yarf.v1.Scene: a scene
# travels once however many tasks and jobs use it.
SCENES_BUCKET = "yarf-scenes"
# Mesh and texture files by SHA-256, uploaded through the coordinator's
# AssetService and copied by each node to its yarfd.
ASSETS_BUCKET = "yarf-assets"
# Task images (npz of pixels and variance), deleted once merged; those of
# renders discarded as duplicates expire.
RESULTS_BUCKET = "yarf-results"
RESULTS_BUCKET_TTL = 24 * 3600.0
# cancel.<job>: the job was cancelled; progress.<job>.<task>: a node's
# progress on a task, refreshed with every heartbeat.
JOBS_BUCKET = "yarf-jobs"
# The coordinator's durable consumer of RESULTS_STREAM.
RESULTS_DURABLE = "yarf-coordinator"
# The server's advisories of tasks whose deliveries ran out, kept in a
# stream: one sent while no coordinator runs waits for the next one (a
# plain subscription would miss it and the task would stall for good).
ADVISORIES_STREAM = "YARF_TASK_ADVISORIES"
MAX_DELIVERIES_SUBJECT = f"$JS.EVENT.ADVISORY.CONSUMER.MAX_DELIVERIES.{TASKS_STREAM}.*"
ADVISORIES_DURABLE = "yarf-coordinator-advisories"
ADVISORIES_MAX_AGE = 7 * 24 * 3600.0

# JetStream 2.9 has no per-message priority: one subject and one consumer
# per tier, pulled in this order.
TIERS = ("high", "normal", "low")
# A node that stops sending in-progress acks (it died) loses its task to
# another node after this many seconds.
TASK_ACK_WAIT = 5.0
# Deliveries of a task before JetStream gives up on it (the coordinator
# then fails or retries the job).
TASK_MAX_DELIVER = 5
# Messages with the same Nats-Msg-Id within this window are stored once.
DUPLICATE_WINDOW = 120.0
# The coordinator acks a result only once it is in SQLite; a coordinator
# that died is redelivered its unacked results after this many seconds.
RESULT_ACK_WAIT = 5.0
# Cancel flags outlive any task of their job still in flight.
JOBS_BUCKET_TTL = 24 * 3600.0


def tier_of(priority: int) -> str:
    """The tier of a job priority 1..100: ≥67 high, ≥34 normal, else low."""
    if priority >= 67:
        return "high"
    if priority >= 34:
        return "normal"
    return "low"


def task_subject(tier: str, job_id: str) -> str:
    return f"yarf.tasks.{tier}.{job_id}"


def job_tasks_filter(job_id: str) -> str:
    """The subjects of a job's tasks in every tier."""
    return f"yarf.tasks.*.{job_id}"


def result_subject(job_id: str) -> str:
    return f"yarf.results.{job_id}"


def tier_durable(tier: str) -> str:
    """The durable pull consumer of a tier, shared by every node."""
    return f"yarf-node-{tier}"


def cancel_key(job_id: str) -> str:
    return f"cancel.{job_id}"


def progress_key(job_id: str, task: int) -> str:
    return f"progress.{job_id}.{task}"


@dataclass(frozen=True)
class Buckets:
    jobs: KeyValue
    scenes: ObjectStore
    results: ObjectStore
    assets: ObjectStore


async def _ensure_stream(js: JetStreamContext, config: StreamConfig) -> None:
    assert config.name is not None
    try:
        await js.stream_info(config.name)
        return
    except NotFoundError:
        pass
    try:
        await js.add_stream(config)
    except BadRequestError:
        # Created by another process meanwhile.
        await js.stream_info(config.name)


async def _ensure_consumer(js: JetStreamContext, stream: str, config: ConsumerConfig) -> None:
    assert config.durable_name is not None
    try:
        await js.consumer_info(stream, config.durable_name)
        return
    except NotFoundError:
        pass
    try:
        await js.add_consumer(stream, config)
    except BadRequestError:
        await js.consumer_info(stream, config.durable_name)


async def _ensure_object_store(js: JetStreamContext, bucket: str, ttl: float | None) -> ObjectStore:
    try:
        return await js.create_object_store(
            bucket, config=ObjectStoreConfig(storage=StorageType.FILE, ttl=ttl)
        )
    except BadRequestError:
        return await js.object_store(bucket)


async def ensure_resources(js: JetStreamContext) -> Buckets:
    """Creates the streams, consumers and buckets that are missing; returns the buckets."""
    for name, subject in ((TASKS_STREAM, "yarf.tasks.>"), (RESULTS_STREAM, "yarf.results.>")):
        await _ensure_stream(
            js,
            StreamConfig(
                name=name,
                subjects=[subject],
                retention=RetentionPolicy.WORK_QUEUE,
                storage=StorageType.FILE,
                duplicate_window=DUPLICATE_WINDOW,
            ),
        )
    await _ensure_stream(
        js,
        StreamConfig(
            name=ADVISORIES_STREAM,
            subjects=[MAX_DELIVERIES_SUBJECT],
            retention=RetentionPolicy.WORK_QUEUE,
            storage=StorageType.FILE,
            max_age=ADVISORIES_MAX_AGE,
        ),
    )
    await _ensure_consumer(
        js,
        ADVISORIES_STREAM,
        ConsumerConfig(
            durable_name=ADVISORIES_DURABLE,
            ack_policy=AckPolicy.EXPLICIT,
            ack_wait=RESULT_ACK_WAIT,
        ),
    )
    for tier in TIERS:
        await _ensure_consumer(
            js,
            TASKS_STREAM,
            ConsumerConfig(
                durable_name=tier_durable(tier),
                filter_subject=f"yarf.tasks.{tier}.>",
                ack_policy=AckPolicy.EXPLICIT,
                ack_wait=TASK_ACK_WAIT,
                max_deliver=TASK_MAX_DELIVER,
            ),
        )
    await _ensure_consumer(
        js,
        RESULTS_STREAM,
        ConsumerConfig(
            durable_name=RESULTS_DURABLE,
            filter_subject="yarf.results.>",
            ack_policy=AckPolicy.EXPLICIT,
            ack_wait=RESULT_ACK_WAIT,
        ),
    )
    # A bucket made by another client version may differ in some default:
    # then it is used as it is.
    try:
        jobs = await js.create_key_value(
            KeyValueConfig(
                bucket=JOBS_BUCKET, history=1, ttl=JOBS_BUCKET_TTL, storage=StorageType.FILE
            )
        )
    except BadRequestError:
        jobs = await js.key_value(JOBS_BUCKET)
    scenes = await _ensure_object_store(js, SCENES_BUCKET, None)
    results = await _ensure_object_store(js, RESULTS_BUCKET, RESULTS_BUCKET_TTL)
    assets = await _ensure_object_store(js, ASSETS_BUCKET, None)
    return Buckets(jobs=jobs, scenes=scenes, results=results, assets=assets)
