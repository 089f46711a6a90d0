"""Fixtures of the end-to-end suite: one real yarfd for the whole session.

The server binary is found as LocalServer finds it ($YARF_YARFD, the
repository's build/bin/yarfd, or PATH); when it is missing the suite fails.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from yarf import Client, LocalServer, component, load_scene, properties, rgb, transform, vec3
from yarf.v1 import render_pb2, scene_pb2

REPO = Path(__file__).resolve().parents[1]
# CI clones the repository with the shared folder beside it.
SHARED = REPO.parent / "shared"
CORNELL_BOX = REPO / "scenes" / "cornell-box" / "scene.json"
MITSUBA_CBOX = SHARED / "scenes" / "mitsuba-cbox" / "cbox-rgb.xml"
# Mitsuba's Cornell box reference: MITSUBA_CBOX_SIZE² pixels, the mean of
# independent renders (scalar_rgb, independent sampler, its max_depth 6).
MITSUBA_CBOX_SIZE = 64
MITSUBA_CBOX_SEEDS = range(16)
MITSUBA_CBOX_SPP = 64

# A mesh file in the server's asset root (one triangle).
ASSET_MESH = "triangle.obj"
TRIANGLE_OBJ = b"v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n"


def small_scene(size: int = 16) -> scene_pb2.Scene:
    """A lit sphere in front of a square emitter facing the camera: renders in milliseconds."""
    scene = scene_pb2.Scene()
    scene.camera.origin.CopyFrom(vec3(0, 0, 4))
    scene.camera.target.CopyFrom(vec3(0, 0, 0))
    scene.camera.up.CopyFrom(vec3(0, 1, 0))
    scene.camera.fov = 40.0
    scene.film.width = size
    scene.film.height = size
    scene.materials.add(
        name="grey", class_name="lambertian", properties=properties(reflectance=rgb(0.5))
    )
    light = scene.shapes.add(name="light", material="grey")
    light.rectangle.SetInParent()
    light.to_world.CopyFrom(transform(np.diag([1.5, 1.5, 1.0, 1.0])))
    light.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1.0)))
    ball = scene.shapes.add(name="ball", material="grey")
    ball.sphere.center.CopyFrom(vec3(0, 0, 1))
    ball.sphere.radius = 0.5
    return scene


def grouped_scene() -> scene_pb2.Scene:
    """A small scene with a group placed twice and a texture: every count of a job's
    scene summary differs."""
    scene = small_scene(24)
    scene.film.height = 12
    group = scene.groups.add(name="pair")
    group.shapes.add(name="in_group", material="grey").sphere.radius = 0.1
    scene.instances.add(group="pair")
    scene.instances.add(group="pair")
    texture = scene.textures.add(name="checks")
    texture.texture.class_name = "checkerboard"
    scene.camera.model = scene_pb2.Camera.THIN_LENS
    scene.camera.lens_radius = 0.01
    scene.camera.focus_distance = 4.0
    return scene


@pytest.fixture(scope="session")
def asset_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The server's --asset-root, holding one mesh file."""
    root = tmp_path_factory.mktemp("assets")
    (root / ASSET_MESH).write_bytes(TRIANGLE_OBJ)
    return root


@pytest.fixture(scope="session")
def server(asset_root: Path) -> Iterator[LocalServer]:
    """The real yarfd, started once for the session."""
    with LocalServer(asset_root=asset_root) as local:
        yield local
        assert local.is_running(), f"yarfd died during the tests:\n{local.log[-4000:]}"


@pytest.fixture(scope="session")
def client(server: LocalServer) -> Iterator[Client]:
    with server.client() as session_client:
        yield session_client


@pytest.fixture(scope="session")
def cornell_box() -> scene_pb2.Scene:
    """The Cornell box the project ships, its meshes inlined."""
    return load_scene(CORNELL_BOX)


@pytest.fixture(scope="session")
def mitsuba_cbox_reference() -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba 3's mean image of MITSUBA_CBOX and the variance of that mean,
    rendered once for the tests that compare yarf's Cornell boxes with it."""
    import mitsuba as mi
    from imagestats import mean_and_variance

    mi.set_variant("scalar_rgb")
    assert MITSUBA_CBOX.exists(), f"{MITSUBA_CBOX} is missing (shared/ beside the repository)"
    scene = mi.load_file(str(MITSUBA_CBOX), res=MITSUBA_CBOX_SIZE)
    renders = [
        np.array(mi.render(scene, spp=MITSUBA_CBOX_SPP, seed=seed), dtype=np.float64)[..., :3]
        for seed in MITSUBA_CBOX_SEEDS
    ]
    return mean_and_variance(renders)


@pytest.fixture
def scene() -> scene_pb2.Scene:
    """A fresh small scene a test may change."""
    return small_scene()


@pytest.fixture
def assert_still_renders(client: Client) -> Callable[[], None]:
    """Checks that the server still renders a small scene correctly."""

    def check() -> None:
        job_id = client.submit(small_scene(), spp=4, seed=3, name="still-renders")
        status = client.wait(job_id, timeout=30)
        assert status.state == render_pb2.SUCCEEDED, (
            f"a small scene no longer renders: {render_pb2.JobState.Name(status.state)} "
            f"{status.error}"
        )
        pixels = client.image(job_id)
        assert pixels.shape == (16, 16, 3)
        assert np.isfinite(pixels).all() and pixels.mean() > 0

    return check


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    """Adds the tail of the session server's log to the report of a failed test."""
    outcome = yield
    report = outcome.get_result()
    local = getattr(item, "funcargs", {}).get("server")
    if report.failed and isinstance(local, LocalServer):
        report.sections.append(("yarfd log (tail)", "\n".join(local.log.splitlines()[-30:])))
