"""Light transport methods at equal time: the unbiased path, light and
bdpt, and photon mapping, stochastic progressive photon mapping,
irradiance caching and radiosity.

For the glossy Cornell box (caustics under a glass sphere), the diffuse
Cornell box, the Veach-style MIS scene (small lights on sharp plates) and,
from ../shared, Bitterli's veach-bidir (a lamp facing the wall) and water
caustic,
each method renders at 1, 2, 4... spp until it has spent TIME_LIMIT
seconds (a method that refuses a scene, e.g. radiosity with non-diffuse
materials, is left out of it); its RMSE against a high-spp reference (the mean of a path-traced
and a bidirectional render) is interpolated, log-log, at equal time, and
reported as a ratio to the path tracer's measured in the same run, over
the whole image and over its hardest pixels: the 5% where the path
tracer's own variance is largest (the caustic, the small lights'
reflections).
On the two Bitterli scenes the default reference (4096 + 1024 spp at 64
px) is itself too noisy to rank the methods: their errors come out nearly
equal; set YARF_BENCH_REFERENCE_SPP far higher for figures worth quoting.
Convergence curves go to out/bench/light_transport.png, beside the
images each method reached (out/bench/light_transport/*.exr), and the
numbers to out/bench/light_transport.json.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from bench_report import cpu_model

from yarf import Client, LocalServer, component, load_scene
from yarf.v1 import render_pb2, scene_pb2

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "out" / "bench"
SIZE = 64
MAX_DEPTH = 6
METHODS = ("path", "light", "bdpt", "photon_map", "sppm", "irradiance_cache", "radiosity")
# Radiosity has no paths to bound.
WITHOUT_DEPTH = {"radiosity"}
BITTERLI = ROOT.parent / "shared" / "scenes" / "bitterli"
SCENES = {
    "glossy box (caustics)": ROOT / "scenes" / "cornell-box" / "glossy.json",
    "cornell box (diffuse)": ROOT / "scenes" / "cornell-box" / "scene.json",
    "veach mis (small lights)": ROOT / "scenes" / "veach-mis" / "scene.json",
    # Bitterli's: a room lit by a lamp facing the wall (light reaches the
    # camera's view only after bounces), and light through a water surface.
    "veach bidir (lamp)": BITTERLI / "veach-bidir" / "scene-v4.pbrt",
    "water caustic": BITTERLI / "water-caustic" / "scene-v4.pbrt",
}
REFERENCE_SPP = {
    "path": int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "4096")),
    "bdpt": int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "4096")) // 4,
}
TIME_LIMIT = float(os.environ.get("YARF_BENCH_SECONDS", "4"))
EQUAL_TIME = TIME_LIMIT / 2


def small(path: Path) -> scene_pb2.Scene:
    scene = load_scene(path)
    scene.film.height = scene.film.height * SIZE // scene.film.width
    scene.film.width = SIZE
    return scene


class Refused(RuntimeError):
    """A method that failed on a scene."""


def render(
    client: Client, scene: scene_pb2.Scene, method: str, spp: int, seed: int
) -> tuple[np.ndarray, float, str]:
    """The image, the render's own seconds and its job id."""
    spec = component(method) if method in WITHOUT_DEPTH else component(method, max_depth=MAX_DEPTH)
    job = client.submit(scene, spp=spp, seed=seed, transport=spec)
    status = client.wait(job)
    if status.state != render_pb2.SUCCEEDED:
        raise Refused(f"{method} failed: {status.error}")
    return client.image(job).astype(np.float64), status.elapsed_seconds, job


def rmse(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((image - reference) ** 2)))


def at_time(curve: list[tuple[float, float]], seconds: float) -> float:
    """RMSE at `seconds`, interpolated on log-log axes."""
    times = np.log([t for t, _ in curve])
    errors = np.log([e for _, e in curve])
    return float(np.exp(np.interp(np.log(seconds), times, errors)))


def main() -> None:
    images = OUT / "light_transport"
    images.mkdir(parents=True, exist_ok=True)
    report: dict[str, dict[str, dict[str, object]]] = {}
    with LocalServer() as server, server.client() as client:
        for name, path in SCENES.items():
            scene = small(path)
            references = [render(client, scene, m, spp, 99) for m, spp in REFERENCE_SPP.items()]
            reference = np.mean([image for image, _, _ in references], axis=0)
            path_variance = client.variance(references[0][2]).sum(axis=2)
            hard = path_variance >= np.quantile(path_variance, 0.95)
            rows: dict[str, dict[str, object]] = {}
            for method in METHODS:
                curve: list[tuple[float, float]] = []
                hard_curve: list[tuple[float, float]] = []
                spp, spent, job = 1, 0.0, ""
                try:
                    while spent < TIME_LIMIT:
                        image, seconds, job = render(client, scene, method, spp, spp)
                        curve.append((max(seconds, 1e-3), rmse(image, reference)))
                        hard_curve.append((max(seconds, 1e-3), rmse(image[hard], reference[hard])))
                        spent, spp = seconds, spp * 2
                except Refused as refused:
                    print(f"{name}: {refused}")
                    continue
                slug = name.split(" (")[0].replace(" ", "-")
                (images / f"{slug}-{method}.exr").write_bytes(
                    client.encoded(job, render_pb2.GetResultRequest.EXR)
                )
                rows[method] = {
                    "curve": curve,
                    "equal_time_rmse": at_time(curve, EQUAL_TIME),
                    "hard_pixels_rmse": at_time(hard_curve, EQUAL_TIME),
                }
            for key in ("equal_time_rmse", "hard_pixels_rmse"):
                baseline = float(rows["path"][key])
                for row in rows.values():
                    row[key + "_vs_path"] = float(row[key]) / baseline
            report[name] = rows

    print(f"cpu: {cpu_model()}")
    print(f"RMSE at {EQUAL_TIME:.1f} s against a high-spp reference, {SIZE} px wide")
    print(f"{'scene':<26}{'method':<18}{'rmse':>10}{'vs path':>9}{'hard 5%':>10}{'vs path':>9}")
    for name, rows in report.items():
        for method, row in rows.items():
            print(
                f"{name:<26}{method:<18}{row['equal_time_rmse']:>10.5f}"
                f"{row['equal_time_rmse_vs_path']:>9.2f}{row['hard_pixels_rmse']:>10.5f}"
                f"{row['hard_pixels_rmse_vs_path']:>9.2f}"
            )
    figure, axes = plt.subplots(1, len(report), figsize=(5 * len(report), 4))
    for axis, (name, rows) in zip(axes, report.items(), strict=True):
        for method, row in rows.items():
            times, errors = zip(*row["curve"], strict=True)
            axis.loglog(times, errors, marker="o", label=method)
        axis.set_title(name)
        axis.set_xlabel("seconds")
        axis.set_ylabel("RMSE")
        axis.grid(True, which="both", alpha=0.3)
        axis.legend()
    figure.tight_layout()
    figure.savefig(OUT / "light_transport.png", dpi=100)
    (OUT / "light_transport.json").write_text(json.dumps(report, indent=2))
    print(f"curves: {OUT / 'light_transport.png'}; images: {images}")


if __name__ == "__main__":
    main()
