"""The SEADS uniform grid against Embree's BVH: rays per second on the same
scenes, the same ray mixes and the same Embree kernels (the grid sits inside
Embree's BVH as one user geometry), as ratios measured in one run.

Scenes: the Cornell box (scenes/cornell-box, 36 triangles) and a bumpy
sphere of about 1M triangles lit by a quad. For each, embree_ceiling times
closest-hit and shadow rays with every kernel (single, stream, 8- and
16-wide packets) and the best is compared, with the build time.

A grid has no hierarchy: on a few large triangles it walks many empty or
crowded cells; on a fine even mesh it is at its best. The ratios say how far
either is from Embree's BVH here.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from bench_report import ROOT, cpu_model, write_result

CEILING = ROOT / "build" / "bin" / "embree_ceiling"
CORNELL_BOX = ROOT / "scenes" / "cornell-box" / "scene.json"


def bumpy_sphere_ply(path: Path, rings: int, segments: int, seed: int = 1) -> int:
    """A binary PLY of a sphere with radial noise; returns its triangle count."""
    random = np.random.default_rng(seed)
    theta = np.linspace(0, np.pi, rings + 1)[:, None]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)[None, :]
    radius = random.uniform(0.97, 1.03, size=(rings + 1, segments))
    radius[0, :] = radius[-1, :] = 1
    points = np.stack(
        [
            radius * np.sin(theta) * np.cos(phi),
            radius * np.cos(theta) + 0 * phi,
            radius * np.sin(theta) * np.sin(phi),
        ],
        axis=-1,
    ).reshape(-1, 3)
    r, s = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = r * segments + s
    b = r * segments + (s + 1) % segments
    c, d = a + segments, b + segments
    # Wound counter-clockwise seen from outside: the faces' normals point out,
    # as one-sided BSDFs (Mitsuba's diffuse) need.
    faces = np.concatenate([np.stack([a, b, c], -1), np.stack([b, d, c], -1)]).reshape(-1, 3)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(points)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    face_records = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<i4", 3)])
    face_records["n"] = 3
    face_records["v"] = faces
    with path.open("wb") as out:
        out.write(header.encode())
        out.write(points.astype("<f4").tobytes())
        out.write(face_records.tobytes())
    return len(faces)


def mesh_scene(folder: Path, rings: int, segments: int) -> tuple[Path, int]:
    triangles = bumpy_sphere_ply(folder / "bumpy.ply", rings, segments)
    light = {"positions": [-1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1], "indices": [0, 2, 1, 0, 3, 2]}
    scene = {
        "camera": {"origin": {"z": -3.5}, "target": {}, "up": {"y": 1}, "fov": 40},
        "film": {"width": 256, "height": 256},
        "materials": [{"name": "grey", "class_name": "lambertian"}],
        "shapes": [
            {"name": "bumpy", "mesh": {"file": "bumpy.ply"}, "material": "grey"},
            {
                "name": "light",
                "mesh": light,
                "material": "grey",
                "emitter": {
                    "class_name": "diffuse_area",
                    "properties": {"values": {"radiance": {"float_value": 5}}},
                },
            },
        ],
    }
    path = folder / "mesh.json"
    path.write_text(json.dumps(scene))
    return path, triangles


def with_grid(scene: Path, density: float) -> Path:
    data = json.loads(scene.read_text())
    data["aggregate"] = {
        "class_name": "seads",
        "properties": {"values": {"density": {"float_value": density}}},
    }
    path = scene.with_name(scene.stem + "-seads.json")
    path.write_text(json.dumps(data))
    return path


def ceiling(scene: Path, rays: int) -> dict[str, object]:
    result = subprocess.run([str(CEILING), str(scene), str(rays)], capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"embree_ceiling {scene.name} failed:\n{result.stderr[-2000:]}")
    return json.loads(result.stdout)


def compare(name: str, scene: Path, density: float, rays: int) -> dict[str, object]:
    bvh = ceiling(scene, rays)
    grid = ceiling(with_grid(scene, density), rays)
    row: dict[str, object] = {"scene": name}
    for kind in ("closest", "shadow"):
        bvh_best, grid_best = bvh[kind]["best"], grid[kind]["best"]  # type: ignore[index]
        row[f"{kind}_bvh_rays_per_s"] = bvh_best
        row[f"{kind}_grid_rays_per_s"] = grid_best
        row[f"{kind}_grid_vs_bvh"] = grid_best / bvh_best
    row["build_seconds_bvh"] = bvh["build_seconds"]
    row["build_seconds_grid"] = grid["build_seconds"]
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=1 << 20)
    parser.add_argument(
        "--rings", type=int, default=500, help="the mesh has 2·rings·segments triangles"
    )
    parser.add_argument("--density", type=float, default=2.0, help="the grid's cells per triangle")
    args = parser.parse_args()
    print(f"CPU: {cpu_model()}")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        mesh, triangles = mesh_scene(Path(folder), args.rings, 2 * args.rings)
        # Beside its meshes: a scene reads files only inside its folder.
        shutil.copytree(CORNELL_BOX.parent / "meshes", Path(folder) / "meshes")
        cornell = Path(folder) / "cornell-box.json"
        cornell.write_text(CORNELL_BOX.read_text())
        rows.append(compare("cornell_box", cornell, args.density, args.rays))
        rows.append(compare(f"bumpy_sphere_{triangles}", mesh, args.density, args.rays))
    for row in rows:
        print(
            f"{row['scene']:>22}: closest {row['closest_grid_vs_bvh']:.2f}x "
            f"({row['closest_grid_rays_per_s'] / 1e6:.1f} vs "
            f"{row['closest_bvh_rays_per_s'] / 1e6:.1f} M rays/s), "
            f"shadow {row['shadow_grid_vs_bvh']:.2f}x, "
            f"build {row['build_seconds_grid']:.2f} s vs {row['build_seconds_bvh']:.2f} s"
        )
    write_result("aggregates", {"cpu": cpu_model(), "density": args.density, "scenes": rows})


if __name__ == "__main__":
    main()
