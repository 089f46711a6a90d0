"""Scene files: load a ``yarf.v1.Scene`` and make it self-contained.

A scene file is the ``Scene`` message in protobuf's JSON format (``.json``)
or text format (``.textproto``, ``.pbtxt``, ``.txtpb``), or a scene of
another renderer — Mitsuba 3 XML (``.xml``) or pbrt-v4 (``.pbrt``) — which
the ``yarf-import`` tool of the build converts. Mesh ``file`` references are
resolved relative to the scene file's folder and inlined as ``data`` +
``format``, so that a remote server never reads a client's paths.
"""

from __future__ import annotations

import numbers
import os
import shutil
import subprocess
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePath

from google.protobuf import json_format, text_format

from yarf.v1 import component_pb2, scene_pb2

MESH_FORMATS = ("obj", "ply")
JSON_SUFFIXES = (".json",)
TEXT_SUFFIXES = (".textproto", ".pbtxt", ".txtpb")
# Scenes of other renderers, converted by yarf-import.
IMPORTED_SUFFIXES = (".xml", ".pbrt")


def is_imported_scene(path: Path) -> bool:
    """Whether yarf-import converts the file: Mitsuba's .xml or pbrt's .pbrt, either
    one also gzip-compressed (.pbrt.gz)."""
    suffixes = [suffix.lower() for suffix in path.suffixes[-2:]]
    if suffixes[-1:] == [".gz"]:
        suffixes = suffixes[:-1]
    return bool(suffixes) and suffixes[-1] in IMPORTED_SUFFIXES


YARF_IMPORT_ENV = "YARF_IMPORT"
# Where a build of this repository puts the importer: <repo>/build/bin/yarf-import.
REPO_YARF_IMPORT = Path(__file__).resolve().parents[3] / "build" / "bin" / "yarf-import"


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
    | component_pb2.FloatArray
)


@dataclass(frozen=True)
class ImportedScene:
    """A scene converted from another renderer's file by yarf-import."""

    scene: scene_pb2.Scene
    # Samples per pixel the file asks for; 0 when it does not say.
    sample_count: int = 0
    # "file:line: message", one per construct ignored or approximated.
    warnings: list[str] = field(default_factory=list)
    # The part of the film the file renders, as --crop takes it
    # ("x0,x1,y0,y1", pixels or fractions); "" for the whole film.
    crop: str = ""


def find_yarf_import() -> Path:
    """The yarf-import binary: $YARF_IMPORT, else this repository's build, else PATH."""
    from_env = os.environ.get(YARF_IMPORT_ENV)
    if from_env:
        path = Path(from_env)
        if not (path.is_file() and os.access(path, os.X_OK)):
            raise SceneError(f"{YARF_IMPORT_ENV}={from_env} is not an executable file")
        return path
    if REPO_YARF_IMPORT.is_file() and os.access(REPO_YARF_IMPORT, os.X_OK):
        return REPO_YARF_IMPORT
    on_path = shutil.which("yarf-import")
    if on_path:
        return Path(on_path)
    raise SceneError(
        f"cannot find yarf-import to read Mitsuba and pbrt scenes: set {YARF_IMPORT_ENV} to "
        f"its path, build the repository (expected at {REPO_YARF_IMPORT}) or put it on PATH"
    )


def import_scene(
    path: str | Path,
    *,
    parameters: Mapping[str, str] | None = None,
    inline_files: bool = True,
    strict: bool = False,
    confine: bool = False,
    timeout: float | None = None,
) -> ImportedScene:
    """Converts a Mitsuba 3 (.xml) or pbrt-v4 (.pbrt) file with yarf-import.

    ``parameters`` set Mitsuba's ``$name`` scene parameters (overriding the
    file's ``<default>``s). Mesh files are named relative to the file's
    folder; with ``inline_files`` they become inline data. ``strict``: any
    construct that would be ignored or approximated is a SceneError.
    ``confine``: the file may name only files inside its folder (for a
    scene from someone else: nothing else of this machine is read).
    ``timeout``: seconds the conversion may take, else a SceneError.
    """
    path = Path(path)
    command = [str(find_yarf_import()), str(path)]
    command += [*(["--strict"] if strict else []), *(["--confine"] if confine else [])]
    for name, value in (parameters or {}).items():
        command += ["-D", f"{name}={value}"]
    try:
        done = subprocess.run(command, capture_output=True, check=False, timeout=timeout)
    except OSError as error:
        raise SceneError(f"cannot run {command[0]}: {error}") from None
    except subprocess.TimeoutExpired:
        raise SceneError(f"{path}: reading the scene took more than {timeout:g} s") from None
    stderr = done.stderr.decode("utf-8", errors="replace").splitlines()
    if done.returncode != 0:
        prefix = "yarf-import: error: "
        errors = [line.removeprefix(prefix) for line in stderr if line.startswith(prefix)]
        message = errors[-1] if errors else f"yarf-import failed (exit status {done.returncode})"
        raise SceneError(message)
    warnings = [line.removeprefix("warning: ") for line in stderr if line.startswith("warning: ")]
    sample_count, crop = 0, ""
    for line in stderr:
        if line.startswith("info: sample_count "):
            sample_count = int(line.split()[-1])
        elif line.startswith("info: crop "):
            crop = line.split()[-1]
    scene = parse_scene(done.stdout.decode("utf-8"), ".json", source=str(path))
    if inline_files:
        inline_mesh_files(scene, path.parent)
    return ImportedScene(scene, sample_count, warnings, crop)


def load_scene(
    path: str | Path,
    *,
    inline_files: bool = True,
    parameters: Mapping[str, str] | None = None,
) -> scene_pb2.Scene:
    """Reads a scene file; with ``inline_files`` its mesh files become inline data.

    Mitsuba (.xml) and pbrt (.pbrt) files go through :func:`import_scene`
    (``parameters`` are Mitsuba's); use it directly for the warnings and the
    file's sample count.
    """
    path = Path(path)
    if is_imported_scene(path):
        return import_scene(path, parameters=parameters, inline_files=inline_files).scene
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


def write_scene(scene: scene_pb2.Scene, path: str | Path) -> None:
    """Writes ``scene`` as protobuf JSON (.json) or text (.textproto, .pbtxt, .txtpb)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in JSON_SUFFIXES:
        text = json_format.MessageToJson(scene, preserving_proto_field_name=True, indent=2) + "\n"
    elif suffix in TEXT_SUFFIXES:
        text = text_format.MessageToString(scene)
    else:
        expected = ", ".join(JSON_SUFFIXES + TEXT_SUFFIXES)
        raise SceneError(f"cannot write {path}: the extension must be one of {expected}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as error:
        raise SceneError(f"cannot write {path}: {error}") from None


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
    """The declared format, else the file's extension (before .gz: yarfd inflates
    gzip-compressed meshes)."""
    path = PurePath(name)
    if path.suffix.lower() == ".gz":
        path = PurePath(path.stem)
    mesh_format = (declared or path.suffix.lstrip(".")).lower()
    if mesh_format not in MESH_FORMATS:
        raise SceneError(
            f"{where}: mesh file {name!r}: unknown mesh format {mesh_format!r} "
            f"(set `format` to one of {', '.join(MESH_FORMATS)})"
        )
    return mesh_format


def mesh_file_path(where: str, base: Path, name: str) -> Path:
    """The file a mesh ``file`` names, relative to ``base`` (resolved).

    It may lie beside the scene's folder ("../meshes/x.obj"): the client
    reads what its user can read and sends the bytes; confining the paths a
    server is sent is the server's rule.
    """
    relative = PurePath(name)
    if not name or relative.is_absolute():
        raise SceneError(
            f"{where}: mesh file {name!r} must be a path relative to the scene's folder {base}"
        )
    return (base / relative).resolve()


def _read_mesh_file(where: str, base: Path, name: str) -> bytes:
    target = mesh_file_path(where, base, name)
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


def float_array(values: Iterable[float]) -> component_pb2.FloatArray:
    """A FloatArray (e.g. a grid's voxels given inline) from any iterable of numbers."""
    return component_pb2.FloatArray(values=[float(v) for v in values])


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
    if isinstance(value, component_pb2.FloatArray):
        return component_pb2.Property(float_array_value=value)
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
