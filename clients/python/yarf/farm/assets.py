"""A farm's assets: mesh and texture files by SHA-256, in the NATS object store.

Clients upload them to the coordinator's AssetService as they would to a
yarfd's (``yarf render`` / ``yarf submit`` send what is missing), and
scenes name them by hash. Before a node submits a task to its yarfd, it
copies the assets the task's scene names that its yarfd lacks: a farm node
gets textures and mesh files the way a single server does, and no node
reads a client's paths.
"""

from __future__ import annotations

import hashlib
import re
import tempfile
from collections.abc import AsyncIterator, Sequence

import grpc
from nats.js.errors import NotFoundError
from nats.js.object_store import ObjectStore

from yarf.assets import asset_chunks
from yarf.v1 import asset_pb2, asset_pb2_grpc

SHA256 = re.compile(r"[0-9a-f]{64}")
# As yarfd: one asset is at most 2 GiB.
MAX_ASSET_BYTES = 2 << 30
# Uploads are kept in memory up to this size, beyond it in a temporary file.
SPOOL_BYTES = 64 << 20


class AssetError(ValueError):
    """An upload the farm refuses (INVALID_ARGUMENT): a malformed hash, an absurd
    size, or bytes that are not what the first message announced."""


class FarmAssets:
    """The assets bucket: what it holds, uploads into it, copies out to a yarfd."""

    def __init__(self, bucket: ObjectStore) -> None:
        self._bucket = bucket

    async def has(self, sha256: str) -> bool:
        try:
            await self._bucket.get_info(sha256)
        except NotFoundError:
            return False
        return True

    async def missing(self, hashes: Sequence[str]) -> list[str]:
        """The hashes the bucket lacks, in the order given; AssetError for a malformed one."""
        for digest in hashes:
            if not SHA256.fullmatch(digest):
                raise AssetError(f"'{digest[:80]}' is not a SHA-256 (64 lowercase hex digits)")
        return [digest for digest in hashes if not await self.has(digest)]

    async def store(self, chunks: AsyncIterator[asset_pb2.AssetChunk]) -> tuple[str, bool]:
        """Receives one upload; returns its hash and whether it was new. Nothing is
        kept unless its size and SHA-256 are the ones announced."""
        first = await anext(chunks, None)
        if first is None:
            raise AssetError("an upload needs at least one message")
        digest, size = first.sha256, first.size
        if not SHA256.fullmatch(digest):
            raise AssetError(f"'{digest[:80]}' is not a SHA-256 (64 lowercase hex digits)")
        if size > MAX_ASSET_BYTES:
            raise AssetError(f"asset {digest}: {size} bytes is more than {MAX_ASSET_BYTES}")
        hasher = hashlib.sha256()
        received = 0
        with tempfile.SpooledTemporaryFile(max_size=SPOOL_BYTES) as spool:
            chunk: asset_pb2.AssetChunk | None = first
            while chunk is not None:
                received += len(chunk.data)
                if received > size:
                    raise AssetError(f"asset {digest}: more than the {size} bytes announced")
                hasher.update(chunk.data)
                spool.write(chunk.data)
                chunk = await anext(chunks, None)
            if received != size:
                raise AssetError(f"asset {digest}: {received} bytes, not the {size} announced")
            if hasher.hexdigest() != digest:
                raise AssetError(f"asset {digest}: the bytes have SHA-256 {hasher.hexdigest()}")
            if await self.has(digest):
                return digest, False
            spool.seek(0)
            await self._bucket.put(digest, spool)  # type: ignore[arg-type]
        return digest, True

    async def copy_to(
        self, yarfd: asset_pb2_grpc.AssetServiceStub, hashes: Sequence[str], timeout: float
    ) -> int:
        """Uploads to ``yarfd`` the assets among ``hashes`` it lacks; returns how many."""
        if not hashes:
            return 0
        reply = await yarfd.Missing(
            asset_pb2.MissingAssetsRequest(sha256=list(hashes)), timeout=timeout
        )
        for digest in reply.sha256:
            with tempfile.NamedTemporaryFile() as file:
                await self._bucket.get(digest, writeinto=file)  # type: ignore[arg-type]
                file.flush()
                await yarfd.Upload(asset_chunks(file.name, digest), timeout=timeout)
        return len(reply.sha256)


class FarmAssetService(asset_pb2_grpc.AssetServiceServicer):
    """yarf.v1.AssetService on the coordinator: clients upload as to a yarfd."""

    def __init__(self, assets: FarmAssets) -> None:
        self._assets = assets

    async def Missing(
        self, request: asset_pb2.MissingAssetsRequest, context: grpc.aio.ServicerContext
    ) -> asset_pb2.MissingAssetsReply:
        try:
            missing = await self._assets.missing(list(request.sha256))
        except AssetError as error:
            await context.abort(grpc.StatusCode.INVALID_ARGUMENT, str(error))
            raise
        return asset_pb2.MissingAssetsReply(sha256=missing)

    async def Upload(
        self,
        request_iterator: AsyncIterator[asset_pb2.AssetChunk],
        context: grpc.aio.ServicerContext,
    ) -> asset_pb2.UploadAssetReply:
        try:
            digest, stored = await self._assets.store(request_iterator)
        except AssetError as error:
            await context.abort(grpc.StatusCode.INVALID_ARGUMENT, str(error))
            raise
        return asset_pb2.UploadAssetReply(sha256=digest, stored=stored)
