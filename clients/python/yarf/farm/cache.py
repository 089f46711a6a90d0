"""A node's disk cache of scenes, by sha256, bounded in size.

Files are named ``<sha256>.scene``; a file's mtime is its last use, so the
least recently used go first when the cache outgrows its limit. Several
nodes may share the folder: a file another node deleted meanwhile is a
miss, not an error.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import uuid
from pathlib import Path

log = logging.getLogger("yarf.farm.cache")

DEFAULT_CACHE_BYTES = 2 << 30
SUFFIX = ".scene"


class SceneCache:
    """Scenes in ``folder``, at most ``max_bytes`` of them (0: no limit)."""

    def __init__(self, folder: Path, max_bytes: int = DEFAULT_CACHE_BYTES) -> None:
        self.folder = folder
        self.max_bytes = max_bytes
        folder.mkdir(parents=True, exist_ok=True)

    def _path(self, scene_hash: str) -> Path:
        return self.folder / f"{scene_hash}{SUFFIX}"

    def get(self, scene_hash: str) -> bytes | None:
        """The scene's bytes if cached and intact, marking it used; else None."""
        path = self._path(scene_hash)
        try:
            data = path.read_bytes()
        except OSError:
            return None
        if hashlib.sha256(data).hexdigest() != scene_hash:
            return None
        with contextlib.suppress(OSError):
            os.utime(path)
        return data

    def put(self, scene_hash: str, data: bytes) -> None:
        """Stores the scene (whole or not at all), then trims the cache to its limit."""
        path = self._path(scene_hash)
        partial = path.with_suffix(f".{uuid.uuid4().hex[:8]}.part")
        partial.write_bytes(data)
        partial.replace(path)
        self.trim(keep=path)

    def trim(self, keep: Path | None = None) -> None:
        """Deletes the least recently used scenes until the rest fit; ``keep`` stays."""
        if self.max_bytes <= 0:
            return
        files: list[tuple[int, int, Path]] = []
        for path in self.folder.glob(f"*{SUFFIX}"):
            with contextlib.suppress(OSError):
                stat = path.stat()
                files.append((stat.st_mtime_ns, stat.st_size, path))
        total = sum(size for _, size, _ in files)
        for _, size, path in sorted(files):
            if total <= self.max_bytes:
                break
            if path == keep:
                continue  # the scene about to render, even alone over the limit
            with contextlib.suppress(OSError):
                path.unlink()
                log.info("scene cache: deleted %s (%d bytes)", path.name, size)
            total -= size
