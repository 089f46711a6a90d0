"""Parameter schemas: what a class declares is what Describe, `yarf classes -v`
and docs/plugins.md say, and what Submit lets a scene give it."""

from __future__ import annotations

import subprocess
import sys
import time
from concurrent import futures
from pathlib import Path

import grpc
import pytest
from component_process import ComponentProcess
from conftest import small_scene

from yarf import Client, LocalServer
from yarf.class_reference import markdown_reference
from yarf.v1 import component_pb2, component_pb2_grpc, render_pb2, scene_pb2

REPO = Path(__file__).resolve().parents[1]
PLUGIN_REFERENCE = REPO / "docs" / "plugins.md"
EXAMPLES = REPO / "components" / "python" / "examples"
YARF = Path(sys.executable).parent / "yarf"


def metal_scene(**properties: component_pb2.Property) -> scene_pb2.Scene:
    """The small scene, its material a roughconductor with ``properties``."""
    scene = small_scene()
    material = scene.materials[0]
    material.name, material.class_name = "metal", "roughconductor"
    material.properties.Clear()
    for key, value in properties.items():
        material.properties.values[key].CopyFrom(value)
    for shape in scene.shapes:
        shape.material = "metal"
    return scene


def refusal(client: Client, scene: scene_pb2.Scene) -> str:
    with pytest.raises(grpc.RpcError) as error:
        client.submit(scene, 1)
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
    return str(error.value.details())  # type: ignore[attr-defined]


def test_describe_tells_the_declared_parameters(client: Client) -> None:
    info = client.describe("roughconductor")
    assert info.declares_parameters
    by_name = {p.name: p for p in info.parameters}
    assert list(by_name["distribution"].choices) == ["ggx", "beckmann"]
    assert by_name["distribution"].default_value == "ggx"
    assert by_name["specular_reflectance"].type == "rgb or texture"
    assert (by_name["specular_reflectance"].min, by_name["specular_reflectance"].max) == (0, 1)
    assert "Au" in by_name["material"].choices


def test_yarf_classes_v_shows_a_class_and_its_parameters(server: LocalServer) -> None:
    done = subprocess.run(
        [str(YARF), "classes", "-v", "roughconductor", "--server", server.address],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("roughconductor 1.0.0: Rough conductor")
    distribution = next(line for line in lines if line.split()[0] == "distribution")
    assert '"ggx"' in distribution and "ggx | beckmann" in distribution
    misspelt = subprocess.run(
        [str(YARF), "classes", "-v", "roughconducter", "--server", server.address],
        capture_output=True,
        text=True,
        check=False,
    )
    assert misspelt.returncode == 2
    assert "did you mean 'roughconductor'" in misspelt.stderr and "Traceback" not in misspelt.stderr


def test_a_misspelt_property_is_refused_at_submit_with_its_path(client: Client) -> None:
    message = refusal(client, metal_scene(alpah=component_pb2.Property(float_value=0.2)))
    assert message.startswith(
        "scene.materials[0] ('metal').properties.alpah: 'roughconductor' has no parameter 'alpah'; "
        "did you mean 'alpha'?"
    ), message


@pytest.mark.parametrize(
    ("key", "value", "said"),
    [
        ("distribution", component_pb2.Property(float_value=3), "must be string, not a float"),
        ("distribution", component_pb2.Property(string_value="gxx"), "did you mean 'ggx'?"),
        ("specular_reflectance", component_pb2.Property(float_value=2), "2 is above 1"),
        ("alpha", component_pb2.Property(float_value=-0.5), "-0.5 is below 0"),
        ("material", component_pb2.Property(string_value="Gold"), "is not one of"),
    ],
)
def test_an_ill_typed_or_out_of_range_property_is_refused_at_submit(
    client: Client, key: str, value: component_pb2.Property, said: str
) -> None:
    message = refusal(client, metal_scene(**{key: value}))
    assert message.startswith(f"scene.materials[0] ('metal').properties.{key}: "), message
    assert said in message, message


def test_declared_properties_render(client: Client) -> None:
    scene = metal_scene(
        alpha=component_pb2.Property(float_value=0.3),
        material=component_pb2.Property(string_value="Au"),
    )
    status = client.wait(client.submit(scene, 2), timeout=60)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_the_plugin_reference_matches_the_registry(client: Client) -> None:
    plugins = [c for c in client.list_classes().classes if not c.origin.startswith("remote ")]
    assert PLUGIN_REFERENCE.read_text() == markdown_reference(plugins), (
        "docs/plugins.md is not what the plugins declare: regenerate it with "
        "`yarf classes --markdown > docs/plugins.md` against a yarfd of this build"
    )


def registered(client: Client, class_name: str) -> component_pb2.ComponentInfo:
    """The class once a starting component's registration has reached the server."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        for info in client.list_classes().classes:
            if info.class_name == class_name:
                return info
        time.sleep(0.1)
    raise AssertionError(f"{class_name} did not register")


def test_a_python_component_declares_its_init_and_submit_checks_it(
    client: Client, server: LocalServer, tmp_path: Path
) -> None:
    target = f"{EXAMPLES / 'lambertian.py'}:Lambertian"
    with ComponentProcess.python(
        [target], f"unix:{tmp_path / 'c.sock'}", "--register", server.address
    ) as process:
        info = registered(client, "py_lambertian")
        assert info.declares_parameters
        assert [(p.name, p.type, p.default_value) for p in info.parameters] == [
            ("reflectance", "rgb", "0.5, 0.5, 0.5")
        ]
        scene = small_scene()
        scene.materials[0].class_name = "py_lambertian"
        scene.materials[0].properties.values["reflectanse"].float_value = 0.2
        message = refusal(client, scene)
        assert "properties.reflectanse: 'py_lambertian' has no parameter" in message, message
        assert "did you mean 'reflectance'?" in message
        process.stop()


class Lister(component_pb2_grpc.RegistryServicer):
    """A component process that lists one class, described as given."""

    def __init__(self, info: component_pb2.ComponentInfo) -> None:
        self.info = info

    def ListClasses(
        self, request: object, context: grpc.ServicerContext
    ) -> component_pb2.ListClassesReply:
        return component_pb2.ListClassesReply(classes=[self.info])


ODD_BSDF = component_pb2.ComponentInfo(
    class_name="odd_bsdf", version="1.0.0", interfaces=["yarf.v1.SurfaceModel"]
)
# A default its type cannot hold, and a capability there is none of.
MALFORMED_SCHEMA = component_pb2.ComponentInfo(
    declares_parameters=True,
    parameters=[component_pb2.ParameterInfo(name="roughness", type="float", default_value="x")],
)
UNKNOWN_CAPABILITY = component_pb2.ComponentInfo(capabilities=["pixel_local", "sample_pases"])


@pytest.mark.parametrize(
    ("description", "expected"),
    [
        (MALFORMED_SCHEMA, ("parameter 'roughness'", "'x' is not float")),
        (UNKNOWN_CAPABILITY, ("unknown capability 'sample_pases'", "sample_passes, pixel_local")),
    ],
)
def test_a_registration_yarf_cannot_check_is_refused(
    client: Client, description: component_pb2.ComponentInfo, expected: tuple[str, str]
) -> None:
    info = component_pb2.ComponentInfo()
    info.CopyFrom(ODD_BSDF)
    info.MergeFrom(description)
    other = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
    component_pb2_grpc.add_RegistryServicer_to_server(Lister(info), other)
    address = f"127.0.0.1:{other.add_insecure_port('127.0.0.1:0')}"
    other.start()
    try:
        with pytest.raises(grpc.RpcError) as refused:
            client.registry.Register(component_pb2.RegisterRequest(address=address))
        details = refused.value.details() or ""  # type: ignore[attr-defined]
        assert "describes its classes in a way yarf cannot check" in details, details
        for part in expected:
            assert part in details, details
        assert "odd_bsdf" not in [c.class_name for c in client.list_classes().classes]
    finally:
        other.stop(None)


def test_a_python_component_declares_its_capabilities(
    client: Client, server: LocalServer, tmp_path: Path
) -> None:
    """py_path declares pixel_local: yarfd lists it, and a job of it may be tiled."""
    target = f"{EXAMPLES / 'path.py'}:PathTracer"
    with ComponentProcess.python(
        [target], f"unix:{tmp_path / 'c.sock'}", "--register", server.address
    ) as process:
        assert list(registered(client, "py_path").capabilities) == ["pixel_local"]
        process.stop()


def test_the_python_sdk_refuses_an_unknown_capability() -> None:
    from yarf_component import Transport
    from yarf_component.component import check_component_class

    class Splatty(Transport):
        class_name = "py_splatty"
        capabilities = ("pixel_locale",)

        def dimensions(self) -> int:
            return 2

    with pytest.raises(TypeError, match=r"unknown capabilities \['pixel_locale'\]"):
        check_component_class(Splatty)
