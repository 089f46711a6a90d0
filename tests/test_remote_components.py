"""Components in other processes, end to end: a BSDF written in Python (and
in Go) renders the Cornell box through yarfd as the C++ one does; classes
are found by address, by the server's command line and by registration
with a lease; a component that crashes, hangs, disappears or answers
wrongly fails its job with an error naming it and the call, and yarfd and
every other job go on."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from concurrent import futures
from pathlib import Path

import grpc
import numpy as np
import pytest
from component_process import ComponentProcess
from conftest import CORNELL_BOX, REPO
from imagestats import block_z_test

from yarf import Client, LocalServer, RenderResult, load_scene
from yarf.v1 import component_pb2, component_pb2_grpc, render_pb2, scene_pb2

EXAMPLES = REPO / "components" / "python" / "examples"
FAULTY = Path(__file__).resolve().parent / "components" / "faulty.py"
GO_LAMBERTIAN = REPO / "build" / "go" / "bin" / "yarf-go-lambertian"
SIZE = 32
SPP = 64
FAMILY_ALPHA = 1e-3


def cornell_box(class_name: str = "", address: str = "") -> scene_pb2.Scene:
    """The shipped Cornell box at SIZE², its Lambertian materials made ``class_name``."""
    scene = load_scene(CORNELL_BOX)
    scene.film.width = scene.film.height = SIZE
    for material in scene.materials:
        if class_name and material.class_name == "lambertian":
            material.class_name = class_name
            material.address = address
    return scene


def render(
    client: Client, scene: scene_pb2.Scene, seed: int, **options: object
) -> render_pb2.JobStatus:
    job_id = client.submit(scene, SPP, seed, name="remote", **options)  # type: ignore[arg-type]
    return client.wait(job_id, timeout=300)


def assert_agrees(result: RenderResult, reference: RenderResult, label: str) -> None:
    """Every 4×4 block of ``result`` agrees with ``reference`` within noise."""
    test = block_z_test(
        result.pixels,
        result.variance,
        reference.pixels,
        reference.variance,
        block=4,
        family_alpha=FAMILY_ALPHA,
    )
    assert not test.failing.size, f"{label}:\n{test.report()}"


def assert_matches_in_process(client: Client, scene: scene_pb2.Scene, label: str) -> None:
    """Renders ``scene`` and the C++ Cornell box; they agree within noise."""
    status = render(client, scene, seed=1)
    assert status.state == render_pb2.SUCCEEDED, status.error
    remote = client.raw(status.job_id)
    reference = client.raw(render(client, cornell_box(), seed=2).job_id)
    assert_agrees(remote, reference, f"{label} vs C++ lambertian")
    assert np.allclose(remote.pixels.mean(), reference.pixels.mean(), rtol=0.03)


@pytest.fixture
def unix_address(tmp_path: Path) -> str:
    return f"unix:{tmp_path / 'component.sock'}"


@pytest.fixture
def python_lambertian(unix_address: str) -> Iterator[ComponentProcess]:
    with ComponentProcess.python(
        [f"{EXAMPLES / 'lambertian.py'}:Lambertian"], unix_address
    ) as process:
        yield process


def test_python_bsdf_over_a_unix_socket_renders_the_cornell_box_as_the_cpp_one(
    client: Client, python_lambertian: ComponentProcess
) -> None:
    scene = cornell_box("py_lambertian", python_lambertian.address)
    assert_matches_in_process(client, scene, "py_lambertian over a unix socket")


def test_python_bsdf_over_tcp_renders_the_cornell_box(client: Client) -> None:
    with ComponentProcess.python(
        [f"{EXAMPLES / 'lambertian.py'}:Lambertian"], "127.0.0.1:0"
    ) as process:
        assert process.address.startswith("127.0.0.1:") and not process.address.endswith(":0")
        status = render(client, cornell_box("py_lambertian", process.address), seed=1)
        assert status.state == render_pb2.SUCCEEDED, status.error
        assert client.image(status.job_id).mean() > 0


@pytest.mark.skipif(not GO_LAMBERTIAN.exists(), reason="the Go component is built by `make build`")
def test_go_bsdf_renders_the_cornell_box_as_the_cpp_one(client: Client, unix_address: str) -> None:
    with ComponentProcess([str(GO_LAMBERTIAN)], unix_address) as process:
        scene = cornell_box("go_lambertian", process.address)
        assert_matches_in_process(client, scene, "go_lambertian")


def test_yarf_render_takes_a_python_bsdf_by_address(
    python_lambertian: ComponentProcess, server: LocalServer, tmp_path: Path
) -> None:
    from yarf.cli import main

    output = tmp_path / "box.exr"
    code = main(
        [
            "render",
            str(CORNELL_BOX),
            "-o",
            str(output),
            "--spp",
            "4",
            "-q",
            "--material",
            f"lambertian=py_lambertian@{python_lambertian.address}",
            "--server",
            server.address,
        ]
    )
    assert code == 0 and output.stat().st_size > 0


def classes_of(client: Client) -> dict[str, component_pb2.ComponentInfo]:
    return {c.class_name: c for c in client.list_classes().classes}


def wait_for_class(client: Client, class_name: str, timeout: float = 10) -> None:
    """Until a starting component's registration has reached the server."""
    deadline = time.monotonic() + timeout
    while class_name not in classes_of(client) and time.monotonic() < deadline:
        time.sleep(0.1)


def test_a_registered_component_is_made_by_class_name_until_its_lease_runs_out(
    client: Client, server: LocalServer, unix_address: str
) -> None:
    target = f"{EXAMPLES / 'lambertian.py'}:Lambertian"
    with ComponentProcess.python(
        [target], unix_address, "--register", server.address, "--lease", "2"
    ) as process:
        wait_for_class(client, "py_lambertian")
        info = classes_of(client)["py_lambertian"]
        assert info.origin == f"remote {process.address}"
        assert list(info.interfaces) == ["yarf.v1.SurfaceModel"]
        # Renewed: still there after more than one lease period.
        time.sleep(3)
        assert "py_lambertian" in classes_of(client)
        status = render(client, cornell_box("py_lambertian"), seed=1)
        assert status.state == render_pb2.SUCCEEDED, status.error
        # Killed, it renews no more: dropped once the lease runs out.
        process.kill()
        time.sleep(2.5)
        assert "py_lambertian" not in classes_of(client)
        # A class no longer known is refused at Submit.
        with pytest.raises(grpc.RpcError) as error:
            render(client, cornell_box("py_lambertian"), seed=1)
        assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
        assert "unknown component class 'py_lambertian'" in error.value.details()  # type: ignore[attr-defined]


def test_a_component_stopped_cleanly_unregisters_at_once(
    client: Client, server: LocalServer, unix_address: str
) -> None:
    target = f"{EXAMPLES / 'lambertian.py'}:Lambertian"
    with ComponentProcess.python(
        [target], unix_address, "--register", server.address, "--lease", "600"
    ) as process:
        wait_for_class(client, "py_lambertian")
        assert "py_lambertian" in classes_of(client)
        process.stop()
        assert "py_lambertian" not in classes_of(client)


def test_the_server_command_line_names_component_processes(
    python_lambertian: ComponentProcess,
) -> None:
    with (
        LocalServer(extra_args=["--component", python_lambertian.address]) as local,
        local.client() as c,
    ):
        assert classes_of(c)["py_lambertian"].origin == f"remote {python_lambertian.address}"
        status = render(c, cornell_box("py_lambertian"), seed=1)
        assert status.state == render_pb2.SUCCEEDED, status.error


def test_registration_is_refused_for_a_taken_name_or_an_unreachable_address(
    client: Client, tmp_path: Path
) -> None:
    with ComponentProcess.python([f"{FAULTY}:WrongLength"], f"unix:{tmp_path / 'a.sock'}") as first:
        client.registry.Register(
            component_pb2.RegisterRequest(address=first.address, lease_seconds=60)
        )
        with ComponentProcess.python(
            [f"{FAULTY}:WrongLength"], f"unix:{tmp_path / 'b.sock'}"
        ) as second:
            with pytest.raises(grpc.RpcError) as taken:
                client.registry.Register(component_pb2.RegisterRequest(address=second.address))
            assert taken.value.code() == grpc.StatusCode.ALREADY_EXISTS
            assert "short_lambertian" in (taken.value.details() or "")
        client.registry.Unregister(component_pb2.UnregisterRequest(address=first.address))
    with pytest.raises(grpc.RpcError) as unreachable:
        client.registry.Register(
            component_pb2.RegisterRequest(address=f"unix:{tmp_path / 'nobody.sock'}")
        )
    assert unreachable.value.code() == grpc.StatusCode.FAILED_PRECONDITION
    # A built-in class cannot be taken over either.
    assert classes_of(client)["lambertian"].origin != "remote"


class OtherIdl(component_pb2_grpc.ComponentServicer, component_pb2_grpc.RegistryServicer):
    """A component of a future IDL: it serves yarf.v2.SurfaceModel."""

    INFO = component_pb2.ComponentInfo(
        class_name="future_bsdf", version="2.0.0", interfaces=["yarf.v2.SurfaceModel"]
    )

    def Describe(
        self, request: object, context: grpc.ServicerContext
    ) -> component_pb2.ComponentInfo:
        return self.INFO

    def ListClasses(
        self, request: object, context: grpc.ServicerContext
    ) -> component_pb2.ListClassesReply:
        return component_pb2.ListClassesReply(classes=[self.INFO])


def test_a_component_of_another_idl_version_is_refused_clearly(client: Client) -> None:
    other = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
    component_pb2_grpc.add_ComponentServicer_to_server(OtherIdl(), other)
    component_pb2_grpc.add_RegistryServicer_to_server(OtherIdl(), other)
    address = f"127.0.0.1:{other.add_insecure_port('127.0.0.1:0')}"
    other.start()
    try:
        with pytest.raises(grpc.RpcError) as refused:
            client.registry.Register(component_pb2.RegisterRequest(address=address))
        assert refused.value.code() == grpc.StatusCode.FAILED_PRECONDITION
        assert "yarf.v2.SurfaceModel" in (refused.value.details() or "")
        status = render(client, cornell_box("future_bsdf", address), seed=1)
        assert status.state == render_pb2.FAILED
        assert "yarf.v2.SurfaceModel" in status.error and "another IDL version" in status.error
    finally:
        other.stop(None)


# Fault isolation: (component class, options, what the error must say).
FAULTS = {
    "crash": ("Crashing", {}, ["UNAVAILABLE"]),
    "hang": ("Hanging", {"component_timeout": 1.0}, ["DEADLINE_EXCEEDED"]),
    "wrong length": ("WrongLength", {}, ["shape", "queries"]),
    "nan": ("NotANumber", {}, ["non-finite", "weight"]),
    "negative pdf": ("NegativePdf", {}, ["negative pdf"]),
}


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_faulty_component_fails_its_job_naming_itself_and_the_call(
    fault: str,
    client: Client,
    unix_address: str,
    assert_still_renders: Callable[[], None],
) -> None:
    class_target, options, words = FAULTS[fault]
    with ComponentProcess.python([f"{FAULTY}:{class_target}"], unix_address) as process:
        class_name = {
            "Crashing": "crashing_lambertian",
            "Hanging": "hanging_lambertian",
            "WrongLength": "short_lambertian",
            "NotANumber": "nan_lambertian",
            "NegativePdf": "negative_pdf_lambertian",
        }[class_target]
        scene = cornell_box(class_name, process.address)
        # Another job renders in process meanwhile, and is not disturbed.
        bystander = client.submit(cornell_box(), SPP, 5, name="bystander")
        started = time.monotonic()
        status = render(client, scene, seed=1, **options)
        assert status.state == render_pb2.FAILED
        assert f"component '{class_name}' at {process.address}" in status.error
        assert "SurfaceModel.Sample" in status.error
        for word in words:
            assert word in status.error, status.error
        assert time.monotonic() - started < 30
        assert client.wait(bystander, timeout=120).state == render_pb2.SUCCEEDED
    assert_still_renders()


def test_a_component_that_disappears_mid_job_fails_it(
    client: Client, python_lambertian: ComponentProcess
) -> None:
    scene = cornell_box("py_lambertian", python_lambertian.address)
    job_id = client.submit(scene, 4096, 1, name="vanishing")
    for status in client.watch(job_id, timeout=120):
        if status.samples_done >= 2:
            break
    python_lambertian.kill()
    status = client.wait(job_id, timeout=60)
    assert status.state == render_pb2.FAILED
    assert f"component 'py_lambertian' at {python_lambertian.address}" in status.error
    assert "UNAVAILABLE" in status.error


def test_a_job_that_asks_for_retries_survives_a_restarted_component(
    client: Client, unix_address: str, tmp_path: Path
) -> None:
    marker = tmp_path / "crashed-once"
    with ComponentProcess.python([f"{FAULTY}:Crashing"], unix_address) as process:
        scene = cornell_box("crashing_lambertian", process.address)
        for material in scene.materials:
            if material.class_name == "crashing_lambertian":
                material.properties.values["after"].int_value = 20
                material.properties.values["marker"].string_value = str(marker)
        job_id = client.submit(scene, SPP, 1, name="retried", component_retries=3)
        process.wait(timeout=120)  # the first crash
        assert marker.exists()
        process.start()  # restarted at the same address
        status = client.wait(job_id, timeout=300)
        assert status.state == render_pb2.SUCCEEDED, status.error
        retried = client.raw(job_id)
    reference = client.raw(render(client, cornell_box(), seed=2).job_id)
    assert_agrees(retried, reference, "the retried job's image")


def test_a_python_sampler_drives_a_render_through_yarfd(client: Client, unix_address: str) -> None:
    # Remote<Sampler>: the integrator asks the Python process for every
    # point it renders with; the image agrees with the in-process sampler's.
    scene = cornell_box()
    scene.film.width = scene.film.height = 8
    with ComponentProcess.python([f"{EXAMPLES / 'halton.py'}:Halton"], unix_address) as process:
        sampler = scene_pb2.ComponentSpec(class_name="py_halton", address=process.address)
        job_id = client.submit(scene, 16, 1, sampler=sampler, name="python sampler")
        status = client.wait(job_id, timeout=300)
        assert status.state == render_pb2.SUCCEEDED, status.error
        remote = client.raw(job_id)
    job_id = client.submit(scene, 64, 2, name="in-process sampler")
    assert client.wait(job_id, timeout=120).state == render_pb2.SUCCEEDED
    reference = client.raw(job_id)
    assert_agrees(remote, reference, "py_halton vs sobol")


def test_cancelling_a_job_ends_its_calls_to_a_hanging_component_at_once(
    client: Client, unix_address: str
) -> None:
    with ComponentProcess.python([f"{FAULTY}:Hanging"], unix_address) as process:
        job_id = client.submit(cornell_box("hanging_lambertian", process.address), SPP, 1)
        time.sleep(1.0)  # the job is now waiting on the component (deadline: 60 s)
        assert client.status(job_id).state == render_pb2.RUNNING
        cancelled = time.monotonic()
        client.cancel(job_id)
        status = client.wait(job_id, timeout=30)
        assert status.state == render_pb2.CANCELLED, status.error
        assert time.monotonic() - cancelled < 2
        process.kill()
