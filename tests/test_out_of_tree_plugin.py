"""A C++ plugin built outside yarf's tree, against an installed yarf.

`cmake --install` puts the interface headers, the helpers of
yarf/support/ and the CMake package (find_package(yarf): the target
yarf::interfaces and yarf_add_plugin) in a prefix. The example project
examples/grey_plugin builds a diffuse reflector against them, which yarfd
loads from --plugin-path and renders with exactly what its own lambertian
renders. A project of checks compiles every installed header on its own.
Plugins built against other interface headers, or refused once they
registered, are refused at load with a message, and yarfd serves on.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import small_scene

from yarf import Client, properties, rgb
from yarf.server import LocalServer

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build"

EXAMPLE = ROOT / "examples" / "grey_plugin"
CHECKS = Path(__file__).resolve().parent / "out_of_tree"


def run(*command: str | Path, cwd: Path | None = None) -> None:
    done = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True)
    assert done.returncode == 0, f"{command}:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"


@pytest.fixture(scope="module")
def plugins(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Folders of plugins built outside the tree against an installed yarf: the
    example project's, and the checks' (every header compiled, plugins to refuse)."""
    work = tmp_path_factory.mktemp("out-of-tree")
    prefix = work / "prefix"
    run("cmake", "--install", BUILD, "--prefix", prefix)
    assert (prefix / "include" / "yarf" / "interface_version.h").exists()
    folders = []
    for name, sources in (("example", EXAMPLE), ("checks", CHECKS)):
        built = work / name
        run("cmake", "-S", sources, "-B", built, "-G", "Ninja", f"-DCMAKE_PREFIX_PATH={prefix}")
        run("cmake", "--build", built)
        folders.append(built)
    for name in ("stale", "unversioned"):
        run(
            "c++",
            "-shared",
            "-fPIC",
            "-o",
            folders[1] / f"libyarf_{name}.so",
            CHECKS / f"{name}.cc",
        )
    return folders


def test_an_out_of_tree_plugin_renders_as_the_builtin_it_copies(plugins: list[Path]) -> None:
    with (
        LocalServer(plugin_paths=[BUILD / "plugins", *plugins]) as server,
        Client(server.address) as client,
    ):
        classes = client.list_classes()
        assert "oot_grey" in {c.class_name for c in classes.classes}
        scene = small_scene(16)
        builtin = client.render(scene, spp=8, seed=2).pixels
        for material in scene.materials:
            material.class_name = "oot_grey"
            material.properties.CopyFrom(properties(reflectance=rgb(0.5)))
        ours = client.render(scene, spp=8, seed=2).pixels
        np.testing.assert_allclose(ours, builtin, rtol=1e-5, atol=1e-7)
        failures = {Path(f.path).name: f.message for f in classes.plugin_errors}
    assert (
        "was built against yarf interface version 0123456789abcdef" in failures["libyarf_stale.so"]
    )
    assert "rebuild it" in failures["libyarf_stale.so"]
    assert "exports no yarf_interface_version" in failures["libyarf_unversioned.so"]


def test_plugins_refused_after_registering_leave_yarfd_serving(plugins: list[Path]) -> None:
    """yarfd unloads a plugin it refuses only once nothing of the plugin's is left:
    the factories it registered and the exception it threw."""
    with (
        LocalServer(plugin_paths=[BUILD / "plugins", *plugins]) as server,
        Client(server.address) as client,
    ):
        classes = client.list_classes()
        names = {c.class_name for c in classes.classes}
        failures = {Path(f.path).name: f.message for f in classes.plugin_errors}
        assert client.render(small_scene(8), spp=2, seed=1).pixels.shape == (8, 8, 3)
    assert "oot_unnamed" not in names and "oot_thrower" not in names
    assert "declares a parameter without a name" in failures["libyarf_oot_unnamed.so"]
    assert "the entry point gave up" in failures["libyarf_oot_thrower.so"]
