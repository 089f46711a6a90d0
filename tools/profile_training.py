"""The training renders of a profile-guided build (the Makefile's `profile`).

An instrumented yarfd (built with YARF_PROFILE=generate) renders the
repository's scenes with the light transport methods users run most, at
small sizes: what it records is which branches and calls the hot loops
take, not how long they run, so a few seconds of each suffice. The
repository's own scenes only, so that a clone builds without anything
beside it.

Usage: profile_training.py BUILD/bin/yarfd
       profile_training.py --plugins   (the plugins the renders load, which
                                        are all the instrumented build needs)
"""

from __future__ import annotations

import sys
from pathlib import Path

from google.protobuf.message import Message

from yarf import LocalServer, component, load_scene
from yarf.scene import rgb
from yarf.v1 import scene_pb2

ROOT = Path(__file__).resolve().parent.parent
# (scene, transport or None for the scene's own, spp, film width, where
# fog is: "" nowhere, "everywhere" (camera included), or "in glass" (the
# glossy box's glass sphere, a medium behind a refracting boundary))
RENDERS: tuple[tuple[str, str | None, int, int, str], ...] = (
    ("cornell-box/scene.json", None, 16, 256, ""),
    ("cornell-box/glossy.json", None, 16, 128, ""),
    ("cornell-box/glossy.json", "bdpt", 8, 64, ""),
    ("cornell-box/glossy.json", "light", 16, 64, ""),
    ("cornell-box/scene.json", "volpath", 8, 64, "everywhere"),
    ("cornell-box/glossy.json", "bdpt", 4, 64, "everywhere"),
    ("cornell-box/glossy.json", "volpath", 16, 64, "in glass"),
    ("cornell-box/glossy.json", "bdpt", 4, 64, "in glass"),
    ("veach-mis/scene.json", None, 16, 256, ""),
)


def add_fog(scene: scene_pb2.Scene, where: str) -> None:
    """A scattering medium, everywhere or inside the glass sphere."""
    sigma_s = rgb(0.0015, 0.001, 0.0006) if where == "everywhere" else rgb(0.02, 0.015, 0.01)
    fog = component("homogeneous", sigma_a=rgb(0.0004), sigma_s=sigma_s, g=0.3)
    scene.media.add(name="fog", medium=fog)
    if where == "everywhere":
        scene.camera_medium = "fog"
        return
    next(shape for shape in scene.shapes if shape.name == "glass_sphere").interior = "fog"


def training_scene(name: str, fog: str) -> scene_pb2.Scene:
    """One render's scene, with its fog."""
    scene = load_scene(ROOT / "scenes" / name)
    if fog:
        add_fog(scene, fog)
    return scene


def class_names(message: Message) -> set[str]:
    """The component classes a message names, at any depth."""
    names: set[str] = set()
    for field, value in message.ListFields():
        if field.name == "class_name":
            names.add(value)
        elif isinstance(value, Message):
            names |= class_names(value)
        elif field.type == field.TYPE_MESSAGE:  # repeated, or a map
            items = value.values() if hasattr(value, "values") else value
            for item in items:
                if isinstance(item, Message):
                    names |= class_names(item)
    return names


def plugins() -> list[str]:
    """The plugins the training renders load: a plugin's build target is
    named after the class it registers."""
    names: set[str] = set()
    for name, transport, _, _, fog in RENDERS:
        names |= class_names(training_scene(name, fog)) | ({transport} if transport else set())
    return sorted(names)


def main() -> None:
    if sys.argv[1:] == ["--plugins"]:
        print(" ".join(plugins()))
        return
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    binary = Path(sys.argv[1]).resolve()
    plugins_folder = binary.parent.parent / "plugins"
    with (
        LocalServer(binary=binary, plugin_paths=[plugins_folder]) as server,
        server.client() as client,
    ):
        for name, transport, spp, width, fog in RENDERS:
            scene = training_scene(name, fog)
            height = scene.film.height * width // scene.film.width
            client.render(scene, spp=spp, seed=1, transport=transport, res=(width, height))
            method = transport or scene.transport.class_name
            print(f"trained on {name}{f' (fog {fog})' if fog else ''} with {method}", flush=True)


if __name__ == "__main__":
    main()
