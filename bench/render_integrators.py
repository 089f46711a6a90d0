"""Rendering with different integrators: RMSE against a high-spp reference
at equal samples per pixel and at equal time, on the Cornell box and on a
variant with a small, bright light (where importance matters). Results also
go to out/bench/render_integrators.json.
"""

from __future__ import annotations

import copy
import json
import os
from pathlib import Path

import numpy as np

from yarf import Client, LocalServer, load_scene
from yarf.v1 import scene_pb2

ROOT = Path(__file__).resolve().parent.parent
SIZE = 128
REFERENCE_SPP = int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "1024"))
EQUAL_SPP = 32
METHODS = {
    "mean_sample (MC)": ("mean_sample", "independent"),
    "mean_sample (QMC)": ("mean_sample", "sobol"),
    "vegas": ("vegas", "independent"),
    "vegas_plus": ("vegas_plus", "independent"),
}


def scenes() -> dict[str, scene_pb2.Scene]:
    box = load_scene(ROOT / "scenes" / "cornell-box" / "scene.json")
    box.film.width = box.film.height = SIZE
    small = copy.deepcopy(box)
    # The luminaire shrunk 5× about its centre, 25× brighter: the same power.
    light = next(s for s in small.shapes if s.name == "luminaire")
    cx, cz, scale = 278.0, 279.5, 0.2
    light.to_world.m[:] = [
        scale,
        0,
        0,
        cx * (1 - scale),
        0,
        1,
        0,
        -0.5,
        0,
        0,
        scale,
        cz * (1 - scale),
        0,
        0,
        0,
        1,
    ]
    radiance = light.emitter.properties.values["radiance"].rgb_value
    radiance.r, radiance.g, radiance.b = radiance.r * 25, radiance.g * 25, radiance.b * 25
    return {"cornell box": box, "small light": small}


def render(
    client: Client, scene: scene_pb2.Scene, method: str, spp: int, seed: int
) -> tuple[np.ndarray, float]:
    integrator, sampler = METHODS[method]
    job = client.submit(
        scene,
        spp=spp,
        seed=seed,
        integrator=scene_pb2.ComponentSpec(class_name=integrator),
        sampler=scene_pb2.ComponentSpec(class_name=sampler),
    )
    status = client.wait(job)
    return client.image(job).astype(np.float64), status.elapsed_seconds


def rmse(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((image - reference) ** 2)))


def main() -> None:
    report: dict[str, dict[str, dict[str, float]]] = {}
    with LocalServer() as server:
        client = server.client()
        for name, scene in scenes().items():
            reference, _ = render(client, scene, "mean_sample (QMC)", REFERENCE_SPP, 1234)
            rows: dict[str, dict[str, float]] = {}
            for method in METHODS:
                image, seconds = render(client, scene, method, EQUAL_SPP, 1)
                rows[method] = {"equal_spp_rmse": rmse(image, reference), "seconds": seconds}
            budget = rows["mean_sample (MC)"]["seconds"]
            for method, row in rows.items():
                spp = max(1, round(EQUAL_SPP * budget / row["seconds"]))
                image, _ = render(client, scene, method, spp, 2)
                row["equal_time_spp"] = spp
                row["equal_time_rmse"] = rmse(image, reference)
            report[name] = rows
    print(f"RMSE against mean_sample+sobol at {REFERENCE_SPP} spp, {SIZE}x{SIZE}")
    print(
        f"{'scene':<13}{'method':<20}{f'rmse@{EQUAL_SPP}spp':>14}"
        f"{'equal-time spp':>16}{'rmse@time':>12}"
    )
    for name, rows in report.items():
        for method, row in rows.items():
            print(
                f"{name:<13}{method:<20}{row['equal_spp_rmse']:>14.5f}{row['equal_time_spp']:>16}{row['equal_time_rmse']:>12.5f}"
            )
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "render_integrators.json").write_text(json.dumps(report, indent=2))
    print("report " + json.dumps(report))


if __name__ == "__main__":
    main()
