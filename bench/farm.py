"""The render farm against a single yarfd: one Cornell-box job rendered by a
local yarfd with one render thread, then by the farm (nats-server,
coordinator) with one and with two nodes, each node's yarfd with one
render thread. Prints samples/s, the farm's throughput ratios and
overhead, and the latency from Submit to the first preview (the first
status with samples done). Results also go to out/bench/farm.json.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from yarf import Client, LocalServer, load_scene
from yarf.v1 import render_pb2, scene_pb2

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
from farm_processes import Farm, find_nats_server  # noqa: E402

SIZE = 64
SPP = 512
RUNS = 2


def scene() -> scene_pb2.Scene:
    cornell = load_scene(ROOT / "scenes" / "cornell-box" / "scene.json")
    cornell.film.width = cornell.film.height = SIZE
    return cornell


def timed_job(client: Client, seed: int) -> tuple[float, float]:
    """Seconds from Submit to the end of the job, and to its first preview."""
    start = time.monotonic()
    job_id = client.submit(scene(), SPP, seed, name="bench")
    first_preview = 0.0
    last: render_pb2.JobStatus | None = None
    for status in client.watch(job_id, timeout=1800):
        if not first_preview and status.samples_done > 0:
            first_preview = time.monotonic() - start
        last = status
    if last is None or last.state != render_pb2.SUCCEEDED:
        raise RuntimeError(f"the bench job did not succeed: {last}")
    return time.monotonic() - start, first_preview


def best_of(client: Client) -> tuple[float, float]:
    """The fastest of RUNS jobs (after a small one warming caches and connections)."""
    client.wait(client.submit(scene(), 1, 0, name="warm-up"), timeout=600)
    runs = [timed_job(client, seed) for seed in range(1, RUNS + 1)]
    return min(runs)


def main() -> None:
    try:
        find_nats_server()
    except FileNotFoundError as error:
        print(f"bench/farm.py skipped: {error}")
        return
    samples = SIZE * SIZE * SPP
    results: dict[str, dict[str, float]] = {}
    with LocalServer(threads=1) as server, server.client() as client:
        seconds, preview = best_of(client)
    results["local yarfd, 1 thread"] = {"seconds": seconds, "first_preview": preview}
    for nodes in (1, 2):
        with Farm() as farm:
            farm.start_coordinator()
            for _ in range(nodes):
                farm.start_node(threads=1)
            with farm.client() as client:
                seconds, preview = best_of(client)
        label = f"farm, {nodes} node{'s' if nodes > 1 else ''} × 1 thread"
        results[label] = {"seconds": seconds, "first_preview": preview}

    local = results["local yarfd, 1 thread"]["seconds"]
    one = results["farm, 1 node × 1 thread"]["seconds"]
    two = results["farm, 2 nodes × 1 thread"]["seconds"]
    print(f"Cornell box {SIZE}² × {SPP} spp, best of {RUNS}:")
    for label, figures in results.items():
        figures["samples_per_second"] = samples / figures["seconds"]
        print(
            f"  {label:28s} {figures['seconds']:7.2f} s  "
            f"{figures['samples_per_second'] / 1e6:6.3f} M samples/s  "
            f"first preview {1000 * figures['first_preview']:6.0f} ms"
        )
    ratios = {
        "farm 1 node / local": local / one,
        "farm 2 nodes / local": local / two,
        "farm 2 nodes / 1 node": one / two,
        "farm overhead, 1 node (s)": one - local,
    }
    print("Throughput ratios:")
    for label, value in ratios.items():
        print(f"  {label:28s} {value:6.2f}")
    output = ROOT / "out" / "bench"
    output.mkdir(parents=True, exist_ok=True)
    (output / "farm.json").write_text(
        json.dumps({"size": SIZE, "spp": SPP, "results": results, "ratios": ratios}, indent=2)
    )


if __name__ == "__main__":
    main()
