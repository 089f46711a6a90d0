"""A BSDF in another process inside the path tracer: the Cornell box with
its Lambertian materials in process (C++), then as the same model in a
Python component over a unix socket and over TCP, and in a Go component
over a unix socket. The path tracer calls a remote model once per
material per bounce per batch, so batches are large (64² pixels × 32
samples). Prints samples/s and ratios to in-process with the same batches
and with the default ones (32² pixels × 1 sample). Results also go to
out/bench/remote_components.json.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from yarf import Client, LocalServer, component, load_scene
from yarf.v1 import render_pb2, scene_pb2

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
from component_process import ComponentProcess  # noqa: E402

SIZE = 128
SPP = 64
# Batches of 64² pixels × 32 samples: a remote call carries a whole batch's
# paths.
TILE = 64
SAMPLES_PER_PASS = 32
DEFAULT = "in-process C++, default batches"
SAME = "in-process C++"
PYTHON_LAMBERTIAN = ROOT / "components" / "python" / "examples" / "lambertian.py"
GO_LAMBERTIAN = ROOT / "build" / "go" / "bin" / "yarf-go-lambertian"


def scene_with(class_name: str, address: str) -> scene_pb2.Scene:
    scene = load_scene(ROOT / "scenes" / "cornell-box" / "scene.json")
    scene.film.width = scene.film.height = SIZE
    for material in scene.materials:
        if material.class_name == "lambertian":
            material.class_name, material.address = class_name, address
    return scene


def samples_per_second(
    client: Client, scene: scene_pb2.Scene, tile: int = TILE, per_pass: int = SAMPLES_PER_PASS
) -> float:
    """Best of three renders (the first also warms connections and caches)."""
    best = 0.0
    integrator = component("mean_sample", tile_size=tile, samples_per_pass=per_pass)
    for seed in (1, 2, 3):
        job_id = client.submit(scene, SPP, seed, integrator=integrator, name="bench")
        status = client.wait(job_id, timeout=1200)
        if status.state != render_pb2.SUCCEEDED:
            raise RuntimeError(status.error)
        best = max(best, SIZE * SIZE * SPP / status.elapsed_seconds)
    return best


def main() -> None:
    results: dict[str, float] = {}
    with (
        tempfile.TemporaryDirectory() as folder,
        LocalServer() as server,
        server.client() as client,
    ):
        results[DEFAULT] = samples_per_second(client, scene_with("lambertian", ""), 32, 1)
        results[SAME] = samples_per_second(client, scene_with("lambertian", ""))
        with ComponentProcess.python(
            [f"{PYTHON_LAMBERTIAN}:Lambertian"], f"unix:{folder}/py.sock"
        ) as python:
            results["Python, unix socket"] = samples_per_second(
                client, scene_with("py_lambertian", python.address)
            )
        with ComponentProcess.python([f"{PYTHON_LAMBERTIAN}:Lambertian"], "127.0.0.1:0") as python:
            results["Python, TCP loopback"] = samples_per_second(
                client, scene_with("py_lambertian", python.address)
            )
        if GO_LAMBERTIAN.exists():
            with ComponentProcess([str(GO_LAMBERTIAN)], f"unix:{folder}/go.sock") as go:
                results["Go, unix socket"] = samples_per_second(
                    client, scene_with("go_lambertian", go.address)
                )
    print(
        f"remote BSDF in the path tracer: Cornell box {SIZE}², {SPP} spp, batches of {TILE}² "
        f"pixels × {SAMPLES_PER_PASS} samples"
    )
    print(f"  {'':32s} {'M samples/s':>11s}  {'/ same batches':>14s}  {'/ default':>9s}")
    for name, rate in results.items():
        print(
            f"  {name:32s} {rate / 1e6:11.3f}  {rate / results[SAME]:14.2f}  "
            f"{rate / results[DEFAULT]:9.2f}"
        )
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    ratios = {
        "same batches": {name: rate / results[SAME] for name, rate in results.items()},
        "default batches": {name: rate / results[DEFAULT] for name, rate in results.items()},
    }
    (out / "remote_components.json").write_text(
        json.dumps({"samples_per_second": results, "ratio_to_in_process": ratios}, indent=2)
    )


if __name__ == "__main__":
    main()
