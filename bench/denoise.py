"""The client's denoiser at equal time: is a denoised 16-spp image closer to the
converged one than an undenoised image given the same time?

For the Cornell box and Veach's MIS scene: a long reference render, then
the 16-spp render with the albedo and sh_normal AOVs denoised by Intel
Open Image Denoise (its whole time counted: submit, render, AOVs, fetch,
denoise), then an undenoised render of as many samples as fit in that time.
Each is compared with the reference by its RMSE, of the radiance and of
display values (clamped at 1, where the lights' own pixels weigh no more
than a white wall's). Printed with the CPU's model; results also go to
out/bench/denoise.json.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

from yarf.client import Client
from yarf.denoise import DENOISE_AOVS, denoise
from yarf.scene import load_scene
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
SCENES = {
    "cornell-box": ROOT / "scenes" / "cornell-box" / "scene.json",
    "veach-mis": ROOT / "scenes" / "veach-mis" / "scene.json",
}
SIDE = int(os.environ.get("YARF_BENCH_DENOISE_SIDE", "256"))
REFERENCE_SPP = int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "1024"))
SPP = 16
SEED = 7


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def errors(image: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    image, reference = image.astype(np.float64), reference.astype(np.float64)
    display = np.minimum(image, 1.0) - np.minimum(reference, 1.0)
    return {
        "rmse": float(np.sqrt(np.mean((image - reference) ** 2))),
        "display_rmse": float(np.sqrt(np.mean(display**2))),
    }


def timed_render(
    client: Client, path: Path, spp: int, seed: int, aovs: tuple[str, ...] = ()
) -> tuple[np.ndarray, dict[str, np.ndarray], float]:
    started = time.perf_counter()
    result = client.render(load_scene(path), spp, seed, res=(SIDE, SIDE), aovs=aovs, timeout=3600)
    return result.pixels, result.aovs, time.perf_counter() - started


def bench_scene(client: Client, name: str, path: Path) -> dict[str, float]:
    reference, _, reference_seconds = timed_render(client, path, REFERENCE_SPP, 1)
    # The denoised image, every step of it timed.
    pixels, aovs, render_seconds = timed_render(client, path, SPP, SEED, DENOISE_AOVS)
    started = time.perf_counter()
    denoised = denoise(pixels, aovs)
    denoise_seconds = time.perf_counter() - started
    total = render_seconds + denoise_seconds
    # The undenoised image at equal time: the samples that fit in that time, from
    # the times of 16 and 64 spp without AOVs (a cost per sample pass and a fixed
    # cost of the job), then measured.
    _, _, short_seconds = timed_render(client, path, SPP, SEED)
    _, _, long_seconds = timed_render(client, path, 4 * SPP, SEED)
    per_spp = max(long_seconds - short_seconds, 1e-6) / (3 * SPP)
    fixed = max(short_seconds - SPP * per_spp, 0.0)
    equal_spp = max(SPP, round((total - fixed) / per_spp))
    equal, _, equal_seconds = timed_render(client, path, equal_spp, SEED)
    raw_16 = errors(pixels, reference)
    den = errors(denoised, reference)
    eq = errors(equal, reference)
    row = {
        "side": SIDE,
        "reference_spp": REFERENCE_SPP,
        "reference_seconds": reference_seconds,
        "denoised_seconds": total,
        "render_and_aovs_seconds": render_seconds,
        "denoise_seconds": denoise_seconds,
        "equal_time_spp": equal_spp,
        "equal_time_seconds": equal_seconds,
        **{f"raw_16spp_{k}": v for k, v in raw_16.items()},
        **{f"denoised_{k}": v for k, v in den.items()},
        **{f"equal_time_{k}": v for k, v in eq.items()},
    }
    print(
        f"{name}: {SIDE}x{SIDE}, reference {REFERENCE_SPP} spp ({reference_seconds:.1f} s)\n"
        f"  denoised 16 spp: {total:.2f} s (render + AOVs {render_seconds:.2f} s, "
        f"denoise {denoise_seconds:.2f} s)\n"
        f"  undenoised at equal time: {equal_spp} spp ({equal_seconds:.2f} s)\n"
        f"  RMSE         16 spp {raw_16['rmse']:.4f}  denoised {den['rmse']:.4f}  "
        f"equal time {eq['rmse']:.4f}  ratio equal-time/denoised "
        f"{eq['rmse'] / den['rmse']:.2f}\n"
        f"  display RMSE 16 spp {raw_16['display_rmse']:.4f}  denoised {den['display_rmse']:.4f}  "
        f"equal time {eq['display_rmse']:.4f}  ratio equal-time/denoised "
        f"{eq['display_rmse'] / den['display_rmse']:.2f}"
    )
    return row


def main() -> None:
    print(f"CPU: {cpu_model()}, {os.cpu_count()} threads")
    results: dict[str, object] = {"cpu": cpu_model(), "threads": os.cpu_count()}
    with LocalServer() as server, server.client(timeout=600) as client:
        for name, path in SCENES.items():
            results[name] = bench_scene(client, name, path)
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "denoise.json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
