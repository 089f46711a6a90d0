"""Small Mitsuba scenes for checking surfaces against Mitsuba 3 itself.

Each scene is a Mitsuba XML file (with the meshes and images it names)
written into a folder, so that yarf's importer and Mitsuba read the very
same file. The Mitsuba reference is rendered in the test, with Mitsuba's
own render-regression budget: 2·10⁶ samples over the image, split into
independent renders whose spread gives each pixel's variance.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from imagestats import mean_and_variance

SIZE = 32
# Mitsuba's render-regression budget: spp = 2·10⁶ / pixels.
SPP = 2_000_000 // (SIZE * SIZE)
# Independent Mitsuba renders the reference is made of.
MITSUBA_RENDERS = 16


def uv_sphere(
    segments: int, rings: int
) -> tuple[list[tuple[float, float, float, float, float]], list[tuple[int, int, int]]]:
    """A unit UV sphere: vertices (x, y, z, u, v) and triangles (0-based,
    counter-clockwise seen from outside).

    Vertices are repeated along the seam (u = 0 and 1) and at the poles so
    that each corner carries its own uv, as modelling tools write them.
    """
    vertices = []
    for ring in range(rings + 1):
        theta = math.pi * ring / rings
        for segment in range(segments + 1):
            phi = 2 * math.pi * segment / segments
            x, y, z = (
                math.sin(theta) * math.cos(phi),
                math.cos(theta),
                math.sin(theta) * math.sin(phi),
            )
            vertices.append((x, y, z, segment / segments, 1 - ring / rings))
    row = segments + 1
    triangles = []
    for ring in range(rings):
        for segment in range(segments):
            a = ring * row + segment
            b, c, d = a + 1, a + row, a + row + 1
            triangles += [(a, b, d), (a, d, c)]
    return vertices, triangles


def uv_sphere_obj(segments: int, rings: int) -> str:
    """The UV sphere as OBJ text, with uvs and exact vertex normals."""
    vertices, triangles = uv_sphere(segments, rings)
    lines = []
    for x, y, z, u, v in vertices:
        lines += [
            f"v {x:.7f} {y:.7f} {z:.7f}",
            f"vn {x:.7f} {y:.7f} {z:.7f}",
            f"vt {u:.7f} {v:.7f}",
        ]
    for triangle in triangles:
        lines.append("f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in triangle))
    return "\n".join(lines) + "\n"


def positions_only_ply(
    mesh: tuple[list[tuple[float, float, float, float, float]], list[tuple[int, int, int]]],
) -> str:
    """A mesh (as uv_sphere gives it) as ASCII PLY of positions and faces
    alone, less its zero-area triangles (the poles'): Mitsuba computes NaN
    normals for their vertices."""
    vertices, all_triangles = mesh
    text = [f"{x:.7f} {y:.7f} {z:.7f}" for x, y, z, _, _ in vertices]
    points = [tuple(float(c) for c in line.split()) for line in text]  # as written
    triangles = [t for t in all_triangles if len({points[i] for i in t}) == 3]
    return (
        "\n".join(
            [
                "ply",
                "format ascii 1.0",
                f"element vertex {len(vertices)}",
                "property float x",
                "property float y",
                "property float z",
                f"element face {len(triangles)}",
                "property list uchar int vertex_indices",
                "end_header",
                *text,
                *(f"3 {a} {b} {c}" for a, b, c in triangles),
            ]
        )
        + "\n"
    )


def uv_sphere_ply(segments: int, rings: int, *, per_face: bool) -> str:
    """The UV sphere as ASCII PLY with vertex normals and colours: per vertex
    from the position (vertex_color), or per face from its index (face_color)."""
    vertices, triangles = uv_sphere(segments, rings)
    vertex_lines = []
    for x, y, z, _, _ in vertices:
        colour = "" if per_face else f" {0.5 + 0.4 * x:.6f} {0.5 + 0.4 * y:.6f} {0.5 + 0.4 * z:.6f}"
        vertex_lines.append(f"{x:.7f} {y:.7f} {z:.7f} {x:.7f} {y:.7f} {z:.7f}{colour}")
    face_lines = []
    for k, (a, b, c) in enumerate(triangles):
        colour = f" {0.2 + 0.7 * (k % 3 == 0):.1f} {0.2 + 0.6 * (k % 5 < 2):.1f} 0.3"
        face_lines.append(f"3 {a} {b} {c}{colour if per_face else ''}")
    colours = "property float r\nproperty float g\nproperty float b\n"
    header = (
        "ply\nformat ascii 1.0\n"
        f"element vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        + ("" if per_face else colours)
        + f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
        + (colours if per_face else "")
        + "end_header\n"
    )
    return header + "\n".join(vertex_lines + face_lines) + "\n"


# The room's light: a tilted square above the shape.
AREA_LIGHT = """<shape type="rectangle">
    <transform name="to_world">
      <scale value="0.8"/><rotate x="1" angle="90"/><rotate z="1" angle="25"/>
      <translate x="1" y="3" z="1"/>
    </transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="12, 12, 12"/></emitter>
  </shape>"""
# The room's floor.
FLOOR = """<shape type="rectangle">
    <transform name="to_world">
      <scale value="4"/><rotate x="1" angle="-90"/><translate y="-1"/>
    </transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  </shape>"""


def scene_xml(
    shape: str,
    *,
    max_depth: int = 4,
    lights: str = AREA_LIGHT,
    floor: str = FLOOR,
    integrator: str = "path",
) -> str:
    """A lit room around one shape (XML of Mitsuba 3): a floor, an area light
    (or the given lights), rendered by ``integrator``."""
    return f"""<scene version="3.0.0">
  <integrator type="{integrator}"><integer name="max_depth" value="{max_depth}"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world">
      <lookat origin="0, 1.5, 4" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/>
    </film>
  </sensor>
  {shape}
  {floor}
  {lights}
</scene>
"""


def write_scene(
    folder: Path, shape: str, files: dict[str, str] | None = None, **room: str | int
) -> Path:
    """Writes the scene around ``shape`` (``room``: scene_xml's options) and the
    text files it names; returns the XML's path."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in (files or {}).items():
        (folder / name).write_text(text)
    path = folder / "scene.xml"
    path.write_text(scene_xml(shape, **room))  # type: ignore[arg-type]
    return path


def render_mitsuba(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba 3's image of the scene file and the variance of each of its pixels."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_file(str(path))
    spp = max(1, SPP // MITSUBA_RENDERS)
    renders = [
        np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]
        for seed in range(MITSUBA_RENDERS)
    ]
    return mean_and_variance(renders)
