"""Light transport methods at equal time: the unbiased path, light and
bdpt, and photon mapping, stochastic progressive photon mapping,
irradiance caching and radiosity.

For the glossy Cornell box (caustics under a glass sphere), the diffuse
Cornell box, the Veach-style MIS scene (small lights on sharp plates)
and, from ../shared, Bitterli's veach-bidir (a lamp facing the wall) and
water caustic, each method renders at 1, 2, 4... spp until it has spent
TIME_LIMIT seconds (a method that refuses a scene, e.g. radiosity with
non-diffuse materials, is left out of it); its RMSE against a long
reference is read at equal time off a line fitted log-log (at_time), and
reported as a ratio to the path tracer's measured in the same run, over
three sets of pixels: the whole image; its hardest pixels, the 5% where
the path tracer's own variance is largest (the caustic, the small
lights' reflections); and the image off its lamps, without the pixels
that see a lamp directly or in a mirror (above LAMP_LEVEL in the
reference, or lit at all in a render of the scene whose materials, but
those that only reflect and refract through delta lobes, are made
black: lamps_only). A lamp much smaller than a pixel, as the water
caustic's, or its glint in a glass, as veach-bidir's bulb in the egg on
the table, is seen by camera paths only when one happens to hit it (no
other strategy samples a lamp seen through delta surfaces): its few
pixels' error, the same for every method that starts at the camera,
would hide the rest of the image's.
Each scene's reference is rendered by the methods that converge fastest
there, far longer than any method's run: on the boxes and the MIS scene
the mean of a path-traced and a bidirectional render; on veach-bidir,
whose room is lit through the wall, bidirectional alone (the path
tracer's noise there would dominate a mean); on the water caustic, whose
floor is seen and lit through the water (specular-diffuse-specular
paths, which neither path nor bidirectional tracing samples well), SPPM,
which converges to the same integral as its passes grow.
The reference is rendered as two independent halves: their difference
measures its own noise, which is taken off each method's squared error
(rmse_beyond_reference). YARF_BENCH_REFERENCE_SCALE multiplies every
reference's samples (1: about six minutes in all on two cores here). Photon mapping and SPPM
shoot photons from their own seed, set to each render's: a render shares
no photon map with the reference.
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
# Photons come from the transport's own seed, not the job's.
OWN_SEED = {"photon_map", "sppm"}
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
REFERENCE_SCALE = float(os.environ.get("YARF_BENCH_REFERENCE_SCALE", "1"))
UNBIASED_REFERENCE = {"path": 4096, "bdpt": 1024}
# Materials that scatter through delta lobes alone (null: a boundary): a
# lamp seen through them is seen as in a mirror.
DELTA_MATERIALS = {"conductor", "dielectric", "mirror", "thindielectric", "null"}
LAMPS_ONLY_SPP = 16384
# A pixel above this (any channel) sees a lamp, directly or in a mirror:
# light reflected off surfaces stays below 2 in these scenes.
LAMP_LEVEL = 10.0
REFERENCES: dict[str, dict[str, int]] = {
    "glossy box (caustics)": UNBIASED_REFERENCE,
    "cornell box (diffuse)": UNBIASED_REFERENCE,
    "veach mis (small lights)": UNBIASED_REFERENCE,
    "veach bidir (lamp)": {"bdpt": 8192},
    "water caustic": {"sppm": 2048},
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
    properties: dict[str, int] = {} if method in WITHOUT_DEPTH else {"max_depth": MAX_DEPTH}
    if method in OWN_SEED:
        properties["seed"] = seed  # photons independent of the reference's
    spec = component(method, **properties)
    job = client.submit(scene, spp=spp, seed=seed, transport=spec)
    status = client.wait(job)
    if status.state != render_pb2.SUCCEEDED:
        raise Refused(f"{method} failed: {status.error}")
    return client.image(job).astype(np.float64), status.elapsed_seconds, job


def lamps_only(scene: scene_pb2.Scene) -> scene_pb2.Scene:
    """`scene` with every material but the delta ones (DELTA_MATERIALS)
    black: its light reaches the camera from the lamps directly or through
    mirrors and glass alone, so its image is lit exactly where a pixel sees
    a lamp so."""
    lamps = scene_pb2.Scene()
    lamps.CopyFrom(scene)
    for material in lamps.materials:
        if material.class_name in DELTA_MATERIALS:
            continue
        material.class_name = "lambertian"
        material.properties.Clear()
        material.properties.values["reflectance"].rgb_value.SetInParent()
    return lamps


def reference_half(client: Client, scene: scene_pb2.Scene, name: str, seed: int) -> np.ndarray:
    """One of two independent halves of a scene's reference: the mean of
    its reference methods' renders, each at half its samples."""
    images = [
        render(client, scene, method, max(1, round(spp * REFERENCE_SCALE / 2)), seed)[0]
        for method, spp in REFERENCES[name].items()
    ]
    return np.mean(images, axis=0)


def reference_noise(first: np.ndarray, second: np.ndarray, region: np.ndarray) -> float:
    """The RMSE of the halves' mean from its expectation over `region`:
    E[(first − second)²] is twice a half's variance, four times the mean's."""
    return float(np.sqrt(np.mean((first[region] - second[region]) ** 2) / 4))


def rmse_beyond_reference(
    image: np.ndarray, reference: np.ndarray, noise: float, region: np.ndarray
) -> float:
    """The RMSE of `image` over `region` from the reference's expectation,
    given the reference's own noise there (reference_noise).

    The squared error against the reference is the image's own plus the
    reference's noise (independent renders); the noise is taken off, so
    that a reference with rare bright samples left (a caustic that only
    some paths find) does not put a floor under every method's error. At
    least a tenth of the measured squared error is kept.
    """
    measured = np.mean((image[region] - reference[region]) ** 2)
    return float(np.sqrt(max(measured - noise**2, 0.1 * measured)))


def at_time(curve: list[tuple[float, float]], seconds: float) -> float:
    """RMSE at `seconds`: the least-squares line on log-log axes through
    the renders from an eighth of `seconds` to four times it. One render's
    error swings with the rare bright samples of a method that finds some
    light only by chance; the line weighs the renders around `seconds`
    alike rather than trusting the two nearest."""
    near = [(t, e) for t, e in curve if seconds / 8 <= t <= 4 * seconds]
    if len(near) < 2:
        times, errors = np.log([t for t, _ in curve]), np.log([e for _, e in curve])
        return float(np.exp(np.interp(np.log(seconds), times, errors)))
    slope, intercept = np.polyfit(np.log([t for t, _ in near]), np.log([e for _, e in near]), 1)
    return float(np.exp(intercept + slope * np.log(seconds)))


def main() -> None:
    images = OUT / "light_transport"
    images.mkdir(parents=True, exist_ok=True)
    report: dict[str, dict[str, dict[str, object]]] = {}
    with LocalServer() as server, server.client() as client:
        for name, path in SCENES.items():
            scene = small(path)
            first, second = (reference_half(client, scene, name, seed) for seed in (99, 100))
            _, _, path_job = render(client, scene, "path", 256, 98)
            path_variance = client.variance(path_job).sum(axis=2)
            seen, _, _ = render(client, lamps_only(scene), "path", LAMPS_ONLY_SPP, 97)
            lamps = seen.max(axis=2) > 0
            for image in (first, second):
                lamps |= image.max(axis=2) > LAMP_LEVEL
            regions = {
                "equal_time_rmse": np.ones(path_variance.shape, dtype=bool),
                "hard_pixels_rmse": path_variance >= np.quantile(path_variance, 0.95),
                "off_lamps_rmse": ~lamps,
            }
            reference = 0.5 * (first + second)
            noise = {key: reference_noise(first, second, region) for key, region in regions.items()}
            rows: dict[str, dict[str, object]] = {}
            for method in METHODS:
                curves: dict[str, list[tuple[float, float]]] = {key: [] for key in regions}
                spp, spent, job = 1, 0.0, ""
                try:
                    while spent < TIME_LIMIT:
                        image, seconds, job = render(client, scene, method, spp, spp)
                        for key, region in regions.items():
                            error = rmse_beyond_reference(image, reference, noise[key], region)
                            curves[key].append((max(seconds, 1e-3), error))
                        spent, spp = seconds, spp * 2
                except Refused as refused:
                    print(f"{name}: {refused}")
                    continue
                slug = name.split(" (")[0].replace(" ", "-")
                (images / f"{slug}-{method}.exr").write_bytes(
                    client.encoded(job, render_pb2.GetResultRequest.EXR)
                )
                rows[method] = {
                    "curves": curves,
                    "lamp_pixels": int(lamps.sum()),
                    "reference_noise_rmse": noise["equal_time_rmse"],
                }
                for key, curve in curves.items():
                    rows[method][key] = at_time(curve, EQUAL_TIME)
            for key in regions:
                baseline = float(rows["path"][key])
                for row in rows.values():
                    row[key + "_vs_path"] = float(row[key]) / baseline
            report[name] = rows

    print(f"cpu: {cpu_model()}")
    print(f"RMSE at {EQUAL_TIME:.1f} s against a high-spp reference, {SIZE} px wide")
    print(f"{'scene':<26}{'method':<18}", end="")
    print("".join(f"{title:>10}{'vs path':>9}" for title in ("rmse", "hard 5%", "off lamps")))
    for name, rows in report.items():
        for method, row in rows.items():
            print(f"{name:<26}{method:<18}", end="")
            for key in ("equal_time_rmse", "hard_pixels_rmse", "off_lamps_rmse"):
                print(f"{row[key]:>10.5f}{row[key + '_vs_path']:>9.2f}", end="")
            print()
    figure, axes = plt.subplots(1, len(report), figsize=(5 * len(report), 4), squeeze=False)
    for axis, (name, rows) in zip(axes[0], report.items(), strict=True):
        for method, row in rows.items():
            times, errors = zip(*row["curves"]["equal_time_rmse"], strict=True)
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
