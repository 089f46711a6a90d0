"""The render farm on NATS JetStream, with real processes on loopback.

A nats-server with JetStream, the coordinator and the render nodes (each
with its own yarfd, one render thread) run as child processes; clients
are yarf.Client, as for a yarfd. Shares of a job take the same sample
points as a whole render, so a farm's image equals a single yarfd's up to
float rounding: it must pass the block z-test and agree pixel for pixel.
"""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import CORNELL_BOX, small_scene
from farm_processes import Farm, Node, free_port, two_node_farm
from imagestats import block_z_test

from yarf import Client, LocalServer, RenderResult, load_scene
from yarf.assets import upload_scene_assets
from yarf.farm import streams
from yarf.farm.cache import SceneCache
from yarf.farm.loops import Loops, run
from yarf.farm.merge import ImageMerge, TaskImage
from yarf.farm.tasks import SplitPolicy, Task, Window, split
from yarf.farm.validation import SubmitChecker
from yarf.v1 import render_pb2, scene_pb2

# Small tasks, so that small test jobs still spread over several nodes:
# 8 sample shares per job, and images over 1024 pixels cut into 16² tiles.
COORDINATOR_ARGS = ["--shares", "8", "--min-task-work", "1024", "--tile-pixels", "1024"]
COORDINATOR_ARGS += ["--tile-size", "16"]
SEED = 7
# Cancel must reach every node's render within this many seconds.
CANCEL_SECONDS = 1.0
CONCURRENT_CLIENTS = 200
# A hang, not a speed: the loops wait up to 5 s, a node its yarfd up to 10 s.
STOP_SECONDS = 30.0


def cornell(width: int, height: int | None = None) -> scene_pb2.Scene:
    scene = load_scene(CORNELL_BOX)
    scene.film.width, scene.film.height = width, height or width
    return scene


@pytest.fixture(scope="module")
def reference() -> Iterator[Client]:
    """A single yarfd rendering the reference images."""
    with LocalServer() as server, server.client() as client:
        yield client


@pytest.fixture(scope="module")
def farm(request: pytest.FixtureRequest) -> Iterator[Farm]:
    """A coordinator and two nodes shared by the tests that leave them running."""
    with two_node_farm(request.session, COORDINATOR_ARGS) as running:
        yield running


@pytest.fixture
def own_farm(request: pytest.FixtureRequest) -> Iterator[Farm]:
    """A farm of its own for a test that kills its processes; its logs print on failure."""
    failed_before = request.session.testsfailed
    with Farm(coordinator_args=COORDINATOR_ARGS) as running:
        yield running
        if request.session.testsfailed > failed_before:
            print(running.log_tail())


@pytest.fixture(scope="module")
def checker() -> Iterator[SubmitChecker]:
    """yarfd's own checks, which read how a job may be divided from its classes."""
    running = SubmitChecker()
    yield running
    running.close()


def split_of(
    checker: SubmitChecker,
    scene: scene_pb2.Scene,
    spp: int,
    policy: SplitPolicy,
    options: render_pb2.RenderOptions | None = None,
) -> list[Task]:
    options = options or render_pb2.RenderOptions(spp=spp)
    checked = checker.check(render_pb2.SubmitRequest(scene=scene, options=options), admin=True)
    return split(checked.accepted, checked.splits, policy)


@pytest.mark.parametrize(("width", "height", "spp"), [(32, 32, 64), (48, 32, 7), (100, 30, 1)])
def test_tasks_cover_every_sample_of_every_pixel_once(
    checker: SubmitChecker, width: int, height: int, spp: int
) -> None:
    tasks = split_of(checker, cornell(width, height), spp, SplitPolicy(8, 16, 1024, 16))
    covered = np.zeros((height, width, spp), dtype=int)
    for task in tasks:
        w = task.window
        covered[w.y0 : w.y1, w.x0 : w.x1, task.first_sample : task.end_sample] += 1
    assert (covered == 1).all()
    assert len({task.index for task in tasks}) == len(tasks)


def test_a_share_of_a_job_asked_for_is_split_within_its_samples_and_window(
    checker: SubmitChecker,
) -> None:
    options = render_pb2.RenderOptions(spp=40, first_sample=8)
    options.crop.CopyFrom(render_pb2.PixelWindow(x0=4, y0=2, x1=40, y1=30))
    tasks = split_of(checker, cornell(48, 32), 40, SplitPolicy(8, 16, 256, 16), options)
    covered = np.zeros((32, 48, 40), dtype=int)
    for task in tasks:
        w = task.window
        assert task.crop
        covered[w.y0 : w.y1, w.x0 : w.x1, task.first_sample : task.end_sample] += 1
    assert (covered[2:30, 4:40, 8:] == 1).all()
    assert covered.sum() == 28 * 36 * 32


def test_jobs_are_divided_by_their_classes_capabilities(checker: SubmitChecker) -> None:
    """Sample shares need an integrator declaring sample_passes; tiles a pixel_local
    transport too, and a filter no wider than a pixel. The light tracer (class
    "light") and BDPT splat anywhere on the film, so their jobs are never tiled."""
    policy = SplitPolicy(shares=4, min_task_work=1, tile_pixels=256, tile_size=16)
    assert any(task.crop for task in split_of(checker, cornell(32), 16, policy))
    wide_filter = cornell(32)
    wide_filter.film.filter.kind = scene_pb2.ReconstructionFilter.GAUSSIAN
    untiled = [wide_filter]
    for transport in ("light", "bdpt"):
        splatting = cornell(32)
        splatting.transport.class_name = transport
        untiled.append(splatting)
    for scene in untiled:
        tasks = split_of(checker, scene, 16, policy)
        assert not any(task.crop for task in tasks) and len(tasks) == 4, scene.transport
    for transport in ("volpath", "sppm"):
        tiled = cornell(32)
        tiled.transport.class_name = transport
        assert any(task.crop for task in split_of(checker, tiled, 16, policy)), transport
    other_integrator = cornell(32)
    other_integrator.integrator.class_name = "vegas"
    assert len(split_of(checker, other_integrator, 16, policy)) == 1


def test_merge_weights_shares_by_their_sample_counts() -> None:
    window = Window(0, 0, 2, 1)
    merge = ImageMerge(2, 1)
    merge.add(TaskImage(window, 1, np.full((1, 2, 3), 4.0), np.full((1, 2, 3), 1.0)))
    merge.add(TaskImage(window, 3, np.full((1, 2, 3), 0.0), np.full((1, 2, 3), 2.0)))
    merge.add(TaskImage(Window(1, 0, 2, 1), 4, np.full((1, 1, 3), 2.0), np.full((1, 1, 3), 0.5)))
    pixels, variance = merge.result()
    # (1·4 + 3·0) / 4; (1·4 + 3·0 + 4·2) / 8.
    np.testing.assert_allclose(pixels[0, :, 0], [1.0, 1.5])
    # (1·1 + 9·2) / 16; (1·1 + 9·2 + 16·0.5) / 64.
    np.testing.assert_allclose(variance[0, :, 0], [19 / 16, 27 / 64])
    image = TaskImage(window, 2, pixels, variance)
    decoded = TaskImage.decode(image.encode())
    assert decoded.window == window and decoded.samples == 2
    np.testing.assert_array_equal(decoded.pixels, pixels)


def render(client: Client, scene: scene_pb2.Scene, spp: int, timeout: float = 120) -> str:
    job_id = client.submit(scene, spp, SEED, name="farm-test")
    status = client.wait(job_id, timeout=timeout)
    assert status.state == render_pb2.SUCCEEDED, status
    return job_id


def assert_same_image(farm_image: RenderResult, reference_image: RenderResult) -> None:
    """The farm's merge against a single render: z-test, pixels and variances."""
    test = block_z_test(
        farm_image.pixels,
        farm_image.variance,
        reference_image.pixels,
        reference_image.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, (
        f"z-test failed (threshold {test.threshold:.2f}):\n{test.report()}"
    )
    # The same samples: equal up to float rounding, but for the rare pixel
    # where a non-finite sample was dropped (its share then counts one
    # sample too many).
    close = np.isclose(farm_image.pixels, reference_image.pixels, rtol=1e-4, atol=1e-5)
    assert close.mean() > 0.99, f"{np.count_nonzero(~close)} pixel values differ"
    # Shares' variances combine into the whole render's (they omit only the
    # spread between share means, small next to the samples' own).
    lit = reference_image.variance > 1e-8
    ratio = float(np.mean(farm_image.variance[lit] / reference_image.variance[lit]))
    assert 0.8 < ratio < 1.25, f"variance ratio farm / single render {ratio:.3f}"


def events_of(nodes: list[Node], kind: str, job_id: str) -> list[dict[str, object]]:
    return [event for node in nodes for event in node.events(kind) if event["job"] == job_id]


def wait_until(condition: Callable[[], object], what: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting: {what}")


def test_two_nodes_render_the_image_of_a_single_server(farm: Farm, reference: Client) -> None:
    with farm.client() as client:
        shares = render(client, cornell(32), 64)
        tiles = render(client, cornell(48, 32), 64)
        shares_image, tiles_image = client.raw(shares), client.raw(tiles)
    assert_same_image(shares_image, reference.raw(render(reference, cornell(32), 64)))
    assert_same_image(tiles_image, reference.raw(render(reference, cornell(48, 32), 64)))
    # 8 sample shares; 6 tiles × 2 shares.
    assert len(events_of(farm.nodes, "task finished", shares)) >= 8
    assert len(events_of(farm.nodes, "task finished", tiles)) >= 12
    for node in farm.nodes:
        assert any(e["job"] in (shares, tiles) for e in node.events("task finished")), (
            f"{node.name} rendered no task"
        )


def textured_cornell(folder: Path) -> scene_pb2.Scene:
    """The Cornell box whose white walls read an image file beside it (tex.png)."""
    from PIL import Image

    rng = np.random.default_rng(5)
    Image.fromarray(rng.integers(40, 230, (8, 8, 3), dtype=np.uint8)).save(folder / "tex.png")
    scene = cornell(24)
    texture = scene.textures.add(name="tex")
    texture.texture.class_name = "bitmap"
    texture.texture.properties.values["filename"].string_value = "tex.png"
    white = next(m for m in scene.materials if m.name == "white")
    white.properties.values["reflectance"].reference = "tex"
    return scene


def test_texture_files_reach_the_nodes_by_hash(
    farm: Farm, reference: Client, tmp_path: Path
) -> None:
    """The client uploads to the coordinator as to a yarfd; nodes copy to theirs."""
    farm_scene, reference_scene = textured_cornell(tmp_path), textured_cornell(tmp_path)
    with farm.client() as client:
        # The image and the box's meshes, once.
        assert upload_scene_assets(client, farm_scene, tmp_path) == 1 + len(farm_scene.shapes)
        assert upload_scene_assets(client, textured_cornell(tmp_path), tmp_path) == 0
        assert "asset" in farm_scene.textures[0].texture.properties.values
        farm_image = client.raw(render(client, farm_scene, 32))
        # A scene naming an asset the farm lacks is refused at Submit.
        farm_scene.textures[0].texture.properties.values["asset"].string_value = "ab" * 32
        with pytest.raises(grpc.RpcError) as refused:
            client.submit(farm_scene, 8, SEED)
        assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert "not on this farm" in (refused.value.details() or "")
    upload_scene_assets(reference, reference_scene, tmp_path)
    assert_same_image(farm_image, reference.raw(render(reference, reference_scene, 32)))


def test_results_come_as_raw_exr_and_png(farm: Farm) -> None:
    with farm.client() as client:
        job_id = render(client, cornell(24, 16), 8)
        exr = client.encoded(job_id, render_pb2.GetResultRequest.EXR)
        png = client.encoded(job_id, render_pb2.GetResultRequest.PNG)
        pixels = client.image(job_id)
    assert exr[:4] == b"\x76\x2f\x31\x01"
    # Uncompressed half floats: the last scanline's R channel ends the file.
    last_red = np.frombuffer(exr[-24 * 2 :], dtype="<f2").astype(np.float32)
    np.testing.assert_allclose(last_red, pixels[-1, :, 0], rtol=1e-3, atol=1e-4)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    pil = pytest.importorskip("PIL.Image")
    import io

    decoded = np.asarray(pil.open(io.BytesIO(png)).convert("RGB"))
    assert decoded.shape == (16, 24, 3)


def test_a_job_the_renderer_refuses_fails_with_its_reason(farm: Farm) -> None:
    scene = cornell(16)
    scene.materials[0].class_name = "no_such_bsdf"
    with farm.client() as client:
        status = client.wait(client.submit(scene, 16, SEED, name="refused"), timeout=60)
        assert status.state == render_pb2.FAILED
        assert "no_such_bsdf" in status.error, status.error
        too_large = cornell(16)
        too_large.film.width = 20000
        with pytest.raises(grpc.RpcError) as refused:
            client.submit(too_large, 16)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "film" in str(refused.value.details())


def test_a_node_killed_mid_task_loses_its_task_to_another(
    own_farm: Farm, reference: Client
) -> None:
    own_farm.start_coordinator()
    victim, survivor = own_farm.start_node(), own_farm.start_node()
    scene = cornell(48)
    with own_farm.client() as client:
        job_id = client.submit(scene, 1024, SEED, name="node-killed")

        def in_flight() -> dict[str, object] | None:
            """A full share (not the short first one) the victim began 0.2 s ago."""
            finished = {e["task"] for e in events_of([victim], "task finished", job_id)}
            for event in events_of([victim], "task started", job_id):
                begun = time.time() - float(event["at"])  # type: ignore[arg-type]
                if event["task"] != 0 and event["task"] not in finished and begun > 0.2:
                    return event
            return None

        wait_until(in_flight, "the victim is in the middle of a task")
        started = in_flight()
        victim.kill()
        assert started is not None
        status = client.wait(job_id, timeout=120)
        assert status.state == render_pb2.SUCCEEDED, status
        farm_image = client.raw(job_id)
    # JetStream redelivered the victim's task (after its ack wait) to the survivor.
    redelivered = [
        e
        for e in events_of([survivor], "task started", job_id)
        if e["task"] == started["task"] and int(e["delivered"]) >= 2  # type: ignore[call-overload]
    ]
    assert redelivered, f"task {started['task']} was not redelivered to {survivor.name}"
    assert_same_image(farm_image, reference.raw(render(reference, scene, 1024)))


def test_cancel_stops_every_node_within_a_second(farm: Farm) -> None:
    with farm.client() as client:
        # 8 shares of 16384 samples of 32² pixels: seconds each, so that
        # every node is still rendering its first when Cancel comes (a
        # share of 2048 took 0.5 s, a race with the Cancel 0.5 s in).
        job_id = client.submit(cornell(32), 131072, SEED, name="cancelled")
        for node in farm.nodes:
            wait_until(
                lambda node=node: events_of([node], "task started", job_id),  # type: ignore[misc]
                f"{node.name} starts a task",
            )
        time.sleep(0.5)
        cancelled_at = time.time()
        client.cancel(job_id)
        wait_until(
            lambda: len(events_of(farm.nodes, "task cancelled", job_id)) == len(farm.nodes),
            "every node stops its task",
            timeout=10,
        )
        status = client.wait(job_id, timeout=10)
    assert status.state == render_pb2.CANCELLED
    for event in events_of(farm.nodes, "task cancelled", job_id):
        delay = float(event["stopped_at"]) - cancelled_at  # type: ignore[arg-type]
        print(f"{event['node']}: yarfd job left RUNNING {1000 * delay:.0f} ms after Cancel")
        assert delay < CANCEL_SECONDS, f"{event['node']} stopped {delay:.2f} s after Cancel"
    # The queued tasks were purged: no node starts one later.
    time.sleep(1.0)
    assert len(events_of(farm.nodes, "task started", job_id)) == len(farm.nodes)


def test_jobs_survive_a_coordinator_killed_under_them(own_farm: Farm, reference: Client) -> None:
    coordinator = own_farm.start_coordinator()
    own_farm.start_node()
    own_farm.start_node()
    scene = cornell(32)
    with own_farm.client() as client:
        jobs = [client.submit(scene, 1024, SEED, name=f"survivor-{i}") for i in range(3)]
        wait_until(lambda: client.status(jobs[0]).state == render_pb2.RUNNING, "the first job runs")
        states = {status.job_id: status.state for status in client.list()}
    assert render_pb2.QUEUED in states.values(), "no job was still queued"
    coordinator.kill()
    time.sleep(1.0)  # nodes keep rendering; their results wait in the stream
    own_farm.start_coordinator()
    with own_farm.client() as client:
        for job_id in jobs:
            status = client.wait(job_id, timeout=120)
            assert status.state == render_pb2.SUCCEEDED, status
        images = [client.raw(job_id) for job_id in jobs]
        later = render(client, small_scene(), 4)
    assert later not in jobs
    expected = reference.raw(render(reference, scene, 1024))
    for image in images:
        assert_same_image(image, expected)


def test_a_high_priority_job_submitted_last_starts_first(own_farm: Farm) -> None:
    own_farm.start_coordinator()
    scene = cornell(32)
    with own_farm.client() as client:
        priorities = {"low-1": 10, "low-2": 20, "normal": 50, "high": 90, "raised": 5}
        jobs = {}
        for name, priority in priorities.items():
            request = render_pb2.SubmitRequest(
                scene=scene, options=render_pb2.RenderOptions(spp=16, seed=SEED), name=name
            )
            request.priority = priority
            jobs[name] = client.render_service.Submit(request).job_id
        raised = client.render_service.SetPriority(
            render_pb2.SetPriorityRequest(job_id=jobs["raised"], priority=95)
        )
        assert raised.priority == 95
        # The node starts with every job queued: it must take them by tier.
        node = own_farm.start_node()
        for job_id in jobs.values():
            assert client.wait(job_id, timeout=60).state == render_pb2.SUCCEEDED
    names = {job_id: name for name, job_id in jobs.items()}
    order: list[str] = []
    for event in node.events("task started"):
        name = names[str(event["job"])]
        if name not in order:
            order.append(name)
    assert order == ["high", "raised", "normal", "low-1", "low-2"], order
    last_of = {
        name: max(i for i, e in enumerate(node.events("task started")) if names[e["job"]] == name)
        for name in names.values()
    }
    first_of = {
        name: min(i for i, e in enumerate(node.events("task started")) if names[e["job"]] == name)
        for name in names.values()
    }
    # Every task of a higher tier before any of a lower one.
    assert last_of["raised"] < first_of["normal"] and last_of["normal"] < first_of["low-1"]


def test_many_concurrent_clients_lose_no_job(farm: Farm) -> None:
    errors: list[BaseException] = []
    lock = threading.Lock()

    def one_client(index: int) -> str:
        with farm.client() as client:
            job_id = client.submit(small_scene(8), 4, index, name=f"client-{index}")
            status = client.wait(job_id, timeout=120)
            assert status.state == render_pb2.SUCCEEDED, status
            pixels = client.image(job_id)
            assert pixels.shape == (8, 8, 3) and pixels.mean() > 0
            return job_id

    def guarded(index: int) -> str:
        try:
            return one_client(index)
        except BaseException as error:
            with lock:
                errors.append(error)
            return ""

    start = time.monotonic()
    with ThreadPoolExecutor(CONCURRENT_CLIENTS) as pool:
        job_ids = list(pool.map(guarded, range(CONCURRENT_CLIENTS)))
    seconds = time.monotonic() - start
    print(f"{CONCURRENT_CLIENTS} clients: {seconds:.1f} s")
    assert not errors, f"{len(errors)} clients failed, first: {errors[0]!r}"
    assert len(set(job_ids)) == CONCURRENT_CLIENTS
    with farm.client() as client:
        listed = {status.job_id: status.state for status in client.list()}
    assert all(listed[job_id] == render_pb2.SUCCEEDED for job_id in job_ids)


def submit(client: Client, scene: scene_pb2.Scene, spp: int, name: str, **fields: int) -> str:
    """Submits with SubmitRequest fields the Client does not take (max_retries)."""
    request = render_pb2.SubmitRequest(
        scene=scene, options=render_pb2.RenderOptions(spp=spp, seed=SEED), name=name, **fields
    )
    return str(client.render_service.Submit(request).job_id)


def stored_advisories(nats_url: str) -> int:
    """Max-deliveries advisories waiting in the farm's advisory stream."""

    async def count() -> int:
        import nats

        nc = await nats.connect(nats_url)
        try:
            info = await nc.jetstream().stream_info(streams.ADVISORIES_STREAM)
            return int(info.state.messages)
        finally:
            await nc.close()

    return asyncio.run(count())


def test_a_task_whose_deliveries_run_out_without_a_coordinator_is_retried(
    own_farm: Farm,
) -> None:
    coordinator = own_farm.start_coordinator()
    with own_farm.client() as client:
        job_id = submit(client, small_scene(8), 1, "spent", max_retries=1)
    coordinator.kill()
    # A node whose yarfd never answers gives every delivery of the task back.
    broken = own_farm.start_node(yarfd=f"127.0.0.1:{free_port()}")
    wait_until(
        lambda: stored_advisories(own_farm.nats_url) >= 1,
        "JetStream gives up on the task",
        timeout=40,
    )
    broken.stop()
    assert max(int(e["delivered"]) for e in events_of([broken], "task started", job_id)) == 5
    own_farm.start_node()
    # The advisory sent while no coordinator ran is handled by the next one.
    own_farm.start_coordinator()
    with own_farm.client() as client:
        status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status
    assert stored_advisories(own_farm.nats_url) == 0


def test_loops_end_a_loop_whose_client_turns_the_cancel_into_a_timeout() -> None:
    async def scenario() -> bool:
        loops = Loops()

        cancels = 0

        async def retrying() -> None:
            nonlocal cancels
            # The bound lets asyncio.run's own cancel end the loop should stop fail.
            while loops.running and cancels < 2:
                try:
                    try:
                        await asyncio.sleep(60)
                    except asyncio.CancelledError:
                        cancels += 1
                        raise TimeoutError from None  # as nats-py's fetch now and then does
                except TimeoutError:
                    continue

        task = loops.start(retrying(), name="retrying")
        await asyncio.sleep(0)
        await loops.stop(timeout=5.0)
        return task.done()

    assert asyncio.run(scenario())


def test_run_ends_a_task_that_loses_its_first_cancels() -> None:
    """As nats-py's reconnect loop when a cancel meets its connect timeout."""
    ended = threading.Event()

    async def reconnecting() -> None:
        for _ in range(3):
            try:
                await asyncio.sleep(60)
            except asyncio.CancelledError:
                continue
        try:
            await asyncio.sleep(60)
        finally:
            ended.set()

    left: list[asyncio.Task[None]] = []

    async def main() -> str:
        left.append(asyncio.create_task(reconnecting(), name="reconnect"))
        await asyncio.sleep(0)
        return "stopped"

    began = time.monotonic()
    assert run(main(), timeout=5.0) == "stopped"
    assert ended.is_set()
    assert time.monotonic() - began < 5.0


def test_run_returns_after_its_timeout_past_a_task_that_ignores_every_cancel(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def deaf_to_cancels() -> None:
        while True:
            try:
                await asyncio.sleep(60)
            except asyncio.CancelledError:
                continue

    left: list[asyncio.Task[None]] = []

    async def main() -> int:
        left.append(asyncio.create_task(deaf_to_cancels(), name="deaf to cancels"))
        await asyncio.sleep(0)
        return 7

    began = time.monotonic()
    assert run(main(), timeout=0.5) == 7
    assert time.monotonic() - began < 5.0
    assert "deaf to cancels" in caplog.text


@pytest.mark.parametrize("after", [0.0, 0.5, 1.5], ids=["at once", "0.5 s", "1.5 s"])
def test_farm_processes_stop_on_sigterm_after_nats_is_gone(after: float) -> None:
    """A coordinator and a node whose NATS died a moment before still exit cleanly on SIGTERM."""
    with Farm(coordinator_args=COORDINATOR_ARGS) as farm:
        processes = {"coordinator": farm.start_coordinator(), "node": farm.start_node()}
        assert farm.nats is not None
        farm.nats.kill()
        time.sleep(after)
        for process in processes.values():
            process.process.send_signal(signal.SIGTERM)
        for what, process in processes.items():
            try:
                process.process.wait(STOP_SECONDS)
            except subprocess.TimeoutExpired:
                pytest.fail(
                    f"the {what} did not stop within {STOP_SECONDS} s:\n{process.log[-3000:]}"
                )
            assert process.process.returncode == 0, f"the {what}:\n{process.log[-3000:]}"


def test_a_task_past_the_node_timeout_fails_and_the_node_serves_on(own_farm: Farm) -> None:
    own_farm.start_coordinator()
    node = own_farm.start_node(extra_args=["--task-timeout", "1"])
    with own_farm.client() as client:
        # Even the short first share of 32768 samples takes seconds.
        slow = submit(client, cornell(32), 32768, "too-slow", max_retries=1)
        status = client.wait(slow, timeout=60)
        assert status.state == render_pb2.FAILED, status
        assert "timed out after 1 s" in status.error, status.error
        # The first try and its retry.
        assert len(events_of([node], "task timed out", slow)) >= 2
        later = render(client, small_scene(), 4)
    assert events_of([node], "task finished", later)
    assert not events_of([node], "task timed out", later)


def test_set_priority_leaves_a_running_task_on_its_node(own_farm: Farm) -> None:
    own_farm.start_coordinator()
    node = own_farm.start_node()
    with own_farm.client() as client:
        # 8 shares of 32² pixels, about a second each on one thread.
        job_id = submit(client, cornell(32), 3072, "moved")

        def in_flight() -> bool:
            """A full share the node began 0.2 s ago: the coordinator has its heartbeat."""
            finished = {e["task"] for e in events_of([node], "task finished", job_id)}
            return any(
                event["task"] != 0
                and event["task"] not in finished
                and time.time() - float(event["at"]) > 0.2
                for event in events_of([node], "task started", job_id)
            )

        wait_until(in_flight, "the node is in the middle of a task")
        client.render_service.SetPriority(render_pb2.SetPriorityRequest(job_id=job_id, priority=90))
        status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status
    started = sorted(int(e["task"]) for e in events_of([node], "task started", job_id))
    assert started == list(range(8)), f"tasks started: {started}"


def test_the_scene_cache_deletes_the_least_recently_used_scenes(tmp_path: Path) -> None:
    import hashlib

    scenes = {name: name.encode() * 100 for name in ("a", "b", "c")}  # 100 bytes each
    hashes = {name: hashlib.sha256(data).hexdigest() for name, data in scenes.items()}
    cache = SceneCache(tmp_path / "cache", max_bytes=250)
    clock = iter(range(1_000_000_000, 2_000_000_000, 1_000_000_000 // 10))

    def used(name: str) -> None:
        """Gives the file a distinct use time (file times may be coarse)."""
        path = tmp_path / "cache" / f"{hashes[name]}.scene"
        stamp = next(clock)
        os.utime(path, ns=(stamp, stamp))

    cache.put(hashes["a"], scenes["a"])
    used("a")
    cache.put(hashes["b"], scenes["b"])
    used("b")
    assert cache.get(hashes["a"]) == scenes["a"]  # a is now used after b
    used("a")
    cache.put(hashes["c"], scenes["c"])
    assert cache.get(hashes["b"]) is None, "b was the least recently used"
    assert cache.get(hashes["a"]) == scenes["a"] and cache.get(hashes["c"]) == scenes["c"]
    assert sum(p.stat().st_size for p in (tmp_path / "cache").iterdir()) <= 250
    # A scene larger than the limit still stays while it is used.
    big = b"x" * 400
    cache.put(hashlib.sha256(big).hexdigest(), big)
    assert [p.stat().st_size for p in (tmp_path / "cache").iterdir()] == [400]
    # A damaged file is a miss; no limit keeps everything.
    (tmp_path / "cache" / f"{hashes['a']}.scene").write_bytes(b"damaged")
    assert cache.get(hashes["a"]) is None
    unlimited = SceneCache(tmp_path / "all", max_bytes=0)
    for name, data in scenes.items():
        unlimited.put(hashes[name], data)
    assert len(list((tmp_path / "all").iterdir())) == 3
