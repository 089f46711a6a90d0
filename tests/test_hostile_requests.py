"""Requests made to crash, stall or overreach yarfd, against the session's real server.

Each is refused at Submit with an error naming the field, or fails its own
job with a clear error; the server stays up and renders the next job. These
are the requests that once aborted yarfd (Embree's ray assertion on NaN
cameras, singular instances, huge lights) or stalled it.
"""

from __future__ import annotations

import hashlib
import math
import os
import sqlite3
import subprocess
import threading
import time
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import small_scene

from yarf import Client, LocalServer, component, properties, rgb, transform, vec3
from yarf.integrate import serve_function
from yarf.scene import Reference, float_array
from yarf.server import find_yarfd
from yarf.v1 import asset_pb2, math_pb2, math_pb2_grpc, render_pb2, scene_pb2


def refusal(client: Client, request: render_pb2.SubmitRequest) -> grpc.RpcError:
    with pytest.raises(grpc.RpcError) as caught:
        client.render_service.Submit(request, timeout=30)
    return caught.value


def submit_request(scene: scene_pb2.Scene, **fields: object) -> render_pb2.SubmitRequest:
    return render_pb2.SubmitRequest(scene=scene, options=render_pb2.RenderOptions(spp=2), **fields)


def camera_with(field: str, axis: str, value: float) -> scene_pb2.Scene:
    scene = small_scene()
    setattr(getattr(scene.camera, field), axis, value)
    return scene


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e39, 1e300])
@pytest.mark.parametrize("field", ["origin", "target", "up"])
def test_a_camera_of_non_finite_or_huge_numbers_is_refused_at_submit(
    client: Client, assert_still_renders: Callable[[], None], field: str, value: float
) -> None:
    error = refusal(client, submit_request(camera_with(field, "x", value)))
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    assert f"scene.camera.{field}.x" in error.details(), error.details()
    assert_still_renders()


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda s: setattr(s.camera, "near_clip", math.nan), "scene.camera.near_clip"),
        (lambda s: setattr(s.camera, "fov", math.inf), "scene.camera.fov"),
        (lambda s: setattr(s.camera, "lens_radius", 1e30), "scene.camera.lens_radius"),
        (lambda s: setattr(s.shapes[1].sphere, "radius", 1e300), "scene.shapes[1].sphere.radius"),
        (
            lambda s: s.shapes[0].to_world.m.__setitem__(3, math.nan),
            "scene.shapes[0].to_world.m[3]",
        ),
        (
            lambda s: (
                s.materials[0].properties.values["reflectance"].rgb_value.__setattr__("g", math.nan)
            ),
            "reflectance",
        ),
    ],
)
def test_a_non_finite_or_huge_number_anywhere_is_refused_naming_its_field(
    client: Client,
    assert_still_renders: Callable[[], None],
    change: Callable[[scene_pb2.Scene], None],
    field: str,
) -> None:
    scene = small_scene()
    change(scene)
    error = refusal(client, submit_request(scene))
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    assert field in error.details(), error.details()
    assert_still_renders()


@pytest.mark.parametrize("position", [1e300, 1e39, math.nan])
def test_a_point_light_infinitely_far_is_refused(client: Client, position: float) -> None:
    scene = small_scene()
    light = scene.lights.add(name="far", emitter=component("point", intensity=rgb(1.0)))
    light.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, position], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]))
    )
    error = refusal(client, submit_request(scene))
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    assert "scene.lights[0].to_world.m[3]" in error.details(), error.details()


def instanced_scene(*scales: float) -> scene_pb2.Scene:
    """The small scene with its ball in a group placed by nested instances of these scales."""
    scene = small_scene()
    ball = scene.shapes.pop()
    names = [f"level{i}" for i in range(len(scales))]
    for i, name in enumerate(names):
        group = scene.groups.add(name=name)
        if i + 1 < len(names):
            placed = group.instances.add(group=names[i + 1])
            placed.to_world.CopyFrom(transform(np.diag([scales[i + 1]] * 3 + [1.0])))
        else:
            group.shapes.add().CopyFrom(ball)
    top = scene.instances.add(group=names[0])
    top.to_world.CopyFrom(transform(np.diag([scales[0]] * 3 + [1.0])))
    return scene


@pytest.mark.parametrize("scale", [0.0, 1e-30, 1e30])
def test_a_singular_instance_transform_is_refused_at_submit(
    client: Client, assert_still_renders: Callable[[], None], scale: float
) -> None:
    error = refusal(client, submit_request(instanced_scene(scale)))
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    assert "instance" in error.details() and "to_world" in error.details(), error.details()
    assert_still_renders()


def test_a_stretched_instance_transform_is_refused(client: Client) -> None:
    scene = instanced_scene(1.0)
    scene.instances[0].to_world.CopyFrom(transform(np.diag([1e5, 1.0, 1e-5, 1.0])))
    error = refusal(client, submit_request(scene))
    assert "degenerate to_world" in error.details(), error.details()


def test_nested_instances_whose_product_is_singular_fail_their_job_and_not_the_server(
    client: Client, assert_still_renders: Callable[[], None]
) -> None:
    # Each level's scale is fine on its own; together they shrink space by 1e-15.
    job = client.submit(instanced_scene(1e-5, 1e-5, 1e-5), spp=2, name="nested singular")
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.FAILED, status
    assert "composed" in status.error and "degenerate to_world" in status.error, status.error
    assert_still_renders()


def test_a_medium_whose_majorant_is_absurdly_loose_fails_its_job(
    client: Client, assert_still_renders: Callable[[], None]
) -> None:
    """A grid whose one dense voxel makes its majorant 1e9 where the density
    is zero: a ray would meet ~1e8 null collisions; the job fails, clearly."""
    scene = small_scene()
    scene.materials.add(name="boundary", class_name="null")
    scene.camera_medium = "fog"
    placement = np.diag([40.0, 40.0, 8.0, 1.0])
    placement[:3, 3] = (-20, -20, -2)
    density = [1e9] + [0.0] * 7
    scene.media.add(
        name="fog",
        medium=component(
            "grid",
            density=float_array(density),
            nx=1,
            ny=1,
            nz=len(density),
            to_world=transform(placement),
        ),
    )
    job = client.submit(scene, spp=1, transport=component("volpath"), name="loose majorant")
    status = client.wait(job, timeout=120)
    assert status.state == render_pb2.FAILED, status
    assert "collisions in one medium" in status.error, status.error
    assert_still_renders()


def test_a_sound_but_extreme_scene_renders(client: Client) -> None:
    """A large thin lens and a distant light are within range: they render, finite."""
    scene = small_scene()
    scene.camera.model = scene_pb2.Camera.THIN_LENS
    scene.camera.lens_radius = 1e6
    scene.camera.focus_distance = 4.0
    light = scene.lights.add(name="distant", emitter=component("point", intensity=rgb(1e10)))
    light.to_world.CopyFrom(
        transform(np.array([[1, 0, 0, 1e5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]))
    )
    result = client.render(scene, spp=4, seed=1, timeout=60)
    assert np.isfinite(result.pixels).all()


def test_a_job_name_over_a_kibibyte_is_refused_and_list_still_works(client: Client) -> None:
    error = refusal(client, submit_request(small_scene(), name="n" * (5 << 20)))
    assert error.code() == grpc.StatusCode.INVALID_ARGUMENT, error
    assert "name" in error.details() and "1024" in error.details(), error.details()
    assert all(len(status.name) <= 1024 for status in client.list())


def test_a_request_over_the_size_limit_is_refused_without_taking_memory(
    client: Client, server: LocalServer, assert_still_renders: Callable[[], None]
) -> None:
    scene = small_scene()
    mesh = scene.shapes.add(name="huge", material="grey").mesh
    mesh.data = b"\0" * (80 << 20)
    mesh.format = "ply"
    error = refusal(client, submit_request(scene))
    assert error.code() in (grpc.StatusCode.RESOURCE_EXHAUSTED, grpc.StatusCode.INVALID_ARGUMENT), (
        error
    )
    assert server.is_running()
    assert_still_renders()


def test_text_that_is_not_utf8_is_refused_and_list_still_decodes(client: Client) -> None:
    marker = "MARKERNAME"
    wire = submit_request(small_scene(), name=marker).SerializeToString()
    wire = wire.replace(marker.encode(), b"\xff\xfeBAD\xc3\x28\xed\xa0\x80")
    submit = client.channel.unary_unary(
        "/yarf.v1.RenderService/Submit",
        request_serializer=lambda raw: raw,
        response_deserializer=render_pb2.SubmitReply.FromString,
    )
    with pytest.raises(grpc.RpcError):
        submit(wire, timeout=30)
    for status in client.list():
        status.name.encode("utf-8")
        status.error.encode("utf-8")


def test_photon_counts_beyond_their_range_are_refused_at_submit(client: Client) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        client.submit(
            small_scene(),
            spp=1,
            transport=component("photon_map", photons=10**10),
            name="too many photons",
        )
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
    details = str(refused.value.details())  # type: ignore[attr-defined]
    assert "options.transport.properties.photons: 10000000000 is above 50000000" in details, details


def start_shooting_photons(client: Client, scene: scene_pb2.Scene, name: str) -> str:
    """A photon_map job in its Prepare: 40 M photons take far longer than the test."""
    transport = component("photon_map", photons=40_000_000, caustic_photons=0)
    job = client.submit(scene, spp=1, transport=transport, name=name)
    deadline = time.monotonic() + 30
    while client.status(job).state != render_pb2.RUNNING:
        assert time.monotonic() < deadline, "the photon job did not start"
        time.sleep(0.02)
    time.sleep(0.5)
    return job


def test_a_job_cancelled_while_shooting_photons_ends_within_a_second(
    client: Client, cornell_box: scene_pb2.Scene, assert_still_renders: Callable[[], None]
) -> None:
    job = start_shooting_photons(client, cornell_box, "photons to cancel")
    cancelled_at = time.monotonic()
    client.cancel(job)
    while client.status(job).state == render_pb2.RUNNING:
        assert time.monotonic() - cancelled_at < 1.0, (
            "the photon job ran on for a second after Cancel"
        )
        time.sleep(0.01)
    assert client.status(job).state == render_pb2.CANCELLED
    assert_still_renders()


def test_yarfd_refuses_to_run_as_root_unless_told(tmp_path: Path) -> None:
    if os.geteuid() != 0:
        pytest.skip("only root can be refused for being root")
    environment = {key: value for key, value in os.environ.items() if key != "YARF_ALLOW_ROOT"}
    refused = subprocess.run(
        [str(find_yarfd()), "--listen", "127.0.0.1:0", "--state-dir", str(tmp_path / "state")],
        env=environment,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert refused.returncode != 0
    assert "refusing to run as root" in refused.stderr and "--allow-root" in refused.stderr
    assert not (tmp_path / "state").exists()


def test_load_plugin_is_off_by_default(client: Client, server: LocalServer) -> None:
    plugin = next((server.binary.resolve().parent.parent / "plugins").glob("*.so"))
    with pytest.raises(grpc.RpcError) as caught:
        client.load_plugin(str(plugin))
    assert caught.value.code() == grpc.StatusCode.FAILED_PRECONDITION
    assert "--allow-load-plugin" in caught.value.details()


def test_load_plugin_takes_only_files_of_the_plugin_path(tmp_path: Path) -> None:
    """A library elsewhere is refused before it is opened: its constructor never runs."""
    marker = tmp_path / "constructor-ran"
    source = tmp_path / "evil.cc"
    source.write_text(
        "#include <fstream>\n"
        f'__attribute__((constructor)) static void Run() {{ std::ofstream("{marker}") << 1; }}\n'
    )
    library = tmp_path / "libevil.so"
    subprocess.run(["g++", "-shared", "-fPIC", "-o", str(library), str(source)], check=True)
    plugins = tmp_path / "plugins"
    plugins.mkdir()
    with (
        LocalServer(plugin_paths=[plugins], extra_args=["--allow-load-plugin"]) as local,
        local.client() as client,
    ):
        # Made after the start, which loads the folder's files as the admin's.
        (plugins / "libescape.so").symlink_to(library)
        for path in (library, plugins / "libescape.so", plugins / ".." / "libevil.so"):
            with pytest.raises(grpc.RpcError) as caught:
                client.load_plugin(str(path))
            assert caught.value.code() == grpc.StatusCode.FAILED_PRECONDITION
            assert "--plugin-path" in caught.value.details(), caught.value.details()
        assert not marker.exists(), "the refused library's constructor ran"
        assert local.is_running()


def test_properties_of_a_material_are_checked_like_every_field(client: Client) -> None:
    scene = small_scene()
    scene.materials.add(
        name="bad",
        class_name="lambertian",
        properties=properties(reflectance=rgb(0.5), scale=math.inf),
    )
    error = refusal(client, submit_request(scene))
    assert "scene.materials[1].properties.values" in error.details(), error.details()


def scale_chain(scene: scene_pb2.Scene, length: int) -> str:
    """Textures t0 … t(length − 1), each the one before scaled; the last one's name."""
    scene.textures.add(name="t0").texture.CopyFrom(component("constant_texture", value=rgb(0.5)))
    for k in range(1, length):
        scene.textures.add(name=f"t{k}").texture.CopyFrom(
            component("scale", tex=Reference(f"t{k - 1}"), scale=1.0)
        )
    return f"t{length - 1}"


def mix_of_mixes(scene: scene_pb2.Scene, levels: int) -> str:
    """Each mix blends the one before with itself: 2^levels lookups of the first."""
    scene.textures.add(name="m0").texture.CopyFrom(component("constant_texture", value=rgb(0.5)))
    for k in range(1, levels + 1):
        before = Reference(f"m{k - 1}")
        scene.textures.add(name=f"m{k}").texture.CopyFrom(
            component("mix", tex1=before, tex2=before, amount=0.5)
        )
    return f"m{levels}"


def blend_of_blends(scene: scene_pb2.Scene, levels: int) -> str:
    for k in range(1, levels + 1):
        before = Reference("grey" if k == 1 else f"b{k - 1}")
        scene.materials.add(
            name=f"b{k}", class_name="blend", properties=properties(bsdf_0=before, bsdf_1=before)
        )
    return f"b{levels}"


def with_sphere_of(scene: scene_pb2.Scene, part: str) -> scene_pb2.Scene:
    """The sphere made of material `part`, or of a grey one textured by texture `part`."""
    if any(m.name == part for m in scene.materials):
        scene.shapes[1].material = part
    else:
        scene.shapes[1].material = "sphere"
        scene.materials.add(name="sphere", class_name="lambertian").properties.CopyFrom(
            properties(reflectance=Reference(part))
        )
    return scene


# A material counts the texture it refers to: the sphere's grey one adds a
# part to the chain and the mixes.
@pytest.mark.parametrize(
    "make, refused, accepted, what",
    [
        (scale_chain, 1025, 1023, "texture 't1024' (scale)"),
        (mix_of_mixes, 10, 9, "texture 'm10' (mix)"),
        (blend_of_blends, 10, 9, "material 'b10' (blend)"),
    ],
    ids=["a chain of 1025 textures", "a mix of mixes 10 deep", "a blend of blends 10 deep"],
)
def test_a_texture_or_material_referring_to_too_many_parts_is_refused_at_submit(
    client: Client,
    make: Callable[[scene_pb2.Scene, int], str],
    refused: int,
    accepted: int,
    what: str,
) -> None:
    """Each lookup evaluates its tree of references: a chain, or a DAG whose
    shared parts double at every level, would stall every render thread
    (2^40 lookups at 40 levels) or exhaust its stack."""
    scene = small_scene()
    error = refusal(client, submit_request(with_sphere_of(scene, make(scene, refused))))
    assert what in error.details() and "at most 1024" in error.details(), error.details()

    scene = small_scene()
    job = client.submit(with_sphere_of(scene, make(scene, accepted)), spp=1)
    status = client.wait(job, timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_a_scene_of_fifty_thousand_textures_starts_rendering_at_once(client: Client) -> None:
    """Making each texture copied the table of those before it: this scene
    (2.6 MB) took the server minutes of work before its first sample."""
    scene = small_scene()
    for k in range(50_000):
        scene.textures.add(name=f"t{k}").texture.CopyFrom(component("constant_texture", value=0.5))
    status = client.wait(client.submit(with_sphere_of(scene, "t49999"), spp=1), timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_whitted_between_glass_and_mirrors_keeps_its_branches_bounded(client: Client) -> None:
    """Glass splits each branch in two: in a mirror room, max_depth 60 asked
    for 2^59 branches per pixel and took the server's memory."""
    scene = small_scene()
    scene.materials.add(name="glass", class_name="dielectric")
    scene.materials.add(name="mirror", class_name="mirror")
    scene.shapes[1].material = "glass"
    second = scene.shapes.add(name="second ball", material="glass")
    second.sphere.center.CopyFrom(vec3(0.3, 0.2, 0.2))
    second.sphere.radius = 0.4
    room = scene.shapes.add(name="room", material="mirror", flip_normals=True)
    room.sphere.radius = 10
    job = client.submit(scene, spp=1, transport=component("whitted", max_depth=60))
    status = client.wait(job, timeout=120)
    assert status.state == render_pb2.SUCCEEDED, status.error
    assert np.isfinite(client.image(job)).all()


def memory_megabytes(pid: int, field: str) -> float:
    """A process's memory figure from /proc: VmRSS (now) or VmHWM (its peak)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024
    raise AssertionError(f"no {field}")


def test_a_path_that_never_ends_between_mirrors_keeps_its_memory_bounded() -> None:
    """Without roulette and without a depth limit, a path inside a mirror
    never ends; each bounce asks for new sample dimensions, and the batch
    kept every one: 75 MB more every second until the server's memory was
    gone. It may run until cancelled (or its time limit), in bounded memory."""
    scene = small_scene()
    scene.materials.add(name="mirror", class_name="mirror")
    room = scene.shapes.add(name="room", material="mirror", flip_normals=True)
    room.sphere.radius = 10
    transport = component("path", max_depth=-1, rr_depth=2**31 - 1)
    with LocalServer() as local, local.client() as own:
        job = own.submit(scene, spp=1, transport=transport, name="endless")
        time.sleep(1)
        start = memory_megabytes(local.pid, "VmRSS")
        time.sleep(4)
        grown = memory_megabytes(local.pid, "VmRSS") - start
        assert own.status(job).state == render_pb2.RUNNING
        own.cancel(job)
        assert own.wait(job, timeout=10).state == render_pb2.CANCELLED
        assert grown < 50, f"{grown:.0f} MB more in 4 s"


def test_a_batch_of_more_points_than_the_integrator_allows_fails_its_job_saying_so(
    client: Client,
) -> None:
    """A tile of 1024² pixels at 1024 samples a pass is 2^30 paths in one
    batch: gigabytes of path state the memory estimate never saw."""
    integrator = component("mean_sample", tile_size=1024, samples_per_pass=1024)
    status = client.wait(client.submit(small_scene(), spp=1024, integrator=integrator), timeout=60)
    assert status.state == render_pb2.FAILED
    assert "1073741824 points a batch, above 262144" in status.error, status.error


def test_an_sppm_radius_that_covers_the_scene_is_estimated_in_bounded_memory() -> None:
    """Each point's estimate pairs it with every photon within the radius;
    with a radius over the whole scene a batch held points × photons
    pairs (std::bad_alloc after 3 s at 2.8 GB under an 8 GB limit). They
    are weighed in runs of points now."""
    scene = small_scene()
    scene.film.width = scene.film.height = 16
    transport = component("sppm", initial_radius=1e6, photons_per_pass=1_000_000)
    with LocalServer() as local, local.client() as own:
        job = own.submit(scene, spp=1, transport=transport)
        status = own.wait(job, timeout=300)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert np.isfinite(own.image(job)).all()
        assert memory_megabytes(local.pid, "VmHWM") < 1500


def test_a_bdpt_deeper_than_its_limit_is_refused_at_submit(client: Client) -> None:
    options = render_pb2.RenderOptions(spp=2, transport=component("bdpt", max_depth=100_000))
    error = refusal(client, render_pb2.SubmitRequest(scene=small_scene(), options=options))
    assert "max_depth: 100000 is above 4096" in error.details(), error.details()


def test_the_camera_frame_must_not_be_degenerate(client: Client) -> None:
    scene = small_scene()
    scene.camera.up.CopyFrom(vec3(0, 0, -1))  # along the view direction
    error = refusal(client, submit_request(scene))
    assert "up is parallel" in error.details(), error.details()


def open_watches(client: Client, job: str, count: int) -> list[grpc.Call]:
    """``count`` Watch streams of ``job``, each answered once (so open on the server)."""
    streams = [
        client.render_service.Watch(render_pb2.WatchRequest(job_id=job), timeout=120)
        for _ in range(count)
    ]
    for stream in streams:
        assert next(stream).job_id == job
    return streams


def threads_of(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError(f"no thread count for process {pid}")


@pytest.fixture(scope="module")
def limited() -> Iterator[LocalServer]:
    """A yarfd whose per-user limits are small enough to reach in a test."""
    args = ["--max-queued-jobs-per-user", "2", "--max-instances-per-user", "3"]
    args += ["--max-running-jobs", "1", "--max-job-memory", "64M"]
    with LocalServer(extra_args=args) as local:
        yield local
        assert local.is_running(), local.log[-4000:]


def test_a_user_may_queue_only_so_many_jobs(
    limited: LocalServer, cornell_box: scene_pb2.Scene
) -> None:
    with limited.client() as client:
        first = client.submit(cornell_box, spp=1 << 20, name="long one")
        second = client.submit(cornell_box, spp=1 << 20, name="long two")
        with pytest.raises(grpc.RpcError) as caught:
            client.submit(small_scene(), spp=1, name="one too many")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "--max-queued-jobs-per-user" in caught.value.details()
        client.cancel(first)
        client.wait(first, timeout=30)
        third = client.submit(small_scene(), spp=1, name="room again")
        client.cancel(second)
        assert client.wait(third, timeout=60).state == render_pb2.SUCCEEDED


def test_a_job_that_would_need_more_memory_than_the_server_allows_is_refused(
    limited: LocalServer,
) -> None:
    with limited.client() as client:
        scene = small_scene()
        scene.film.width = scene.film.height = 1024  # about 320 MiB of film accumulators
        with pytest.raises(grpc.RpcError) as caught:
            client.submit(scene, spp=1, name="too large for this server")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "--max-job-memory" in caught.value.details() and "MiB" in caught.value.details()
        scene.film.width = scene.film.height = 64
        assert client.wait(client.submit(scene, spp=1), timeout=60).state == render_pb2.SUCCEEDED


def test_textures_count_as_the_images_they_decode(limited: LocalServer, tmp_path: Path) -> None:
    """Each bitmap texture decodes its own copy of its image: two textures
    of one 2048² RGB image (a file of a few kilobytes) are 96 MiB of
    texels, past this server's 64 MiB. Eight of an 8192² one took 5.6 GB
    before the job failed."""
    import OpenImageIO as oiio

    path = tmp_path / "flat.png"
    flat = oiio.ImageBuf(oiio.ImageSpec(2048, 2048, 3, oiio.UINT8))
    oiio.ImageBufAlgo.fill(flat, (0.5, 0.5, 0.5))
    assert flat.write(str(path)), flat.geterror()
    with limited.client() as client:
        digest = client.upload_asset(path)
        scene = small_scene()
        scene.film.width = scene.film.height = 16
        for name in ("first", "second"):
            texture = scene.textures.add(name=name)
            texture.texture.class_name = "bitmap"
            texture.texture.properties.values["asset"].string_value = digest
        with pytest.raises(grpc.RpcError) as caught:
            client.submit(scene, spp=1, name="two decoded images")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "images" in caught.value.details(), caught.value.details()
        del scene.textures[1]
        assert client.wait(client.submit(scene, spp=1), timeout=60).state == render_pb2.SUCCEEDED


def test_a_user_may_hold_only_so_many_instances(limited: LocalServer) -> None:
    with limited.client() as client:
        handles = [client.create("independent").handle for _ in range(3)]
        with pytest.raises(grpc.RpcError) as caught:
            client.create("independent")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        client.release(handles.pop())
        handles.append(client.create("independent").handle)
        for handle in handles:
            client.release(handle)


def test_a_thousand_open_watches_do_not_cost_a_thousand_threads(limited: LocalServer) -> None:
    with limited.client() as client:
        job = client.submit(small_scene(), spp=1, name="watched by many")
        client.wait(job, timeout=60)
        long_job = client.submit(small_scene(64), spp=1 << 20, name="watched while it runs")
        before = threads_of(limited.pid)
        streams = open_watches(client, long_job, 1000)
        during = threads_of(limited.pid)
        assert during - before < 50, (
            f"{before} threads before 1000 Watch streams, {during} with them"
        )
        for stream in streams:
            stream.cancel()
        client.cancel(long_job)


def test_a_user_may_open_only_so_many_watches() -> None:
    with (
        LocalServer(extra_args=["--max-watches-per-user", "20"]) as local,
        local.client() as client,
    ):
        job = client.submit(small_scene(64), spp=1 << 20, name="watched too often")
        streams = open_watches(client, job, 20)
        with pytest.raises(grpc.RpcError) as caught:
            next(client.render_service.Watch(render_pb2.WatchRequest(job_id=job), timeout=60))
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "--max-watches-per-user" in caught.value.details()
        streams.pop().cancel()
        deadline = time.monotonic() + 10
        while True:  # the cancelled stream's place comes free once the server has seen it end
            try:
                streams += open_watches(client, job, 1)
                break
            except grpc.RpcError as error:
                assert error.code() == grpc.StatusCode.RESOURCE_EXHAUSTED, error
                assert time.monotonic() < deadline, "a cancelled Watch kept its place"
                time.sleep(0.05)
        for stream in streams:
            stream.cancel()
        client.cancel(job)


def test_a_user_may_hold_only_so_many_asset_bytes() -> None:
    with (
        LocalServer(extra_args=["--max-asset-bytes-per-user", "1K"]) as local,
        local.client() as client,
    ):
        first = client.upload_asset(os.urandom(600))
        with pytest.raises(grpc.RpcError) as caught:
            client.upload_asset(os.urandom(600))
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "--max-asset-bytes-per-user" in caught.value.details()
        assert client.missing_assets([first]) == []


def asset_scene(digest: str) -> scene_pb2.Scene:
    scene = small_scene(32)
    shape = scene.shapes.add(name="uploaded", material="grey")
    shape.mesh.asset = digest
    shape.mesh.format = "obj"
    return scene


def test_assets_no_job_needs_are_collected_after_their_grace_period() -> None:
    mesh = b"v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n"
    with (
        LocalServer(extra_args=["--asset-grace-hours", "0"]) as local,
        local.client() as client,
    ):
        unused = client.upload_asset(mesh + b"# unused\n")
        needed = client.upload_asset(mesh + b"# needed\n")
        running = client.submit(asset_scene(needed), spp=1 << 20, name="needs its asset")
        # A job's end is when the server collects.
        assert (
            client.wait(client.submit(small_scene(), spp=1), timeout=60).state
            == render_pb2.SUCCEEDED
        )
        assert client.missing_assets([unused, needed]) == [unused]
        client.cancel(running)
        client.wait(running, timeout=30)
        assert client.missing_assets([needed]) == [needed]
        assert not list((local.state_path / "assets").glob(f"*/{needed}"))


def test_sigterm_stops_yarfd_within_five_seconds_while_it_shoots_photons(
    cornell_box: scene_pb2.Scene,
) -> None:
    local = LocalServer()
    local.start()
    try:
        with local.client() as client:
            start_shooting_photons(client, cornell_box, "photons at shutdown")
        asked = time.monotonic()
        code = local.stop(timeout=5.0)
        took = time.monotonic() - asked
        assert code == 0 and took < 5.0, (code, took, local.log[-2000:])
    finally:
        if local.is_running():
            local.kill()


def test_names_and_errors_stored_unbounded_or_not_utf8_are_mended_at_restart(
    tmp_path: Path,
) -> None:
    """A state folder of an older server, whose job name is 5 MiB with bytes that are not UTF-8."""
    state = tmp_path / "state"
    with LocalServer(state_dir=state) as local, local.client() as client:
        job = client.submit(small_scene(), spp=1, name="to be damaged")
        client.wait(job, timeout=60)
    with sqlite3.connect(state / "jobs.sqlite") as database:
        database.execute(
            "UPDATE jobs SET name = ?, error = ?",
            (b"\xff\xfe" + b"n" * (5 << 20), b"\xc3\x28" * (1 << 20)),
        )
    database.close()
    with LocalServer(state_dir=state) as local, local.client() as client:
        (status,) = client.list()
        assert len(status.name.encode()) <= 1024 and status.name.endswith("\u2026")
        assert len(status.error.encode()) <= 1024
        assert len(client.status(job).error.encode()) <= 64 << 10


def fan_mesh(fans: int, format: str) -> bytes:
    """``fans`` faces of 255 vertices each: 253 triangles apiece, a triangle
    every 4 bytes of OBJ or every byte of binary PLY (uchar indices)."""
    corners = [(math.cos(k / 41), math.sin(k / 41), 0.0) for k in range(255)]
    if format == "obj":
        face = "f " + " ".join(str(k + 1) for k in range(255)) + "\n"
        return ("".join(f"v {x} {y} {z}\n" for x, y, z in corners) + face * fans).encode()
    header = (
        "ply\nformat binary_little_endian 1.0\nelement vertex 255\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {fans}\nproperty list uchar uchar vertex_indices\nend_header\n"
    )
    positions = np.array(corners, dtype="<f4").tobytes()
    return header.encode() + positions + (bytes([255]) + bytes(range(255))) * fans


@pytest.mark.parametrize("format", ["obj", "ply"])
def test_a_small_mesh_file_of_many_triangles_is_measured_by_its_triangles(
    limited: LocalServer, format: str
) -> None:
    """A mesh's memory is its triangles' (the BVH's above all), not its
    file's: 2000 fans are 506 000 triangles, about 90 MiB, in 2 MB of OBJ or
    0.5 MB of PLY, which the estimate took for 8 or 2 MiB. Refused under a
    64 MiB limit; 100 fans render."""
    with limited.client() as client:
        scene = small_scene()
        fans = scene.shapes.add(name="fans", material="grey")
        fans.mesh.format = format
        fans.mesh.data = fan_mesh(2000, format)
        assert len(fans.mesh.data) < 2_200_000
        with pytest.raises(grpc.RpcError) as caught:
            client.submit(scene, spp=1, name="many triangles")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "--max-job-memory" in caught.value.details(), caught.value.details()
        fans.mesh.data = fan_mesh(100, format)
        assert client.wait(client.submit(scene, spp=1), timeout=60).state == render_pb2.SUCCEEDED


def test_a_gzip_mesh_is_inflated_at_submit_no_further_than_a_job_may_take(
    limited: LocalServer,
) -> None:
    """1 MB of gzip inflates to 1 GiB: counting its triangles at Submit
    stops at the job limit (64 MiB here), and the job is refused."""
    packer = zlib.compressobj(9, zlib.DEFLATED, 16 + 15)
    zeros = bytes(1 << 20)
    bomb = b"".join(packer.compress(zeros) for _ in range(1024)) + packer.flush()
    assert len(bomb) < 2 << 20
    with limited.client() as client:
        scene = small_scene()
        shape = scene.shapes.add(name="bomb", material="grey")
        shape.mesh.format = "ply"
        shape.mesh.data = bomb
        before = memory_megabytes(limited.pid, "VmHWM")
        with pytest.raises(grpc.RpcError) as caught:
            client.submit(scene, spp=1, name="gzip bomb")
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED, caught.value.details()
        assert memory_megabytes(limited.pid, "VmHWM") - before < 300


def test_instancing_a_million_copies_of_many_shapes_is_refused_before_it_takes_the_memory(
    client: Client, assert_still_renders: Callable[[], None]
) -> None:
    """999 × 1000 placements (under the limit of 10^6) of a group of 1000 spheres: 10^9 shapes."""
    scene = small_scene()
    many = scene.groups.add(name="many")
    for i in range(1000):
        ball = many.shapes.add(name=f"ball{i}", material="grey")
        ball.sphere.center.CopyFrom(vec3(i * 0.01, 0, 0))
        ball.sphere.radius = 0.001
    copies = scene.groups.add(name="copies")
    for _ in range(1000):
        copies.instances.add(group="many")
    for _ in range(999):
        scene.instances.add(group="copies")
    error = refusal(client, submit_request(scene))
    assert error.code() == grpc.StatusCode.RESOURCE_EXHAUSTED, error
    assert "--max-job-memory" in error.details(), error.details()
    assert_still_renders()


def test_uploads_running_at_once_count_against_the_asset_share() -> None:
    """Two 800 KiB uploads under a 1 MiB share: the second is refused while the first runs."""
    first, second = os.urandom(800 << 10), os.urandom(800 << 10)
    go_on = threading.Event()

    def slow_chunks() -> Iterator[asset_pb2.AssetChunk]:
        digest = hashlib.sha256(first).hexdigest()
        yield asset_pb2.AssetChunk(sha256=digest, size=len(first), data=first[:1024])
        go_on.wait(30)
        yield asset_pb2.AssetChunk(data=first[1024:])

    with (
        LocalServer(extra_args=["--max-asset-bytes-per-user", "1M"]) as local,
        local.client() as client,
    ):
        running = client.asset_service.Upload.future(slow_chunks(), timeout=60)
        time.sleep(0.5)  # the first chunk has arrived: its room is held
        with pytest.raises(grpc.RpcError) as caught:
            client.upload_asset(second)
        assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "uploads" in caught.value.details()
        go_on.set()
        assert running.result().stored


def test_a_second_yarfd_on_a_port_in_use_refuses_to_start(
    server: LocalServer, tmp_path: Path
) -> None:
    """Not two servers sharing one port by SO_REUSEPORT, clients alternating between them."""
    second = subprocess.run(
        [str(find_yarfd()), "--listen", server.address, "--state-dir", str(tmp_path / "state")],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert second.returncode != 0, second.stdout
    assert "cannot listen" in second.stderr, second.stderr
    assert server.is_running()


def test_instances_left_idle_make_room_when_their_user_needs_it() -> None:
    """A client that died holding its instances does not lock its user out for good."""
    args = ["--max-instances-per-user", "3", "--instance-idle-seconds", "1"]
    with LocalServer(extra_args=args) as local, local.client() as client:
        abandoned, _, used = (client.create("independent").handle for _ in range(3))
        time.sleep(1.5)
        client.describe(handle=used)  # in use: kept
        fresh = client.create("independent").handle
        with pytest.raises(grpc.RpcError) as caught:
            client.describe(handle=abandoned)
        assert caught.value.code() == grpc.StatusCode.NOT_FOUND
        assert client.describe(handle=used).class_name == "independent"
        assert client.describe(handle=fresh).class_name == "independent"


def test_an_integration_stops_calling_its_integrand_once_the_caller_has_gone(
    client: Client,
) -> None:
    calls: list[float] = []

    def integrand(points: np.ndarray) -> np.ndarray:
        calls.append(time.monotonic())
        return points.sum(axis=1)

    with serve_function(integrand, 2) as address:
        integrator = client.create("mean_sample").handle
        request = math_pb2.IntegrateRequest(
            handle=integrator,
            function_address=address,
            lower=[0.0, 0.0],
            upper=[1.0, 1.0],
            evaluations=1 << 36,
        )
        with pytest.raises(grpc.RpcError) as caught:
            math_pb2_grpc.IntegratorStub(client.channel).Integrate(request, timeout=1.0)
        assert caught.value.code() == grpc.StatusCode.DEADLINE_EXCEEDED
        gone = time.monotonic()
        time.sleep(2.0)
        late = [t for t in calls if t > gone + 1.0]
        assert calls and not late, f"{len(late)} calls of the integrand after its caller left"
        client.release(integrator)
