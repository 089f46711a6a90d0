"""The component model and job bookkeeping seen from a client."""

from __future__ import annotations

import re
import struct
import time
import warnings

import grpc
import pytest
from conftest import ASSET_MESH, small_scene

from yarf import Client, SubmitWarning, component, properties, rgb
from yarf.v1 import render_pb2

SEMANTIC_VERSION = re.compile(r"^\d+\.\d+\.\d+")


def test_health_check_reports_serving(client: Client) -> None:
    assert client.health() == "SERVING"


def test_lambertian_describes_itself_as_a_surface_model(client: Client) -> None:
    info = client.describe("lambertian")
    assert info.class_name == "lambertian"
    assert "yarf.v1.SurfaceModel" in info.interfaces
    assert SEMANTIC_VERSION.match(info.version), info.version


def test_every_listed_class_has_a_version_and_an_interface(client: Client) -> None:
    classes = client.list_classes().classes
    names = {info.class_name for info in classes}
    for expected in ("lambertian", "phong", "mirror", "dielectric", "diffuse_area", "path"):
        assert expected in names, f"{expected} is not among the classes: {sorted(names)}"
    for info in classes:
        assert SEMANTIC_VERSION.match(info.version), f"{info.class_name}: version {info.version!r}"
        assert info.interfaces, f"{info.class_name} lists no interface"
        assert all(name.startswith("yarf.v1.") for name in info.interfaces), info


def test_describe_of_an_unknown_class_is_not_found(client: Client) -> None:
    with pytest.raises(grpc.RpcError) as caught:
        client.describe("no_such_class")
    assert caught.value.code() == grpc.StatusCode.NOT_FOUND, caught.value


def test_factory_creates_and_releases_an_instance(client: Client) -> None:
    reply = client.create("lambertian", properties(reflectance=rgb(0.5)))
    assert reply.handle != 0
    assert reply.info.class_name == "lambertian"
    assert client.describe(handle=reply.handle).class_name == "lambertian"
    client.release(reply.handle)
    with pytest.raises(grpc.RpcError) as caught:
        client.release(reply.handle)
    assert caught.value.code() == grpc.StatusCode.NOT_FOUND, caught.value


def test_factory_rejects_an_unknown_property_naming_it(client: Client) -> None:
    with pytest.raises(grpc.RpcError) as caught:
        client.create("lambertian", properties(reflectance=rgb(0.5), shininess_typo=2.0))
    assert caught.value.code() == grpc.StatusCode.INVALID_ARGUMENT, caught.value
    assert "shininess_typo" in str(caught.value.details())


def test_list_shows_submitted_jobs_newest_first(client: Client) -> None:
    first = client.submit(small_scene(), spp=1, seed=1, name="listed job one")
    second = client.submit(small_scene(), spp=1, seed=2, name="listed job two")
    for job_id in (first, second):
        assert client.wait(job_id, timeout=30).state == render_pb2.SUCCEEDED
    jobs = client.list()
    ids = [job.job_id for job in jobs]
    assert first in ids and second in ids
    assert ids.index(second) < ids.index(first)
    names = {job.job_id: job.name for job in jobs}
    assert names[first] == "listed job one" and names[second] == "listed job two"


def test_watch_streams_growing_progress_until_the_job_ends(client: Client) -> None:
    job_id = client.submit(small_scene(), spp=8, seed=1, name="watched")
    statuses = list(client.watch(job_id, timeout=30))
    assert statuses, "Watch sent nothing"
    assert statuses[-1].state == render_pb2.SUCCEEDED
    assert statuses[-1].samples_done == statuses[-1].samples_total == 8
    assert statuses[-1].percent == pytest.approx(100.0)
    done = [status.samples_done for status in statuses]
    assert done == sorted(done), done


def test_mesh_file_inside_the_asset_root_renders(client: Client) -> None:
    scene = small_scene()
    shape = scene.shapes.add(name="asset_triangle", material="grey")
    shape.mesh.file = ASSET_MESH
    job_id = client.submit(scene, spp=2, seed=1)
    status = client.wait(job_id, timeout=30)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_a_raw_result_too_large_to_send_is_refused_before_it_is_copied(client: Client) -> None:
    # Just over the 256 MiB a reply may carry as RAW (24 bytes a pixel);
    # its film takes about 1 GB while it renders.
    width, height = 3400, 3300
    scene = small_scene()
    scene.film.width, scene.film.height = width, height
    job_id = client.submit(scene, spp=1, name="too large for RAW")
    # Cancelled once its film exists: before, the job has no image at all
    # (FAILED_PRECONDITION) and there is nothing too large to refuse.
    deadline = time.monotonic() + 60
    while True:
        with pytest.raises(grpc.RpcError) as early:
            client.result(job_id)
        if early.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED:  # type: ignore[attr-defined]
            break
        assert time.monotonic() < deadline, "the job made no film"
        time.sleep(0.01)
    client.cancel(job_id)
    assert client.wait(job_id, timeout=120).state in (render_pb2.CANCELLED, render_pb2.SUCCEEDED)
    with pytest.raises(grpc.RpcError) as caught:
        client.result(job_id)
    assert caught.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED  # type: ignore[attr-defined]
    message = caught.value.details()  # type: ignore[attr-defined]
    assert f"{width}x{height}" in message and "EXR or PNG" in message, message
    png = client.result(job_id, render_pb2.GetResultRequest.PNG)
    assert png.image.startswith(b"\x89PNG")
    assert struct.unpack(">II", png.image[16:24]) == (width, height)


def test_submit_warns_of_sobol_at_a_count_between_powers_of_two(client: Client) -> None:
    """Sobol's points are best in powers of two; the reply says so, and
    the job runs as asked all the same."""
    with pytest.warns(SubmitWarning, match=r"'sobol' .* at 100 .* use 64 or 128"):
        job_id = client.submit(small_scene(4), spp=100)
    assert client.wait(job_id).state == render_pb2.SUCCEEDED
    with warnings.catch_warnings():
        warnings.simplefilter("error", SubmitWarning)
        client.submit(small_scene(4), spp=128)
        client.submit(small_scene(4), spp=100, sampler=component("independent"))
