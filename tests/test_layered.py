"""pbrt-v4's layered materials (coateddiffuse, coatedconductor) in whole renders.

Their f, Sample and Pdf are stochastic estimates (a random walk between the
coat and the base, seeded by a hash of the call's inputs); the path tracer
and bidirectional path tracing weigh their BSDF and light samples by one
density (Pdf), so both must estimate the same image. Mitsuba has no such
material: the room is surface_scenes' Mitsuba XML, and the layered
materials are put on its sphere and floor with yarf's Python API.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from imagestats import block_z_test
from surface_scenes import write_scene
from test_surfaces import INDEPENDENT

from yarf import Client, RenderResult, component, load_scene, properties, rgb
from yarf.v1 import scene_pb2

SPHERE = '<shape type="sphere"><float name="radius" value="0.9"/><bsdf type="diffuse"/></shape>'
# A small sphere light: light samples by solid angle, BSDF samples
# weighted against them.
SPHERE_LIGHT = (
    '<shape type="sphere"><point name="center" x="1.2" y="1.8" z="1.5"/>'
    '<float name="radius" value="0.25"/>'
    '<emitter type="area"><rgb name="radiance" value="30, 30, 30"/></emitter></shape>'
)


def layered_room(folder: Path) -> scene_pb2.Scene:
    """The room with a coateddiffuse sphere (a rough coat over a scattering
    slab) on a coatedconductor floor (copper under a glossy coat)."""
    scene = load_scene(write_scene(folder, SPHERE, lights=SPHERE_LIGHT, max_depth=5))
    scene.materials.add(
        name="coated diffuse",
        class_name="coateddiffuse",
        properties=properties(
            reflectance=rgb(0.7, 0.4, 0.2), roughness=0.05, thickness=0.1, albedo=rgb(0.6), g=0.3
        ),
    )
    scene.materials.add(
        name="coated copper",
        class_name="coatedconductor",
        properties=properties(**{"interface.roughness": 0.02, "conductor.roughness": 0.1}),
    )
    spheres = [s for s in scene.shapes if s.HasField("sphere") and not s.HasField("emitter")]
    floors = [s for s in scene.shapes if s.HasField("rectangle") and not s.HasField("emitter")]
    assert len(spheres) == 1 and len(floors) == 1, scene.shapes
    spheres[0].material, floors[0].material = "coated diffuse", "coated copper"
    return scene


@pytest.mark.parametrize("transport", ["bdpt"])
def test_coated_materials_render_alike_by_path_and_bdpt(
    client: Client, tmp_path: Path, transport: str
) -> None:
    """Bidirectional path tracing (light subpaths evaluate the walk in
    importance mode, and weigh every strategy by Pdf) agrees with the path
    tracer on the layered room."""
    scene = layered_room(tmp_path)

    def render(name: str, spp: int, seed: int) -> RenderResult:
        return client.render(
            scene,
            spp=spp,
            seed=seed,
            transport=component(name, max_depth=5),
            sampler=INDEPENDENT,
            timeout=600,
        )

    reference, other = render("path", 1024, 1), render(transport, 1024, 2)
    assert reference.pixels.mean() > 0.01, "the room renders black"
    test = block_z_test(
        other.pixels,
        other.variance,
        reference.pixels,
        reference.variance,
        block=4,
        family_alpha=1e-3,
    )
    assert not test.failing.size, f"{transport} vs path:\n{test.report()}"
