"""Scene files: load a ``yarf.v1.Scene`` and make it self-contained.

A scene file is the ``Scene`` message in protobuf's JSON format (``.json``)
or text format (``.textproto``, ``.pbtxt``, ``.txtpb``). Mesh ``file``
references are resolved relative to the scene file's folder and inlined as
``data`` + ``format``, so that a remote server never reads a client's paths.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePath

from google.protobuf import json_format, text_format

from yarf.v1 import component_pb2, scene_pb2

MESH_FORMATS = ("obj", "ply")
JSON_SUFFIXES = (".json",)
TEXT_SUFFIXES = (".textproto", ".pbtxt", ".txtpb")


class SceneError(ValueError):
    """A scene file that cannot be read, parsed or made self-contained."""


@dataclass(frozen=True)
class Reference:
    """A property naming another object of the scene (``Property.reference``)."""

    name: str


PropertyValue = (
    bool
    | int
    | float
    | str
    | Reference
    | component_pb2.Vec3
    | component_pb2.Rgb
    | component_pb2.Transform
)


def load_scene(path: str | Path, *, inline_files: bool = True) -> scene_pb2.Scene:
    """Reads a scene file; with ``inline_files`` its mesh files become inline data."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"scene file {path} not found") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"cannot read scene file {path}: {error}") from None
    scene = parse_scene(text, path.suffix, source=str(path))
    if inline_files:
        inline_mesh_files(scene, path.parent)
    return scene


def parse_scene(text: str, suffix: str, *, source: str = "<scene>") -> scene_pb2.Scene:
    """Parses scene text; ``suffix`` (".json", ".textproto"...) chooses the syntax."""
    scene = scene_pb2.Scene()
    suffix = suffix.lower()
    try:
        if suffix in JSON_SUFFIXES:
            json_format.Parse(text, scene)
        elif suffix in TEXT_SUFFIXES:
            text_format.Parse(text, scene)
        else:
            expected = ", ".join(JSON_SUFFIXES + TEXT_SUFFIXES)
            raise SceneError(f"{source}: unknown scene file type {suffix!r} (expected {expected})")
    except (json_format.ParseError, text_format.ParseError) as error:
        raise SceneError(f"{source}: {error}") from None
    return scene


def inline_mesh_files(scene: scene_pb2.Scene, base_dir: str | Path) -> int:
    """Replaces every mesh ``file`` by its bytes; returns how many were inlined.

    Files are named relative to ``base_dir`` and must stay inside it.
    """
    base = Path(base_dir).resolve()
    inlined = 0
    for where, shape in iter_shapes(scene):
        if shape.WhichOneof("geometry") != "mesh":
            continue
        mesh = shape.mesh
        if mesh.WhichOneof("source") != "file":
            continue
        name = mesh.file
        mesh_format = _mesh_format(where, name, mesh.format)
        data = _read_mesh_file(where, base, name)
        mesh.data = data  # clears `file` (same oneof)
        mesh.format = mesh_format
        inlined += 1
    return inlined


def iter_shapes(scene: scene_pb2.Scene) -> Iterator[tuple[str, scene_pb2.SceneShape]]:
    """Every shape of the scene (world and groups) with a label for messages."""
    for index, shape in enumerate(scene.shapes):
        yield _label(f"shapes[{index}]", shape.name), shape
    for group_index, group in enumerate(scene.groups):
        group_label = _label(f"groups[{group_index}]", group.name)
        for index, shape in enumerate(group.shapes):
            yield _label(f"{group_label}.shapes[{index}]", shape.name), shape


def _label(position: str, name: str) -> str:
    return f"{position} ({name!r})" if name else position


def _mesh_format(where: str, name: str, declared: str) -> str:
    mesh_format = (declared or PurePath(name).suffix.lstrip(".")).lower()
    if mesh_format not in MESH_FORMATS:
        raise SceneError(
            f"{where}: mesh file {name!r}: unknown mesh format {mesh_format!r} "
            f"(set `format` to one of {', '.join(MESH_FORMATS)})"
        )
    return mesh_format


def _read_mesh_file(where: str, base: Path, name: str) -> bytes:
    relative = PurePath(name)
    if not name or relative.is_absolute():
        raise SceneError(
            f"{where}: mesh file {name!r} must be a path relative to the scene's folder {base}"
        )
    target = (base / relative).resolve()
    if not target.is_relative_to(base):
        raise SceneError(f"{where}: mesh file {name!r} is outside the scene's folder {base}")
    try:
        return target.read_bytes()
    except FileNotFoundError:
        raise SceneError(f"{where}: mesh file {name!r} not found (looked for {target})") from None
    except OSError as error:
        raise SceneError(f"{where}: cannot read mesh file {name!r}: {error}") from None


def vec3(x: float, y: float, z: float) -> component_pb2.Vec3:
    return component_pb2.Vec3(x=x, y=y, z=z)


def rgb(r: float, g: float | None = None, b: float | None = None) -> component_pb2.Rgb:
    """An RGB triple; ``rgb(v)`` is grey."""
    return component_pb2.Rgb(r=r, g=r if g is None else g, b=r if b is None else b)


def transform(matrix: Sequence[float] | Sequence[Sequence[float]]) -> component_pb2.Transform:
    """A Transform from a 4x4 matrix (row-major, column vectors) or 16 numbers."""
    values = [float(v) for row in matrix for v in _as_row(row)]
    if len(values) != 16:
        raise ValueError(f"a transform has 16 values, got {len(values)}")
    return component_pb2.Transform(m=values)


def _as_row(row: float | Sequence[float]) -> Sequence[float]:
    return [row] if isinstance(row, numbers.Real) else row


def property_value(value: PropertyValue) -> component_pb2.Property:
    """Wraps a Python value in the Property variant of its type."""
    if isinstance(value, bool):
        return component_pb2.Property(bool_value=value)
    if isinstance(value, numbers.Integral):
        return component_pb2.Property(int_value=int(value))
    if isinstance(value, numbers.Real):
        return component_pb2.Property(float_value=float(value))
    if isinstance(value, str):
        return component_pb2.Property(string_value=value)
    if isinstance(value, Reference):
        return component_pb2.Property(reference=value.name)
    if isinstance(value, component_pb2.Vec3):
        return component_pb2.Property(vec3_value=value)
    if isinstance(value, component_pb2.Rgb):
        return component_pb2.Property(rgb_value=value)
    if isinstance(value, component_pb2.Transform):
        return component_pb2.Property(transform_value=value)
    raise TypeError(f"no Property type for {type(value).__name__}")


def properties(**values: PropertyValue) -> component_pb2.Properties:
    """``properties(max_depth=6, reflectance=rgb(0.5))`` as a Properties message."""
    result = component_pb2.Properties()
    for key, value in values.items():
        result.values[key].CopyFrom(property_value(value))
    return result


def component(class_name: str, **values: PropertyValue) -> scene_pb2.ComponentSpec:
    """``component("path", max_depth=-1)`` as a ComponentSpec message."""
    return scene_pb2.ComponentSpec(class_name=class_name, properties=properties(**values))
