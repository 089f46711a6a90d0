"""Assets by content hash: uploads to a real yarfd, scenes naming them, `yarf render`.

The server of this module keeps its state in a folder of its own, so the
tests can look at the files of the asset store.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import grpc
import numpy as np
import pytest
from conftest import small_scene
from google.protobuf import json_format

from yarf import Client, LocalServer, transform
from yarf.assets import CHUNK_BYTES, asset_chunks, sha256_of, upload_scene_assets
from yarf.v1 import asset_pb2, render_pb2, scene_pb2

QUAD_OBJ = b"v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n"
MAX_SIZE = 2 << 30


def local_server(state_dir: Path) -> LocalServer:
    """A yarfd keeping its state (and so its assets) in ``state_dir``; no asset root."""
    return LocalServer(state_dir=state_dir)


@pytest.fixture(scope="module")
def state_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("state")


@pytest.fixture(scope="module")
def asset_server(state_dir: Path) -> Iterator[LocalServer]:
    with local_server(state_dir) as local:
        yield local
        assert local.is_running(), f"yarfd died during the tests:\n{local.log[-4000:]}"


@pytest.fixture(scope="module")
def assets_client(asset_server: LocalServer) -> Iterator[Client]:
    with asset_server.client() as module_client:
        yield module_client


def unique_bytes(size: int = 64) -> bytes:
    """Bytes no other test uploads."""
    return os.urandom(size)


def stored_files(state_dir: Path) -> list[Path]:
    """Every file of the asset store, temporary files included."""
    return sorted(p for p in (state_dir / "assets").rglob("*") if p.is_file())


def upload_raw(client: Client, chunks: list[asset_pb2.AssetChunk]) -> asset_pb2.UploadAssetReply:
    return client.asset_service.Upload(iter(chunks), timeout=60)


def rpc_error(call: grpc.RpcError) -> tuple[grpc.StatusCode, str]:
    assert isinstance(call, grpc.Call)
    return call.code(), call.details() or ""


def scene_with_quad(mesh: scene_pb2.Mesh) -> scene_pb2.Scene:
    """The small scene with a quad in front of the ball, its mesh given by ``mesh``."""
    scene = small_scene()
    quad = scene.shapes.add(name="quad", material="grey")
    quad.mesh.CopyFrom(mesh)
    quad.to_world.CopyFrom(
        transform(np.array([[0.4, 0, 0, 0.3], [0, 0.4, 0, 0], [0, 0, 0.4, 2], [0, 0, 0, 1]]))
    )
    return scene


def test_an_uploaded_asset_is_no_longer_missing(assets_client: Client) -> None:
    data = unique_bytes()
    digest = sha256_of(data)
    assert assets_client.missing_assets([digest]) == [digest]
    assert assets_client.upload_asset(data) == digest
    assert assets_client.missing_assets([digest]) == []


def test_missing_lists_the_absent_hashes_in_the_order_asked(assets_client: Client) -> None:
    held = assets_client.upload_asset(unique_bytes())
    absent = [sha256_of(unique_bytes()) for _ in range(3)]
    asked = [absent[2], held, absent[0], absent[1]]
    assert assets_client.missing_assets(asked) == [absent[2], absent[0], absent[1]]


def test_the_same_bytes_uploaded_twice_are_stored_once(
    assets_client: Client, state_dir: Path
) -> None:
    data = unique_bytes(3 * CHUNK_BYTES // 2)
    digest = sha256_of(data)
    first = upload_raw(assets_client, list(asset_chunks(data, digest)))
    second = upload_raw(assets_client, list(asset_chunks(data, digest)))
    assert (first.sha256, first.stored) == (digest, True)
    assert (second.sha256, second.stored) == (digest, False)
    copies = [p for p in stored_files(state_dir) if digest in p.name]
    assert copies == [state_dir / "assets" / digest[:2] / digest]
    assert copies[0].read_bytes() == data


def test_bytes_that_do_not_match_the_hash_are_refused_and_not_kept(
    assets_client: Client, state_dir: Path
) -> None:
    data, claimed = unique_bytes(), sha256_of(unique_bytes())
    before = stored_files(state_dir)
    with pytest.raises(grpc.RpcError) as refused:
        upload_raw(assets_client, list(asset_chunks(data, claimed)))
    code, details = rpc_error(refused.value)
    assert code == grpc.StatusCode.INVALID_ARGUMENT
    assert claimed in details and sha256_of(data) in details, details
    assert stored_files(state_dir) == before
    assert assets_client.missing_assets([claimed, sha256_of(data)]) == [claimed, sha256_of(data)]


@pytest.mark.parametrize("size_error", [-1, +1], ids=["short", "long"])
def test_a_size_that_does_not_match_the_bytes_is_refused(
    assets_client: Client, state_dir: Path, size_error: int
) -> None:
    data = unique_bytes(100)
    digest = sha256_of(data)
    before = stored_files(state_dir)
    chunk = asset_pb2.AssetChunk(sha256=digest, size=len(data) + size_error, data=data)
    with pytest.raises(grpc.RpcError) as refused:
        upload_raw(assets_client, [chunk])
    assert rpc_error(refused.value)[0] == grpc.StatusCode.INVALID_ARGUMENT
    assert stored_files(state_dir) == before
    assert assets_client.missing_assets([digest]) == [digest]


@pytest.mark.parametrize(
    ("sha256", "size"),
    [
        ("A" * 64, 1),
        ("ab" * 31, 1),
        ("", 1),
        ("0" * 64, MAX_SIZE + 1),
    ],
    ids=["uppercase", "short", "empty", "over-2-GiB"],
)
def test_a_malformed_hash_or_an_absurd_size_is_refused_before_any_bytes(
    assets_client: Client, sha256: str, size: int
) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        upload_raw(assets_client, [asset_pb2.AssetChunk(sha256=sha256, size=size, data=b"x")])
    assert rpc_error(refused.value)[0] == grpc.StatusCode.INVALID_ARGUMENT


def test_a_chunk_over_4_mib_is_refused(assets_client: Client, state_dir: Path) -> None:
    data = unique_bytes((4 << 20) + 1)
    before = stored_files(state_dir)
    with pytest.raises(grpc.RpcError) as refused:
        upload_raw(
            assets_client, [asset_pb2.AssetChunk(sha256=sha256_of(data), size=len(data), data=data)]
        )
    code, details = rpc_error(refused.value)
    assert code == grpc.StatusCode.INVALID_ARGUMENT and "4 MiB" in details, details
    assert stored_files(state_dir) == before


def test_missing_refuses_a_malformed_hash(assets_client: Client) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        assets_client.missing_assets(["not-a-hash"])
    assert rpc_error(refused.value)[0] == grpc.StatusCode.INVALID_ARGUMENT


def test_a_20_mb_file_uploads_in_1_mib_chunks_and_round_trips(
    assets_client: Client, state_dir: Path, tmp_path: Path
) -> None:
    path = tmp_path / "big.bin"
    path.write_bytes(unique_bytes(20_000_000))
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    chunks = list(asset_chunks(path, digest))
    assert len(chunks) == -(-20_000_000 // CHUNK_BYTES)
    assert all(len(c.data) <= CHUNK_BYTES for c in chunks)
    assert (chunks[0].sha256, chunks[0].size) == (digest, 20_000_000)
    assert assets_client.upload_asset(path) == digest
    stored = state_dir / "assets" / digest[:2] / digest
    assert hashlib.sha256(stored.read_bytes()).hexdigest() == digest
    assert not list((state_dir / "assets" / "tmp").iterdir()), "a temporary file was left behind"


def test_a_mesh_named_by_its_hash_renders_the_same_image_as_the_inline_mesh(
    assets_client: Client,
) -> None:
    digest = assets_client.upload_asset(QUAD_OBJ)
    by_hash = scene_with_quad(scene_pb2.Mesh(asset=digest, format="obj"))
    inline = scene_with_quad(scene_pb2.Mesh(data=QUAD_OBJ, format="obj"))
    first = assets_client.render(by_hash, spp=4, seed=7, timeout=60).pixels
    second = assets_client.render(inline, spp=4, seed=7, timeout=60).pixels
    assert first.mean() > 0
    assert np.array_equal(first, second)
    # The quad is there: without it the image differs.
    assert not np.array_equal(first, assets_client.render(small_scene(), spp=4, seed=7).pixels)


def test_a_scene_naming_an_unknown_hash_is_refused_at_submit(assets_client: Client) -> None:
    unknown = sha256_of(unique_bytes())
    scene = scene_with_quad(scene_pb2.Mesh(asset=unknown, format="obj"))
    with pytest.raises(grpc.RpcError) as refused:
        assets_client.submit(scene, spp=1)
    code, details = rpc_error(refused.value)
    assert code == grpc.StatusCode.INVALID_ARGUMENT
    assert unknown in details and "quad" in details and "upload" in details, details


def test_a_mesh_asset_without_a_format_is_refused_at_submit(assets_client: Client) -> None:
    digest = assets_client.upload_asset(QUAD_OBJ)
    scene = scene_with_quad(scene_pb2.Mesh(asset=digest))
    with pytest.raises(grpc.RpcError) as refused:
        assets_client.submit(scene, spp=1)
    code, details = rpc_error(refused.value)
    assert code == grpc.StatusCode.INVALID_ARGUMENT and "format" in details, details


def test_upload_scene_assets_sends_each_missing_file_once(
    assets_client: Client, tmp_path: Path
) -> None:
    (tmp_path / "meshes").mkdir()
    mesh_bytes = QUAD_OBJ + f"# {os.urandom(8).hex()}\n".encode()
    (tmp_path / "meshes" / "quad.obj").write_bytes(mesh_bytes)
    inline_bytes = QUAD_OBJ + f"# {os.urandom(8).hex()}\n".encode()
    scene = small_scene()
    for name in ("a", "b"):
        scene.shapes.add(name=name, material="grey").mesh.file = "meshes/quad.obj"
    scene.shapes.add(name="c", material="grey").mesh.CopyFrom(
        scene_pb2.Mesh(data=inline_bytes, format="OBJ")
    )
    again = scene_pb2.Scene()
    again.CopyFrom(scene)

    assert upload_scene_assets(assets_client, scene, tmp_path) == 2
    meshes = [s.mesh for s in scene.shapes if s.HasField("mesh")]
    assert [m.asset for m in meshes] == [sha256_of(mesh_bytes)] * 2 + [sha256_of(inline_bytes)]
    assert all(m.format == "obj" and not m.file and not m.data for m in meshes)
    assert upload_scene_assets(assets_client, again, tmp_path) == 0
    assert again == scene


def test_upload_scene_assets_sends_a_file_beside_the_scene_folder(
    assets_client: Client, tmp_path: Path
) -> None:
    # The client reads what its user can read; the server gets only bytes.
    (tmp_path / "beside.obj").write_bytes(QUAD_OBJ)
    (tmp_path / "scene").mkdir()
    scene = small_scene()
    scene.shapes.add(name="beside", material="grey").mesh.file = "../beside.obj"
    upload_scene_assets(assets_client, scene, tmp_path / "scene")
    assert scene.shapes[-1].mesh.asset == sha256_of(QUAD_OBJ)
    assert not scene.shapes[-1].mesh.file


def test_yarf_render_uploads_the_mesh_files_to_a_server_without_asset_root(
    asset_server: LocalServer, assets_client: Client, tmp_path: Path
) -> None:
    mesh_bytes = QUAD_OBJ + f"# {os.urandom(8).hex()}\n".encode()
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "quad.obj").write_bytes(mesh_bytes)
    scene = scene_with_quad(scene_pb2.Mesh(file="meshes/quad.obj"))
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json_format.MessageToJson(scene))
    digest = sha256_of(mesh_bytes)
    assert assets_client.missing_assets([digest]) == [digest]

    output = tmp_path / "out.png"
    yarf = Path(sys.executable).parent / "yarf"
    command = [str(yarf), "render", str(scene_path), "-o", str(output), "--spp", "2"]
    command += ["--server", asset_server.address, "--quiet"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, f"yarf render failed ({run.returncode}):\n{run.stderr}"
    assert output.read_bytes()[:4] == b"\x89PNG"
    assert assets_client.missing_assets([digest]) == []


def test_an_asset_survives_a_restart_of_the_server(tmp_path: Path) -> None:
    data = QUAD_OBJ + f"# {os.urandom(8).hex()}\n".encode()
    digest = sha256_of(data)
    with local_server(tmp_path) as first, first.client() as client:
        client.upload_asset(data)
    with local_server(tmp_path) as second, second.client() as client:
        assert client.missing_assets([digest]) == []
        scene = scene_with_quad(scene_pb2.Mesh(asset=digest, format="obj"))
        job = client.wait(client.submit(scene, spp=1), timeout=60)
        assert job.state == render_pb2.SUCCEEDED, job.error


def test_concurrent_uploads_of_the_same_bytes_store_one_file(
    asset_server: LocalServer, state_dir: Path
) -> None:
    data = unique_bytes(2 * CHUNK_BYTES + 17)
    digest = sha256_of(data)

    def upload(_: int) -> bool:
        with asset_server.client() as own:
            return bool(upload_raw(own, list(asset_chunks(data, digest))).stored)

    with ThreadPoolExecutor(max_workers=6) as pool:
        stored = list(pool.map(upload, range(6)))
    assert stored.count(True) == 1, stored
    copies = [p for p in stored_files(state_dir) if digest in p.name]
    assert copies == [state_dir / "assets" / digest[:2] / digest]
    assert copies[0].read_bytes() == data


def test_an_upload_the_client_abandons_leaves_nothing(
    assets_client: Client, state_dir: Path
) -> None:
    data = unique_bytes(3 * CHUNK_BYTES)
    digest = sha256_of(data)
    before = stored_files(state_dir)

    def abandoned() -> Iterator[asset_pb2.AssetChunk]:
        chunks = asset_chunks(data, digest)
        yield next(chunks)
        raise RuntimeError("the client gives up")

    with pytest.raises(grpc.RpcError):
        assets_client.asset_service.Upload(abandoned(), timeout=60)
    assert assets_client.missing_assets([digest]) == [digest]
    # The server notices the end of the stream on its own thread.
    deadline = time.monotonic() + 10
    while stored_files(state_dir) != before and time.monotonic() < deadline:
        time.sleep(0.05)
    assert stored_files(state_dir) == before


def test_yarf_render_names_a_missing_mesh_file_before_asking_for_a_server(
    tmp_path: Path,
) -> None:
    scene = scene_with_quad(scene_pb2.Mesh(file="meshes/missing.obj"))
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json_format.MessageToJson(scene))
    command = [sys.executable, "-m", "yarf.cli", "render", str(scene_path)]
    command += ["-o", str(tmp_path / "out.png"), "--server", "127.0.0.1:1"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert run.returncode == 2, run.stderr
    assert "meshes/missing.obj" in run.stderr and "not found" in run.stderr, run.stderr
