"""Assets by content: mesh and texture files uploaded once to a yarfd, named by their SHA-256.

A scene then names a mesh by its hash (``Mesh.asset`` + ``format``)
instead of a path on the client (``Mesh.file``) or its bytes
(``Mesh.data``), and a texture's image by an ``asset`` property instead of
its ``filename``: a remote server never reads the client's paths, and
bytes the server already holds are not sent again.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from yarf.scene import MESH_FORMATS, SceneError, _mesh_format, iter_shapes, mesh_file_path
from yarf.v1 import asset_pb2, scene_pb2

if TYPE_CHECKING:
    from yarf.client import Client

# Bytes per upload message (the server takes up to 4 MiB) and per read.
CHUNK_BYTES = 1 << 20

# An asset's bytes, or the path of a file holding them.
AssetData = bytes | str | os.PathLike[str]


def sha256_of(source: AssetData) -> str:
    """The SHA-256 (64 lowercase hex digits) of bytes, or of a file read in chunks."""
    if isinstance(source, bytes):
        return hashlib.sha256(source).hexdigest()
    digest = hashlib.sha256()
    with open(source, "rb") as file:
        while block := file.read(CHUNK_BYTES):
            digest.update(block)
    return digest.hexdigest()


def asset_chunks(source: AssetData, sha256: str) -> Iterator[asset_pb2.AssetChunk]:
    """The messages of an upload: the first names the hash and size; a file is read lazily."""
    if isinstance(source, bytes):
        size = len(source)
        blocks: Iterator[bytes] = (
            source[start : start + CHUNK_BYTES] for start in range(0, size, CHUNK_BYTES)
        )
        yield from _with_header(blocks, sha256, size)
        return
    with open(source, "rb") as file:
        size = os.fstat(file.fileno()).st_size
        yield from _with_header(iter(lambda: file.read(CHUNK_BYTES), b""), sha256, size)


def _with_header(blocks: Iterator[bytes], sha256: str, size: int) -> Iterator[asset_pb2.AssetChunk]:
    first = next(blocks, b"")
    yield asset_pb2.AssetChunk(sha256=sha256, size=size, data=first)
    for block in blocks:
        yield asset_pb2.AssetChunk(data=block)


@dataclass
class SceneAssets:
    """A scene's mesh files, inline meshes and texture files, checked and hashed, not yet sent."""

    # The bytes, or the file, of each hash.
    sources: dict[str, AssetData] = field(default_factory=dict)
    # Each mesh of the scene to rename, with its hash and format.
    meshes: list[tuple[scene_pb2.Mesh, str, str]] = field(default_factory=list)
    # Each component file (a texture's or light's `filename`, a medium's
    # `NAME_filename`) that becomes an `asset`: the component, the key and the hash.
    files: list[tuple[scene_pb2.ComponentSpec, str, str]] = field(default_factory=list)

    def upload(self, client: Client) -> int:
        """Asks the server once which hashes it lacks, sends only those, then names
        every mesh and texture file by its hash; returns how many assets were sent."""
        missing = client.missing_assets(self.sources) if self.sources else []
        for digest in missing:
            client.upload_asset(self.sources[digest], sha256=digest)
        for mesh, digest, mesh_format in self.meshes:
            mesh.asset = digest  # clears `file` or `data` (same oneof)
            mesh.format = mesh_format
        for spec, key, digest in self.files:
            values = spec.properties.values
            del values[key]
            values[asset_key_of(key)].string_value = digest
        return len(missing)


def file_components(scene: scene_pb2.Scene) -> Iterator[tuple[str, scene_pb2.ComponentSpec]]:
    """The components of ``scene`` that may read files of their own (textures'
    images, environment maps, media's grids), each with where it is for errors."""
    for index, texture in enumerate(scene.textures):
        yield f"textures[{index}] ({texture.name})", texture.texture
    for index, light in enumerate(scene.lights):
        yield f"lights[{index}] ({light.name or light.emitter.class_name})", light.emitter
    for index, medium in enumerate(scene.media):
        yield f"media[{index}] ({medium.name})", medium.medium


def _is_key(key: str, word: str) -> bool:
    return key == word or key.endswith("_" + word)


def is_file_key(key: str) -> bool:
    """Whether a component's property names a file: ``filename``, or
    ``NAME_filename`` for components that read several."""
    return _is_key(key, "filename")


def is_asset_key(key: str) -> bool:
    """Whether a component's property names an uploaded asset: ``asset`` or ``NAME_asset``."""
    return _is_key(key, "asset")


def asset_key_of(file_key: str) -> str:
    """The ``asset`` key that stands for a file key."""
    return file_key[: -len("filename")] + "asset"


def scene_assets(scene: scene_pb2.Scene, base_dir: str | Path) -> SceneAssets:
    """Checks and hashes the mesh ``file`` and ``data`` and the texture files of
    ``scene``; raises SceneError.

    Mesh files and textures' ``filename`` are relative to ``base_dir`` and
    may lie anywhere its user can read (scenes share mesh and texture
    folders): only their bytes reach the server. Each file is read here only to hash it (and
    again, in chunks, if it is sent).
    """
    base = Path(base_dir).resolve()
    assets = SceneAssets()
    hashes_of_files: dict[Path, str] = {}
    for where, spec in file_components(scene):
        for key, value in spec.properties.values.items():
            if not is_file_key(key) or value.WhichOneof("value") != "string_value":
                continue
            path = (base / value.string_value).resolve()
            if path not in hashes_of_files:
                hashes_of_files[path] = _hash_file(where, value.string_value, path, "file")
            assets.sources.setdefault(hashes_of_files[path], path)
            assets.files.append((spec, key, hashes_of_files[path]))
    for where, shape in iter_shapes(scene):
        if shape.WhichOneof("geometry") != "mesh":
            continue
        mesh = shape.mesh
        source = mesh.WhichOneof("source")
        if source == "file":
            mesh_format = _mesh_format(where, mesh.file, mesh.format)
            path = mesh_file_path(where, base, mesh.file)
            if path not in hashes_of_files:
                hashes_of_files[path] = _hash_file(where, mesh.file, path, "mesh")
            digest = hashes_of_files[path]
            assets.sources.setdefault(digest, path)
        elif source == "data":
            mesh_format = mesh.format.lower()
            if mesh_format not in MESH_FORMATS:
                raise SceneError(
                    f"{where}: inline mesh data needs `format`, one of {', '.join(MESH_FORMATS)}"
                )
            data = bytes(mesh.data)
            digest = sha256_of(data)
            assets.sources.setdefault(digest, data)
        else:
            continue
        assets.meshes.append((mesh, digest, mesh_format))
    return assets


def scene_asset_hashes(scene: scene_pb2.Scene) -> list[str]:
    """The hashes of the uploaded assets ``scene`` names (meshes' ``asset`` and
    textures' ``asset`` property), each once, in the order first named."""
    hashes: dict[str, None] = {}
    for _, spec in file_components(scene):
        for key, value in spec.properties.values.items():
            if is_asset_key(key) and value.WhichOneof("value") == "string_value":
                hashes[value.string_value] = None
    for _, shape in iter_shapes(scene):
        if shape.WhichOneof("geometry") == "mesh" and shape.mesh.WhichOneof("source") == "asset":
            hashes[shape.mesh.asset] = None
    return list(hashes)


def upload_scene_assets(client: Client, scene: scene_pb2.Scene, base_dir: str | Path) -> int:
    """Makes every mesh ``file``, inline mesh ``data`` and texture file of ``scene``
    an uploaded ``asset``.

    Files are named relative to ``base_dir`` (see :func:`scene_assets`). The
    server is asked once which hashes it lacks and only those are sent;
    returns how many assets were sent. The scene changes only once every
    upload succeeded.
    """
    return scene_assets(scene, base_dir).upload(client)


def _hash_file(where: str, name: str, path: Path, kind: str) -> str:
    try:
        return sha256_of(path)
    except FileNotFoundError:
        raise SceneError(f"{where}: {kind} file {name!r} not found (looked for {path})") from None
    except OSError as error:
        raise SceneError(f"{where}: cannot read {kind} file {name!r}: {error}") from None
