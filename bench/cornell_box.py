"""The Cornell box benchmark: yarf against Embree's ceiling and Mitsuba 3.

All figures come from this one run, on this machine, and are printed as
ratios against baselines measured here too:

- yarf's samples/s and rays/s (closest-hit and shadow rays apart);
- Embree's raw rate for a like mix of incoherent rays on the same
  triangles, the best of its single-ray, stream and 8/16-wide kernels;
- Mitsuba 3 (llvm_ad_rgb and scalar_rgb) samples/s on the same scene;
- RMSE against a high-spp reference at equal time, yarf vs Mitsuba.

Results also go to out/bench/cornell_box.json.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_report import cpu_model

from yarf.client import Client
from yarf.scene import load_scene
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "cornell-box" / "scene.json"
MITSUBA_SCENE = ROOT.parent / "shared" / "scenes" / "mitsuba-cbox" / "cbox-rgb.xml"
LLVM = Path("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")  # Debian package libllvm19
THROUGHPUT_SPP = int(os.environ.get("YARF_BENCH_SPP", "64"))
REFERENCE_SPP = int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "1024"))
EQUAL_TIME_SECONDS = float(os.environ.get("YARF_BENCH_SECONDS", "2.0"))
# Independent equal-time renders per renderer; their mean squared error is reported.
EQUAL_TIME_SEEDS = (7, 8, 9)
# Renders per thread count for the scaling ratio.
SCALING_RUNS = 3


def yarf_render(
    client: Client, spp: int, seed: int, scene_path: Path = SCENE, threads: int = 0
) -> tuple[np.ndarray, dict[str, float]]:
    scene = load_scene(scene_path)
    job = client.submit(scene, spp=spp, seed=seed, name=f"bench {spp} spp", threads=threads)
    status = client.wait(job)
    if status.error:
        sys.exit(f"yarf render failed: {status.error}")
    image = client.image(job)
    pixels = image.shape[0] * image.shape[1]
    seconds = status.elapsed_seconds
    stats = {
        "spp": spp,
        "seconds": seconds,
        "samples_per_second": pixels * spp / seconds,
        "closest_hit_rays_per_second": status.closest_hit_rays / seconds,
        "shadow_rays_per_second": status.shadow_rays / seconds,
        "closest_hit_rays": status.closest_hit_rays,
        "shadow_rays": status.shadow_rays,
    }
    return image, stats


def mitsuba_render(
    variant: str,
    spp: int,
    seed: int,
    scene_path: Path = MITSUBA_SCENE,
    max_depth: int | None = None,
) -> tuple[np.ndarray, dict[str, float]]:
    env = dict(os.environ)
    if variant.startswith("llvm"):
        env["DRJIT_LIBLLVM_PATH"] = str(LLVM)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "image.npy"
        command = [
            sys.executable,
            str(ROOT / "bench" / "mitsuba_render.py"),
            str(scene_path),
            "--variant",
            variant,
            "--spp",
            str(spp),
            "--seed",
            str(seed),
            "--out",
            str(out),
        ]
        if max_depth is not None:
            command += ["--max-depth", str(max_depth)]
        result = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
        if result.returncode != 0:
            sys.exit(f"mitsuba {variant} failed:\n{result.stderr[-2000:]}")
        return np.load(out), json.loads(result.stdout.strip().splitlines()[-1])


def embree_ceiling() -> dict[str, dict[str, float]]:
    binary = ROOT / "build" / "bin" / "embree_ceiling"
    result = subprocess.run([str(binary), str(SCENE)], capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def rmse(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((image.astype(np.float64) - reference) ** 2)))


def mean_rmse(images: list[np.ndarray], reference: np.ndarray) -> float:
    """The root of the mean squared error over several independent images."""
    return float(np.sqrt(np.mean([rmse(image, reference) ** 2 for image in images])))


def spp_for(seconds: float, samples_per_second: float, pixels: int) -> int:
    return max(1, round(seconds * samples_per_second / pixels))


def main() -> None:
    report: dict[str, object] = {"cpu_model": cpu_model()}
    with LocalServer() as server:
        client = server.client()
        yarf_render(client, 4, 99)  # warm-up: plugins, caches
        _, yarf = yarf_render(client, THROUGHPUT_SPP, 1)
        report["yarf"] = yarf

        # Scaling: the same render on one thread and on every thread, in
        # turn, SCALING_RUNS times; the medians, so that one slow run on a
        # shared machine does not decide the ratio.
        cores = os.cpu_count() or 1
        rates: dict[int, list[float]] = {1: [], cores: []}
        for _ in range(SCALING_RUNS):
            for threads in rates:
                _, run = yarf_render(client, THROUGHPUT_SPP, 1, threads=threads)
                rates[threads].append(run["samples_per_second"])
        report["threads"] = {
            "threads": cores,
            "runs": SCALING_RUNS,
            "one_thread_samples_per_second": statistics.median(rates[1]),
            "samples_per_second": statistics.median(rates[cores]),
        }

        ceiling = embree_ceiling()
        c_best, s_best = ceiling["closest"]["best"], ceiling["shadow"]["best"]
        # The ceiling for yarf's own mix of closest-hit and shadow rays.
        mix_seconds = yarf["closest_hit_rays"] / c_best + yarf["shadow_rays"] / s_best
        ceiling_rate = (yarf["closest_hit_rays"] + yarf["shadow_rays"]) / mix_seconds
        yarf_rate = (yarf["closest_hit_rays"] + yarf["shadow_rays"]) / yarf["seconds"]
        report["embree"] = {**ceiling, "mix_rays_per_second": ceiling_rate}

        mitsuba = {}
        for variant in ("llvm_ad_rgb", "scalar_rgb"):
            _, mitsuba[variant] = mitsuba_render(variant, THROUGHPUT_SPP, 1)
        report["mitsuba"] = mitsuba

        # Reference: the mean of both renderers at high spp, so neither is
        # judged against its own bias.
        yarf_ref, _ = yarf_render(client, REFERENCE_SPP, 12345)
        mitsuba_ref, _ = mitsuba_render("llvm_ad_rgb", REFERENCE_SPP, 12345)
        reference = 0.5 * (yarf_ref.astype(np.float64) + mitsuba_ref)
        pixels = reference.shape[0] * reference.shape[1]

        y_spp = spp_for(EQUAL_TIME_SECONDS, yarf["samples_per_second"], pixels)
        m_spp = spp_for(EQUAL_TIME_SECONDS, mitsuba["llvm_ad_rgb"]["samples_per_second"], pixels)
        y_runs = [yarf_render(client, y_spp, seed) for seed in EQUAL_TIME_SEEDS]
        m_runs = [mitsuba_render("llvm_ad_rgb", m_spp, seed) for seed in EQUAL_TIME_SEEDS]
        y16, _ = yarf_render(client, 16, 8)
        m16, _ = mitsuba_render("llvm_ad_rgb", 16, 8)
        report["equal_time"] = {
            "budget_seconds": EQUAL_TIME_SECONDS,
            "yarf": {
                "spp": y_spp,
                "seconds": float(np.mean([run["seconds"] for _, run in y_runs])),
                "rmse": mean_rmse([image for image, _ in y_runs], reference),
            },
            "mitsuba_llvm_ad_rgb": {
                "spp": m_spp,
                "seconds": float(np.mean([run["seconds"] for _, run in m_runs])),
                "rmse": mean_rmse([image for image, _ in m_runs], reference),
            },
        }
        report["equal_spp_16"] = {
            "yarf_rmse": rmse(y16, reference),
            "mitsuba_llvm_ad_rgb_rmse": rmse(m16, reference),
        }

    eq = report["equal_time"]
    ratios = {
        "rays_vs_embree_ceiling": yarf_rate / ceiling_rate,
        "samples_vs_mitsuba_llvm": yarf["samples_per_second"]
        / mitsuba["llvm_ad_rgb"]["samples_per_second"],
        "samples_vs_mitsuba_scalar": yarf["samples_per_second"]
        / mitsuba["scalar_rgb"]["samples_per_second"],
        "threads_speedup": report["threads"]["samples_per_second"]
        / report["threads"]["one_thread_samples_per_second"],
        "equal_time_rmse_vs_mitsuba_llvm": eq["yarf"]["rmse"] / eq["mitsuba_llvm_ad_rgb"]["rmse"],
        "equal_spp_rmse_vs_mitsuba_llvm": report["equal_spp_16"]["yarf_rmse"]
        / report["equal_spp_16"]["mitsuba_llvm_ad_rgb_rmse"],
    }
    report["ratios"] = ratios

    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "cornell_box.json").write_text(json.dumps(report, indent=2))
    print(f"cpu: {report['cpu_model']}")
    print(
        f"yarf: {yarf['samples_per_second'] / 1e6:.2f} M samples/s, "
        f"{yarf['closest_hit_rays_per_second'] / 1e6:.2f} M closest-hit rays/s, "
        f"{yarf['shadow_rays_per_second'] / 1e6:.2f} M shadow rays/s"
    )
    print(
        f"embree ceiling: {c_best / 1e6:.2f} M closest-hit rays/s, "
        f"{s_best / 1e6:.2f} M shadow rays/s, {ceiling_rate / 1e6:.2f} M rays/s for yarf's mix"
    )
    for variant, stats in mitsuba.items():
        print(f"mitsuba {variant}: {stats['samples_per_second'] / 1e6:.2f} M samples/s")
    y_eq, m_eq = eq["yarf"], eq["mitsuba_llvm_ad_rgb"]
    print(
        f"equal time ({EQUAL_TIME_SECONDS:.1f} s): yarf {y_eq['spp']} spp rmse {y_eq['rmse']:.5f}, "
        f"mitsuba llvm {m_eq['spp']} spp rmse {m_eq['rmse']:.5f}"
    )
    for name, value in ratios.items():
        print(f"ratio {name}: {value:.3f}")
    print(f"written {out / 'cornell_box.json'}")
    print("ratios " + json.dumps(ratios))


if __name__ == "__main__":
    main()
