"""The prepare passes on one thread and on all: photon mapping's two maps,
SPPM's map per pass, radiosity's solve.

Each job is almost all preparing (a 32×32 film at one sample per pass), so
its seconds on one thread over its seconds on every thread is how far the
prepare pass scales. The images must be the same bit for bit (the passes
join their threads' work in a fixed order). Results also go to
out/bench/prepare_threads.json.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np
from bench_report import ROOT, cpu_model

from yarf import Client, LocalServer, component, load_scene
from yarf.v1 import render_pb2

GLOSSY_BOX = ROOT / "scenes" / "cornell-box" / "glossy.json"
DIFFUSE_BOX = ROOT / "scenes" / "cornell-box" / "scene.json"
# Transport, scene, spp: each pass of SPPM shoots its own map.
JOBS = {
    "photon_map": (
        component("photon_map", photons=1_000_000, caustic_photons=1_000_000),
        GLOSSY_BOX,
        1,
    ),
    "sppm": (component("sppm", photons_per_pass=200_000), GLOSSY_BOX, 8),
    "radiosity": (component("radiosity"), DIFFUSE_BOX, 1),
}


def render(client: Client, method: str, threads: int) -> tuple[np.ndarray, float]:
    transport, path, spp = JOBS[method]
    scene = load_scene(path)
    scene.film.width = scene.film.height = 32
    job = client.submit(scene, spp, 1, transport=transport, threads=threads)
    status = client.wait(job)
    if status.state != render_pb2.SUCCEEDED:
        sys.exit(f"{method} failed: {status.error}")
    return client.raw(job).pixels, status.elapsed_seconds


def main() -> None:
    cores = os.cpu_count() or 1
    report: dict[str, object] = {"cpu_model": cpu_model(), "threads": cores}
    with LocalServer() as server, server.client() as client:
        for method in JOBS:
            one, one_seconds = render(client, method, 1)
            every, every_seconds = render(client, method, cores)
            report[method] = {
                "one_thread_seconds": one_seconds,
                "seconds": every_seconds,
                "speedup": one_seconds / every_seconds,
                "same_image": bool(np.array_equal(one, every)),
            }
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "prepare_threads.json").write_text(json.dumps(report, indent=2))
    print(f"cpu: {report['cpu_model']}, {cores} threads")
    for method in JOBS:
        row = report[method]
        assert isinstance(row, dict)
        print(
            f"{method:<12} 1 thread {row['one_thread_seconds']:6.2f} s, {cores} threads "
            f"{row['seconds']:6.2f} s: {row['speedup']:.2f}x, same image {row['same_image']}"
        )


if __name__ == "__main__":
    main()
