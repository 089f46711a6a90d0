"""Lights benchmark: yarf's light sampling against Mitsuba 3, in one run.

- Equal-time RMSE against a high-spp reference, yarf's path tracer vs
  Mitsuba 3 llvm_ad_rgb, on the Veach MIS scene (scenes/veach-mis, its
  Mitsuba file) and on an environment-lit scene (a sphere and a floor
  under a 256×128 sky map with a sun), both renderers reading one file.
- The Veach MIS scene's per-pixel variance at equal spp with sphere lights
  sampled by solid angle against by area.
- A many-light scene (100 small sphere lights of unequal power over a
  floor) at equal spp: RMSE with lights chosen uniformly, by power, and by
  the light BVH (power, distance and orientation, as pbrt-v4's default).

Ratios are of figures measured in this run on this machine (its CPU is
printed). Results also go to out/bench/lights.json.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_report import cpu_model
from cornell_box import EQUAL_TIME_SEEDS, mean_rmse, mitsuba_render, rmse, spp_for

from yarf.assets import upload_scene_assets
from yarf.client import Client
from yarf.scene import load_scene
from yarf.server import LocalServer
from yarf.v1 import scene_pb2

ROOT = Path(__file__).resolve().parent.parent
VEACH = ROOT / "scenes" / "veach-mis" / "scene.xml"
EQUAL_TIME_SECONDS = 4.0
REFERENCE_SPP = 1024
INDEPENDENT = scene_pb2.ComponentSpec(class_name="independent")


def yarf_render(
    client: Client,
    scene: scene_pb2.Scene,
    spp: int,
    seed: int,
    sampler: scene_pb2.ComponentSpec | None = None,
) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    job = client.submit(scene, spp=spp, seed=seed, sampler=sampler, name=f"lights bench {spp} spp")
    status = client.wait(job)
    if status.error:
        sys.exit(f"yarf render failed: {status.error}")
    result = client.raw(job)
    pixels = scene.film.width * scene.film.height
    stats = {
        "spp": spp,
        "seconds": status.elapsed_seconds,
        "samples_per_second": pixels * spp / status.elapsed_seconds,
        "closest_hit_rays": status.closest_hit_rays,
        "shadow_rays": status.shadow_rays,
    }
    return result.pixels, result.variance, stats


def write_pfm(path: Path, rgb: np.ndarray) -> None:
    height, width, _ = rgb.shape
    with path.open("wb") as out:
        out.write(f"PF\n{width} {height}\n-1.0\n".encode())
        out.write(np.ascontiguousarray(rgb[::-1], dtype="<f4").tobytes())


def mitsuba_scene(camera_origin: str, width: int, height: int, shapes: str) -> str:
    """A Mitsuba 3 scene file: path tracing to depth 6, a 40° camera at
    `camera_origin` looking at the origin, independent samples, a box
    filter, and `shapes` (lights and shapes, as XML)."""
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="6"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world">
      <lookat origin="{camera_origin}" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"/>
    <film type="hdrfilm"><integer name="width" value="{width}"/>
      <integer name="height" value="{height}"/><rfilter type="box"/></film></sensor>
{shapes}</scene>
"""


def environment_scene(folder: Path) -> Path:
    """A glossy and a diffuse sphere on a floor under a sky map with a sun."""
    rows, columns = np.mgrid[0:128, 0:256]
    elevation = 1 - (rows + 0.5) / 64
    image = np.where(
        (elevation > 0)[..., None],
        np.stack([0.3 + 0.2 * elevation, 0.5 + 0.2 * elevation, 0.9 + 0.1 * elevation], -1),
        np.array([0.25, 0.18, 0.1]),
    )
    image[(abs(rows - 30) <= 2) & (abs(columns - 80) <= 2)] = [400.0, 360.0, 300.0]
    write_pfm(folder / "sky.pfm", image.astype(np.float32))
    path = folder / "scene.xml"
    path.write_text(
        mitsuba_scene(
            "0, 1.5, 5",
            192,
            128,
            """  <emitter type="envmap"><string name="filename" value="sky.pfm"/></emitter>
  <shape type="sphere"><point name="center" x="-1" y="0" z="0"/><float name="radius" value="0.9"/>
    <bsdf type="roughconductor"><string name="material" value="Au"/>
      <string name="distribution" value="ggx"/>
      <float name="alpha" value="0.1"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="1.1" y="0" z="0"/><float name="radius" value="0.9"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="6"/><rotate x="1" angle="-90"/>
    <translate y="-0.9"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
""",
        )
    )
    return path


def many_lights_scene() -> scene_pb2.Scene:
    """A floor under 100 small sphere lights on a grid, one of them far
    brighter than the rest and near the camera."""
    scene = scene_pb2.Scene()
    scene.camera.origin.y, scene.camera.origin.z = 3.0, 9.0
    scene.camera.target.y = 0.0
    scene.camera.up.y = 1.0
    scene.camera.fov = 50
    scene.film.width, scene.film.height = 128, 96
    floor = scene.materials.add(name="floor", class_name="lambertian")
    floor.properties.values["reflectance"].rgb_value.r = 0.6
    floor.properties.values["reflectance"].rgb_value.g = 0.6
    floor.properties.values["reflectance"].rgb_value.b = 0.6
    black = scene.materials.add(name="black", class_name="lambertian")
    black.properties.values["reflectance"].rgb_value.r = 0
    shape = scene.shapes.add(name="floor", material="floor")
    shape.rectangle.SetInParent()
    shape.to_world.m[:] = [10, 0, 0, 0, 0, 0, 1, 0, 0, -10, 0, 0, 0, 0, 0, 1]
    for k in range(100):
        light = scene.shapes.add(name=f"light{k}", material="black")
        light.sphere.center.x = -4.5 + (k % 10)
        light.sphere.center.y = 0.6
        light.sphere.center.z = -4.5 + (k // 10)
        light.sphere.radius = 0.05
        radiance = 2000.0 if k == 95 else 20.0
        light.emitter.class_name = "diffuse_area"
        value = light.emitter.properties.values["radiance"].rgb_value
        value.r = value.g = value.b = radiance
    return scene


def equal_time(client: Client, path: Path, folder: Path) -> dict[str, object]:
    """yarf vs Mitsuba llvm at equal time on the Mitsuba file `path`."""
    scene = load_scene(path)
    upload_scene_assets(client, scene, folder)
    pixels = scene.film.width * scene.film.height
    yarf_render(client, scene, 4, 99)  # warm-up
    _, _, yarf = yarf_render(client, scene, 64, 1)
    _, mitsuba = mitsuba_render("llvm_ad_rgb", 64, 1, path)
    yarf_reference, _, _ = yarf_render(client, scene, REFERENCE_SPP, 12345)
    mitsuba_reference, _ = mitsuba_render("llvm_ad_rgb", REFERENCE_SPP, 12345, path)
    # The mean of both, so that neither is judged against its own bias.
    reference = 0.5 * (yarf_reference.astype(np.float64) + mitsuba_reference)
    y_spp = spp_for(EQUAL_TIME_SECONDS, yarf["samples_per_second"], pixels)
    m_spp = spp_for(EQUAL_TIME_SECONDS, mitsuba["samples_per_second"], pixels)
    y_runs = [yarf_render(client, scene, y_spp, seed)[0] for seed in EQUAL_TIME_SEEDS]
    m_runs = [mitsuba_render("llvm_ad_rgb", m_spp, seed, path)[0] for seed in EQUAL_TIME_SEEDS]
    y64, _, _ = yarf_render(client, scene, 64, 8)
    m64, _ = mitsuba_render("llvm_ad_rgb", 64, 8, path)
    y_rmse, m_rmse = mean_rmse(y_runs, reference), mean_rmse(m_runs, reference)
    return {
        "yarf": {
            **yarf,
            "equal_time_spp": y_spp,
            "equal_time_rmse": y_rmse,
            "rmse_64spp": rmse(y64, reference),
        },
        "mitsuba_llvm_ad_rgb": {
            **mitsuba,
            "equal_time_spp": m_spp,
            "equal_time_rmse": m_rmse,
            "rmse_64spp": rmse(m64, reference),
        },
        "equal_time_rmse_vs_mitsuba_llvm": y_rmse / m_rmse,
        "equal_spp_rmse_vs_mitsuba_llvm": rmse(y64, reference) / rmse(m64, reference),
        "yarf_reference_vs_mitsuba_reference_rmse": rmse(yarf_reference, mitsuba_reference),
    }


def main() -> None:
    report: dict[str, object] = {"cpu": cpu_model()}
    with LocalServer() as server, tempfile.TemporaryDirectory() as folder:
        client = server.client()
        report["veach_mis"] = equal_time(client, VEACH, VEACH.parent)
        env = environment_scene(Path(folder))
        report["environment"] = equal_time(client, env, Path(folder))

        veach = load_scene(ROOT / "scenes" / "veach-mis" / "scene.json")
        _, by_cone, _ = yarf_render(client, veach, 64, 1, INDEPENDENT)
        veach.sphere_sampling = veach.SPHERE_SAMPLING_AREA
        _, by_area, _ = yarf_render(client, veach, 64, 2, INDEPENDENT)
        cone, area = by_cone.mean(-1), by_area.mean(-1)
        noisy = area > 0
        report["sphere_sampling_variance_solid_angle_vs_area"] = {
            "mean": float(cone.mean() / area.mean()),
            "median_pixel": float(np.median(cone[noisy] / area[noisy])),
        }

        lights = many_lights_scene()
        reference, _, _ = yarf_render(client, lights, 2048, 777)
        errors = {}
        for name, choice in (
            ("uniform", lights.LIGHT_SAMPLER_UNIFORM),
            ("power", lights.LIGHT_SAMPLER_POWER),
            ("bvh", lights.LIGHT_SAMPLER_BVH),
        ):
            lights.light_sampler = choice
            image, _, _ = yarf_render(client, lights, 16, 3, INDEPENDENT)
            errors[name] = rmse(image, reference)
        report["many_lights_rmse_16spp"] = {
            **errors,
            "power_vs_uniform": errors["power"] / errors["uniform"],
            "bvh_vs_uniform": errors["bvh"] / errors["uniform"],
        }

    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "lights.json").write_text(json.dumps(report, indent=2))
    print(f"lights benchmark on {report['cpu']}")
    for name in ("veach_mis", "environment"):
        r = report[name]
        print(
            f"{name}: equal-time ({EQUAL_TIME_SECONDS:.0f} s) RMSE yarf/mitsuba llvm "
            f"{r['equal_time_rmse_vs_mitsuba_llvm']:.3f} (yarf {r['yarf']['equal_time_spp']} spp, "
            f"mitsuba {r['mitsuba_llvm_ad_rgb']['equal_time_spp']} spp); equal-spp (64) "
            f"{r['equal_spp_rmse_vs_mitsuba_llvm']:.3f}"
        )
    s = report["sphere_sampling_variance_solid_angle_vs_area"]
    print(
        "veach_mis variance, spheres by solid angle / by area: "
        f"mean {s['mean']:.3f}, median pixel {s['median_pixel']:.3f}"
    )
    m = report["many_lights_rmse_16spp"]
    print(
        f"many lights, 16 spp RMSE: uniform {m['uniform']:.5f}, power {m['power']:.5f} "
        f"({m['power_vs_uniform']:.3f}x), bvh {m['bvh']:.5f} ({m['bvh_vs_uniform']:.3f}x)"
    )
    print(f"written {out / 'lights.json'}")


if __name__ == "__main__":
    main()
