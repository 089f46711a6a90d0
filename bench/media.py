"""Media benchmark: transports through participating media, and yarf's
volpath against Mitsuba 3's, in one run.

- A foggy Cornell box (Mitsuba's box, filled with a homogeneous medium
  bounded by a null cube; one Mitsuba file both renderers read): volpath's
  samples/s against Mitsuba 3 llvm_ad_rgb's volpath, and equal-time RMSE of
  yarf's volpath, bdpt, sppm and light tracer and of Mitsuba's volpath
  against a reference (the mean of long yarf and Mitsuba renders).
- Bitterli's volumetric caustic (a small light focused by a glass sphere
  into fog; pbrt-v4, which Mitsuba cannot render bidirectionally): the
  equal-time RMSE of the same yarf transports against a long bdpt
  reference (bdpt finds every path; the light tracer cannot see the glass
  sphere, whose camera vertex is specular), and PNGs of the equal-time
  images in out/bench.

A transport that refuses media is reported as such. Ratios are of figures
measured in this run on this machine (its CPU is printed). Results also go
to out/bench/media.json.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_report import cpu_model
from cornell_box import EQUAL_TIME_SEEDS, mean_rmse, mitsuba_render, rmse, spp_for

from yarf.client import Client
from yarf.scene import load_scene
from yarf.server import LocalServer
from yarf.v1 import scene_pb2

ROOT = Path(__file__).resolve().parent.parent
CBOX = ROOT.parent / "shared" / "scenes" / "mitsuba-cbox"
CAUSTIC = ROOT.parent / "shared" / "scenes" / "bitterli" / "volumetric-caustic" / "scene-v4.pbrt"
OUT = ROOT / "out" / "bench"
EQUAL_TIME_SECONDS = float(os.environ.get("YARF_BENCH_MEDIA_SECONDS", "6.0"))
REFERENCE_SECONDS = float(os.environ.get("YARF_BENCH_MEDIA_REFERENCE_SECONDS", "90.0"))
TRANSPORTS = ("volpath", "bdpt", "sppm", "light")

FOG = """
  <shape type="cube">
    <transform name="to_world"><scale x="282" y="280" z="332"/>
      <translate x="278" y="274" z="230"/></transform>
    <bsdf type="null"/>
    <medium type="homogeneous" name="interior">
      <float name="sigma_t" value="0.0025"/><rgb name="albedo" value="0.85, 0.8, 0.7"/>
      <phase type="hg"><float name="g" value="0.3"/></phase>
    </medium>
  </shape>
"""


def foggy_cornell_box(folder: Path) -> Path:
    """Mitsuba's Cornell box at 128² rendered by volpath, filled with fog."""
    box = folder / "cbox"
    shutil.copytree(CBOX, box)
    base = box / "fragments" / "base.xml"
    text = base.read_text().replace('type="path"', 'type="volpath"')
    base.write_text(text.replace('name="res" value="256"', 'name="res" value="128"'))
    scene = box / "foggy.xml"
    scene.write_text((box / "cbox-rgb.xml").read_text().replace("</scene>", FOG + "</scene>"))
    return scene


def render(
    client: Client, scene: scene_pb2.Scene, transport: str, spp: int, seed: int
) -> tuple[np.ndarray | None, dict[str, object]]:
    """yarf's image (None when the transport refuses the scene) and its timing."""
    job = client.submit(
        scene, spp=spp, seed=seed, transport=scene_pb2.ComponentSpec(class_name=transport)
    )
    status = client.wait(job)
    if status.error:
        return None, {"refused": status.error}
    pixels = scene.film.width * scene.film.height
    stats = {
        "spp": spp,
        "seconds": status.elapsed_seconds,
        "samples_per_second": pixels * spp / status.elapsed_seconds,
        "job": job,
    }
    return client.image(job), stats


def equal_time(
    client: Client, scene: scene_pb2.Scene, reference: np.ndarray, png_prefix: str | None
) -> dict[str, dict[str, object]]:
    """Each transport's RMSE against `reference` after EQUAL_TIME_SECONDS."""
    pixels = scene.film.width * scene.film.height
    report: dict[str, dict[str, object]] = {}
    for transport in TRANSPORTS:
        image, probe = render(client, scene, transport, 4, 99)
        if image is None:
            report[transport] = probe
            continue
        spp = spp_for(EQUAL_TIME_SECONDS, float(probe["samples_per_second"]), pixels)
        runs = [render(client, scene, transport, spp, seed) for seed in EQUAL_TIME_SEEDS]
        report[transport] = {
            "equal_time_spp": spp,
            "samples_per_second": probe["samples_per_second"],
            "equal_time_rmse": mean_rmse([run[0] for run in runs if run[0] is not None], reference),
        }
        if png_prefix:
            client.fetch(str(runs[0][1]["job"]), OUT / f"{png_prefix}_{transport}.png")
    return report


def reference_render(client: Client, scene: scene_pb2.Scene, transport: str) -> np.ndarray:
    """`transport`'s image after about REFERENCE_SECONDS."""
    image, probe = render(client, scene, transport, 4, 12344)
    if image is None:
        sys.exit(f"the reference transport {transport} refused the scene: {probe['refused']}")
    pixels = scene.film.width * scene.film.height
    spp = spp_for(REFERENCE_SECONDS, float(probe["samples_per_second"]), pixels)
    image, _ = render(client, scene, transport, spp, 12345)
    assert image is not None
    return image.astype(np.float64)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    report: dict[str, object] = {"cpu": cpu_model(), "equal_time_seconds": EQUAL_TIME_SECONDS}
    with LocalServer() as server, tempfile.TemporaryDirectory() as folder:
        client = server.client()

        path = foggy_cornell_box(Path(folder))
        scene = load_scene(path)
        pixels = scene.film.width * scene.film.height
        _, yarf = render(client, scene, "volpath", 64, 1)
        _, mitsuba = mitsuba_render("llvm_ad_rgb", 64, 1, path)
        yarf_reference = reference_render(client, scene, "volpath")
        m_reference_spp = spp_for(REFERENCE_SECONDS / 2, mitsuba["samples_per_second"], pixels)
        mitsuba_reference, _ = mitsuba_render("llvm_ad_rgb", m_reference_spp, 12345, path)
        reference = 0.5 * (yarf_reference + mitsuba_reference)
        fog = equal_time(client, scene, reference, None)
        m_spp = spp_for(EQUAL_TIME_SECONDS, mitsuba["samples_per_second"], pixels)
        m_runs = [mitsuba_render("llvm_ad_rgb", m_spp, seed, path)[0] for seed in EQUAL_TIME_SEEDS]
        m_rmse = mean_rmse(m_runs, reference)
        fog["mitsuba_llvm_ad_rgb volpath"] = {
            "equal_time_spp": m_spp,
            "samples_per_second": mitsuba["samples_per_second"],
            "equal_time_rmse": m_rmse,
        }
        report["foggy_cornell_box"] = {
            "transports": fog,
            "volpath_samples_per_second_vs_mitsuba_llvm": float(yarf["samples_per_second"])
            / mitsuba["samples_per_second"],
            "yarf_reference_vs_mitsuba_reference_rmse": rmse(yarf_reference, mitsuba_reference),
        }

        caustic = load_scene(CAUSTIC)
        caustic.film.width = caustic.film.height = 128
        report["volumetric_caustic"] = {
            "transports": equal_time(
                client, caustic, reference_render(client, caustic, "bdpt"), "volumetric_caustic"
            ),
            "reference": f"bdpt, about {REFERENCE_SECONDS:.0f} s",
        }

    (OUT / "media.json").write_text(json.dumps(report, indent=2))
    print(f"media benchmark on {report['cpu']}")
    fog_report = report["foggy_cornell_box"]
    print(
        "foggy Cornell box: volpath samples/s yarf/mitsuba llvm "
        f"{fog_report['volpath_samples_per_second_vs_mitsuba_llvm']:.3f}"  # type: ignore[index]
    )
    for scene_name in ("foggy_cornell_box", "volumetric_caustic"):
        entries = report[scene_name]["transports"]  # type: ignore[index]
        base = entries["volpath"].get("equal_time_rmse")
        for name, entry in entries.items():
            if "refused" in entry:
                print(f"  {scene_name} {name}: refused ({entry['refused']})")
                continue
            ratio = f" ({entry['equal_time_rmse'] / base:.3f}x volpath's)" if base else ""
            print(
                f"  {scene_name} {name}: equal-time ({EQUAL_TIME_SECONDS:.0f} s) RMSE "
                f"{entry['equal_time_rmse']:.5f}{ratio}, {entry['equal_time_spp']} spp"
            )
    print(f"written {OUT / 'media.json'} and {OUT}/volumetric_caustic_*.png")


if __name__ == "__main__":
    main()
