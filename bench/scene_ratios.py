"""yarf's path tracer against Mitsuba 3 and Embree beyond the Cornell box:
the Veach MIS scene, a mesh of about a million triangles, Mitsuba's own
Cornell box file (its default Gaussian filter, spectra read as RGB) and a
scene of bitmap textures (bilinear, Mitsuba's default).

Both renderers read one Mitsuba file per scene. For each, the three ratios
bench/cornell_box.py gives for the Cornell box, measured in this run:

- samples/s vs Mitsuba llvm_ad_rgb. yarf's rate is its marginal one, the
  samples of a render at 4·S spp less those of one at S over the seconds
  between them: Mitsuba's timing leaves out loading and building the
  scene (a second or two for a million triangles), so yarf's does too;
- rays/s vs Embree's ceiling for yarf's own mix of closest-hit and shadow
  rays on the same scene (bench/embree_ceiling), marginal likewise;
- RMSE at equal time vs Mitsuba llvm's, against the mean of both
  renderers at high spp (neither is judged against its own bias).

Results go to out/bench/scene_ratios.json.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from aggregates import bumpy_sphere_ply
from bench_report import cpu_model
from cornell_box import EQUAL_TIME_SEEDS, mean_rmse, mitsuba_render, spp_for
from google.protobuf import json_format
from lights import mitsuba_scene, write_pfm, yarf_render

from yarf.assets import upload_scene_assets
from yarf.client import Client
from yarf.scene import load_scene
from yarf.server import LocalServer
from yarf.v1 import scene_pb2

ROOT = Path(__file__).resolve().parent.parent
VEACH = ROOT / "scenes" / "veach-mis" / "scene.xml"
MITSUBA_CBOX = ROOT.parent / "shared" / "scenes" / "mitsuba-cbox" / "cbox.xml"
CEILING = ROOT / "build" / "bin" / "embree_ceiling"
# The samples per pixel S of the lower throughput render (the higher has
# 4·S), per scene: enough that building the scene (seconds for a million
# triangles, and never quite the same) is small beside rendering 3·S.
THROUGHPUT_SPP = int(os.environ.get("YARF_BENCH_SPP", "16"))
MILLION_TRIANGLES_SPP = 4 * THROUGHPUT_SPP
REFERENCE_SPP = int(os.environ.get("YARF_BENCH_REFERENCE_SPP", "1024"))
EQUAL_TIME_SECONDS = float(os.environ.get("YARF_BENCH_SECONDS", "2.0"))
# 2 · rings · segments triangles.
RINGS, SEGMENTS = 500, 1000


def million_triangles(folder: Path) -> Path:
    """A bumpy sphere of 10^6 triangles on a floor under a square light."""
    bumpy_sphere_ply(folder / "bumpy.ply", RINGS, SEGMENTS)
    path = folder / "scene.xml"
    path.write_text(
        mitsuba_scene(
            "0, 1.2, -4",
            256,
            256,
            """  <shape type="ply"><string name="filename" value="bumpy.ply"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/>
    <translate y="-1.05"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.7"/><rotate x="1" angle="90"/>
    <translate y="2.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="12, 12, 12"/></emitter></shape>
""",
        )
    )
    return path


def textured(folder: Path) -> Path:
    """A floor, a wall and a sphere under a square light, each diffuse with
    a bilinear bitmap texture of coloured checks and ramps."""
    rows, columns = np.mgrid[0:512, 0:512]
    checks = (rows // 32 + columns // 32) % 2
    image = np.stack([0.2 + 0.6 * checks, 0.3 + 0.4 * columns / 512, 0.3 + 0.4 * rows / 512], -1)
    write_pfm(folder / "checks.pfm", image.astype(np.float32))
    bsdf = """<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
      <string name="filename" value="checks.pfm"/></texture></bsdf>"""
    path = folder / "textured.xml"
    path.write_text(
        mitsuba_scene(
            "0, 1, 5",
            256,
            256,
            f"""  <shape type="rectangle"><transform name="to_world"><scale value="3"/>
    <rotate x="1" angle="-90"/><translate y="-1"/></transform>{bsdf}</shape>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-2"/>
    </transform>{bsdf}</shape>
  <shape type="sphere"><point name="center" x="0" y="0" z="0"/><float name="radius" value="0.9"/>
    {bsdf}</shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.7"/><rotate x="1" angle="90"/>
    <translate y="2.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="12, 12, 12"/></emitter></shape>
""",
        )
    )
    return path


def embree_ceiling(scene: scene_pb2.Scene) -> dict[str, dict[str, float]]:
    """Embree's rates on the scene as loaded (meshes inline, as load_scene reads them)."""
    # Only the shapes matter to Embree: textures, whose files stay in the
    # scene's folder, become constants.
    shapes = scene_pb2.Scene()
    shapes.CopyFrom(scene)
    for texture in shapes.textures:
        texture.texture.Clear()
        texture.texture.class_name = "constant_texture"
    with tempfile.TemporaryDirectory() as temporary:
        path = Path(temporary) / "scene.json"
        path.write_text(json_format.MessageToJson(shapes))
        result = subprocess.run(
            [str(CEILING), str(path)], capture_output=True, text=True, check=False
        )
    if result.returncode != 0:
        sys.exit(f"embree_ceiling failed:\n{result.stderr[-2000:]}")
    return json.loads(result.stdout)


def ratios(client: Client, path: Path, spp: int) -> dict[str, object]:
    """The three ratios for the Mitsuba file `path`, throughput measured
    from renders at `spp` and 4·`spp`."""
    scene = load_scene(path)
    ceiling = embree_ceiling(scene)
    upload_scene_assets(client, scene, path.parent)
    pixels = scene.film.width * scene.film.height

    yarf_render(client, scene, 1, 99)  # warm-up: plugins, caches
    _, _, low = yarf_render(client, scene, spp, 1)
    _, _, high = yarf_render(client, scene, 4 * spp, 2)
    seconds = high["seconds"] - low["seconds"]
    samples_per_second = 3 * spp * pixels / seconds
    closest = high["closest_hit_rays"] - low["closest_hit_rays"]
    shadow = high["shadow_rays"] - low["shadow_rays"]
    c_best, s_best = ceiling["closest"]["best"], ceiling["shadow"]["best"]
    ceiling_rate = (closest + shadow) / (closest / c_best + shadow / s_best)
    yarf_rate = (closest + shadow) / seconds
    _, mitsuba = mitsuba_render("llvm_ad_rgb", 4 * spp, 1, path)

    yarf_reference, _, _ = yarf_render(client, scene, REFERENCE_SPP, 12345)
    mitsuba_reference, _ = mitsuba_render("llvm_ad_rgb", REFERENCE_SPP, 12345, path)
    reference = 0.5 * (yarf_reference.astype(np.float64) + mitsuba_reference)
    y_spp = spp_for(EQUAL_TIME_SECONDS, samples_per_second, pixels)
    m_spp = spp_for(EQUAL_TIME_SECONDS, mitsuba["samples_per_second"], pixels)
    y_runs = [yarf_render(client, scene, y_spp, seed)[0] for seed in EQUAL_TIME_SEEDS]
    m_runs = [mitsuba_render("llvm_ad_rgb", m_spp, seed, path)[0] for seed in EQUAL_TIME_SEEDS]
    y_rmse, m_rmse = mean_rmse(y_runs, reference), mean_rmse(m_runs, reference)
    return {
        "yarf_samples_per_second": samples_per_second,
        "mitsuba_llvm_samples_per_second": mitsuba["samples_per_second"],
        "yarf_rays_per_second": yarf_rate,
        "embree_ceiling_rays_per_second": ceiling_rate,
        "embree_build_seconds": ceiling["build_seconds"],
        "equal_time": {
            "budget_seconds": EQUAL_TIME_SECONDS,
            "yarf_spp": y_spp,
            "mitsuba_spp": m_spp,
        },
        "samples_vs_mitsuba_llvm": samples_per_second / mitsuba["samples_per_second"],
        "rays_vs_embree_ceiling": yarf_rate / ceiling_rate,
        "equal_time_rmse_vs_mitsuba_llvm": y_rmse / m_rmse,
    }


def main() -> None:
    report: dict[str, object] = {"cpu_model": cpu_model()}
    with (
        LocalServer() as server,
        server.client() as client,
        tempfile.TemporaryDirectory() as folder,
    ):
        report["veach_mis"] = ratios(client, VEACH, THROUGHPUT_SPP)
        report["million_triangles"] = ratios(
            client, million_triangles(Path(folder)), MILLION_TRIANGLES_SPP
        )
        report["mitsuba_cbox"] = ratios(client, MITSUBA_CBOX, THROUGHPUT_SPP)
        report["textured"] = ratios(client, textured(Path(folder)), THROUGHPUT_SPP)
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "scene_ratios.json").write_text(json.dumps(report, indent=2))
    print(f"cpu: {report['cpu_model']}")
    header = ("scene", "samples/s", "vs mitsuba", "rays vs embree", "equal-time rmse")
    print(f"{header[0]:<20}{header[1]:>12}{header[2]:>12}{header[3]:>16}{header[4]:>17}")
    for name in ("veach_mis", "million_triangles", "mitsuba_cbox", "textured"):
        row = report[name]
        assert isinstance(row, dict)
        print(
            f"{name:<20}{row['yarf_samples_per_second'] / 1e6:>10.2f} M"
            f"{row['samples_vs_mitsuba_llvm']:>12.3f}"
            f"{row['rays_vs_embree_ceiling']:>16.3f}{row['equal_time_rmse_vs_mitsuba_llvm']:>17.3f}"
        )
    print(f"written {out / 'scene_ratios.json'}")


if __name__ == "__main__":
    main()
