"""Light transport written in Python, rendering through yarfd's kernel
services (the job's SceneView and Intersect):
ambient occlusion against its analytic value, a Python path tracer against
the C++ one, and splats that land where and as much as they should."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import grpc
import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import CORNELL_BOX, REPO
from imagestats import block_z_test

from yarf import Client, LocalServer, component, load_scene, transform, vec3
from yarf.v1 import render_pb2, scene_pb2, transport_pb2, transport_pb2_grpc

EXAMPLES = REPO / "components" / "python" / "examples"
SPLATTER = Path(__file__).resolve().parent / "components" / "splatter.py"
# A "large" plane: its edges subtend under 0.2% of the hemisphere from where we look.
HALF_SIZE = 2000.0


@pytest.fixture(scope="module")
def transports(tmp_path_factory: pytest.TempPathFactory, server: LocalServer) -> Iterator[str]:
    """One process serving the example transports and the splatter; they
    call the session's yarfd back for its scenes."""
    socket = tmp_path_factory.mktemp("transports") / "t.sock"
    targets = [
        f"{EXAMPLES / 'ambient_occlusion.py'}:AmbientOcclusion",
        f"{EXAMPLES / 'path.py'}:PathTracer",
        f"{EXAMPLES / 'direct.py'}:DirectLighting",
        f"{SPLATTER}:CentreSplatter",
    ]
    with ComponentProcess.python(targets, f"unix:{socket}", "--server", server.address) as process:
        yield process.address


def floor_and_wall(size: int = 16) -> scene_pb2.Scene:
    """The floor y = 0 and the wall x = 0, both huge; the camera looks down at
    the floor between x = 1 and x = 3, away from the corner."""
    scene = scene_pb2.Scene()
    scene.camera.origin.CopyFrom(vec3(2, 4, 0))
    scene.camera.target.CopyFrom(vec3(2, 0, 0))
    scene.camera.up.CopyFrom(vec3(0, 0, 1))
    scene.camera.fov = 28.0
    scene.film.width = scene.film.height = size
    scene.materials.add(name="grey", class_name="lambertian")
    # The rectangle lies in z = 0 with normal +z: turn +z to +y (floor), to +x (wall).
    floor = np.array([[HALF_SIZE, 0, 0, 0], [0, 0, HALF_SIZE, 0], [0, -1, 0, 0], [0, 0, 0, 1]])
    wall = np.array([[0, 0, 1, 0], [0, HALF_SIZE, 0, 0], [-HALF_SIZE, 0, 0, 0], [0, 0, 0, 1]])
    for name, matrix in (("floor", floor), ("wall", wall)):
        shape = scene.shapes.add(name=name, material="grey")
        shape.rectangle.SetInParent()
        shape.to_world.CopyFrom(transform(matrix))
    return scene


def render(
    client: Client, scene: scene_pb2.Scene, spp: int, seed: int, spec: scene_pb2.ComponentSpec
) -> render_pb2.JobStatus:
    job_id = client.submit(scene, spp, seed, transport=spec, name=spec.class_name)
    status = client.wait(job_id, timeout=300)
    assert status.state == render_pb2.SUCCEEDED, status.error
    return status


def at(address: str, class_name: str, **values: float | int) -> scene_pb2.ComponentSpec:
    spec = component(class_name, **values)
    spec.address = address
    return spec


def test_ambient_occlusion_beside_an_infinite_wall_is_one_half(
    client: Client, transports: str
) -> None:
    # Half of the cosine-weighted hemisphere of every floor point looks
    # toward the wall, which is infinite: AO = 1/2 wherever it is.
    status = render(client, floor_and_wall(), 64, 1, at(transports, "py_ambient_occlusion"))
    result = client.raw(status.job_id)
    mean = result.pixels[..., 0].mean()
    standard_error = np.sqrt(result.variance[..., 0].sum()) / result.pixels[..., 0].size
    assert abs(mean - 0.5) < 4 * standard_error + 0.003, (mean, standard_error)
    assert np.array_equal(result.pixels[..., 0], result.pixels[..., 2])


def test_ambient_occlusion_within_a_short_distance_sees_no_wall(
    client: Client, transports: str
) -> None:
    # Every visible floor point is at least 1 from the wall: nothing within 0.5.
    status = render(
        client, floor_and_wall(), 8, 1, at(transports, "py_ambient_occlusion", distance=0.5)
    )
    assert np.all(client.image(status.job_id) == 1.0)


def test_python_path_tracer_renders_the_cornell_box_as_the_cpp_one(
    client: Client, transports: str
) -> None:
    scene = load_scene(CORNELL_BOX)
    scene.film.width = scene.film.height = 32
    python = client.raw(render(client, scene, 64, 1, at(transports, "py_path", max_depth=5)).job_id)
    cpp = client.raw(render(client, scene, 64, 2, component("path", max_depth=5)).job_id)
    test = block_z_test(
        python.pixels, python.variance, cpp.pixels, cpp.variance, block=4, family_alpha=1e-3
    )
    assert not test.failing.size, f"py_path vs path:\n{test.report()}"
    assert np.allclose(python.pixels.mean(), cpp.pixels.mean(), rtol=0.03)


@pytest.mark.parametrize("scene_name", ["veach-mis", "cornell-box"])
def test_direct_light_through_the_surface_samplers_matches_the_path_tracer(
    client: Client, transports: str, scene_name: str
) -> None:
    """py_direct samples the emitting shapes through SampleSurfaceDirection and
    weighs its BSDF samples by SampleSurfaceDirection.Pdf: sphere lights by
    their cone (Veach's MIS scene), the Cornell box's lamp by the solid angle
    of its triangles. Any density that did not match its samples would bias
    the image away from the C++ path tracer's two-segment paths."""
    scene = load_scene(REPO / "scenes" / scene_name / "scene.json")
    scene.film.width, scene.film.height = (48, 36) if scene_name == "veach-mis" else (32, 32)
    scene.triangle_sampling = scene.TRIANGLE_SAMPLING_SOLID_ANGLE
    # The plates' glimpses of the smallest lamp are rare, bright samples: at
    # few samples a variance estimate misses them, so both take many.
    python = client.raw(render(client, scene, 256, 1, at(transports, "py_direct")).job_id)
    cpp = client.raw(render(client, scene, 1024, 2, component("path", max_depth=2)).job_id)
    test = block_z_test(
        python.pixels, python.variance, cpp.pixels, cpp.variance, block=4, family_alpha=1e-3
    )
    assert not test.failing.size, f"py_direct vs path:\n{test.report()}"
    assert np.allclose(python.pixels.mean(), cpp.pixels.mean(), rtol=0.03)


def test_splats_add_light_where_they_land(client: Client, transports: str) -> None:
    scene = floor_and_wall(size=8)
    status = render(client, scene, 3, 1, at(transports, "centre_splatter"))
    image = client.image(status.job_id)
    # Each pass of 64 points adds 64/64 = 1 to the middle pixel; passes average.
    assert np.allclose(image[4, 4], 1.0, rtol=1e-5), image[4, 4]
    assert np.allclose(image.sum(axis=(0, 1)), 1.0, rtol=1e-5)


def test_the_scene_view_of_no_running_job_is_not_found(client: Client) -> None:
    stub = transport_pb2_grpc.SceneViewStub(client.channel)
    with pytest.raises(grpc.RpcError) as missing:
        stub.Layout(transport_pb2.SceneViewRequest(handle=987654), timeout=10)
    assert missing.value.code() == grpc.StatusCode.NOT_FOUND
