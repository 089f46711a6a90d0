"""Access control: a yarfd with TLS and bearer tokens (alice and bob submit,
root admin) refuses callers without a valid token, keeps the registry to
admins and each job to its owner; and yarfd refuses to listen beyond
loopback without TLS and tokens."""

from __future__ import annotations

import itertools
import os
import subprocess
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

import grpc
import pytest
from component_process import ComponentProcess
from conftest import REPO, small_scene

from yarf import Client, LocalServer
from yarf.cli import main as yarf_main
from yarf.server import find_yarfd
from yarf.v1 import component_pb2, math_pb2, math_pb2_grpc, render_pb2, render_pb2_grpc, scene_pb2

HALTON = f"{REPO / 'components' / 'python' / 'examples' / 'halton.py'}:Halton"
AMBIENT_OCCLUSION = (
    f"{REPO / 'components' / 'python' / 'examples' / 'ambient_occlusion.py'}:AmbientOcclusion"
)
TOKENS = """\
# token       user   role
alice-secret  alice  submit
bob-secret    bob    submit
root-secret   root   admin   # may do everything
"""
ALICE, BOB, ROOT = "alice-secret", "bob-secret", "root-secret"
# How long yarfd may take to refuse a command line.
REFUSAL_TIMEOUT = 30.0


def code_of(error: pytest.ExceptionInfo[grpc.RpcError]) -> grpc.StatusCode:
    return error.value.code()  # type: ignore[attr-defined,no-any-return]


class Secrets:
    """A self-signed certificate for 127.0.0.1 and localhost, its key, a tokens file."""

    def __init__(self, folder: Path) -> None:
        self.cert = folder / "cert.pem"
        self.key = folder / "key.pem"
        self.tokens = folder / "tokens"
        subprocess.run(
            [
                "openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
                "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1",
                "-keyout", str(self.key), "-out", str(self.cert),
            ],
            check=True,
            capture_output=True,
        )  # fmt: skip
        self.tokens.write_text(TOKENS)

    def args(self, tokens: Path | None = None) -> list[str]:
        """yarfd's TLS and token flags."""
        return [
            "--tls-cert", str(self.cert), "--tls-key", str(self.key),
            "--tokens", str(tokens or self.tokens),
        ]  # fmt: skip


@pytest.fixture(scope="module")
def secrets(tmp_path_factory: pytest.TempPathFactory) -> Secrets:
    return Secrets(tmp_path_factory.mktemp("secrets"))


@pytest.fixture(scope="module")
def secured(secrets: Secrets, tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalServer]:
    """A yarfd on 127.0.0.1 with TLS and tokens, its own state folder."""
    state = tmp_path_factory.mktemp("state")
    args = [*secrets.args(), "--state-dir", str(state)]
    with LocalServer(extra_args=args, tls_ca=secrets.cert, token=ROOT) as server:
        yield server
        assert server.is_running(), f"yarfd died during the tests:\n{server.log[-4000:]}"


@pytest.fixture(scope="module")
def as_user(secured: LocalServer, secrets: Secrets) -> Iterator[dict[str, Client]]:
    """A client per token: "alice", "bob", "root"."""
    clients = {
        name: Client(secured.address, token=token, tls_ca=secrets.cert)
        for name, token in (("alice", ALICE), ("bob", BOB), ("root", ROOT))
    }
    yield clients
    for client in clients.values():
        client.close()


@pytest.fixture(scope="module")
def alice_job(as_user: dict[str, Client]) -> str:
    """A job of alice's, finished."""
    alice = as_user["alice"]
    job_id = alice.submit(small_scene(), spp=2, name="alice's")
    assert alice.wait(job_id, timeout=120).state == render_pb2.SUCCEEDED
    return job_id


def yarfd_refuses(args: Sequence[str], tmp_path: Path) -> str:
    """Runs yarfd with ``args``, expects it to exit 2 before serving; returns its message."""
    done = subprocess.run(
        [str(find_yarfd()), "--state-dir", str(tmp_path / "state"), *args],
        capture_output=True,
        text=True,
        timeout=REFUSAL_TIMEOUT,
    )
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    assert "listening" not in done.stdout
    return done.stderr


# Authentication.


def test_a_call_without_a_token_is_unauthenticated(secured: LocalServer, secrets: Secrets) -> None:
    with Client(secured.address, token="", tls_ca=secrets.cert) as anonymous:
        with pytest.raises(grpc.RpcError) as error:
            anonymous.list()
    assert code_of(error) == grpc.StatusCode.UNAUTHENTICATED


def test_an_unknown_token_is_unauthenticated(secured: LocalServer, secrets: Secrets) -> None:
    with Client(secured.address, token="guessed", tls_ca=secrets.cert) as stranger:
        with pytest.raises(grpc.RpcError) as error:
            stranger.submit(small_scene(), spp=1)
    assert code_of(error) == grpc.StatusCode.UNAUTHENTICATED


def test_a_plaintext_client_gets_no_answer(secured: LocalServer) -> None:
    with Client(secured.address, token="", tls_ca="", timeout=5) as plaintext:
        with pytest.raises(grpc.RpcError) as error:
            plaintext.list()
        assert not plaintext.is_serving()
    assert code_of(error) == grpc.StatusCode.UNAVAILABLE


def test_a_client_that_does_not_trust_the_certificate_gets_no_answer(
    secured: LocalServer,
) -> None:
    # The system's CAs did not sign the self-signed certificate.
    with Client(secured.address, token=ALICE, tls_ca="", timeout=5) as client:
        with pytest.raises(grpc.RpcError) as error:
            client.list()
    assert code_of(error) == grpc.StatusCode.UNAVAILABLE


def test_health_checks_need_no_token(secured: LocalServer, secrets: Secrets) -> None:
    with Client(secured.address, token="", tls_ca=secrets.cert) as anonymous:
        assert anonymous.health() == "SERVING"


def test_the_token_and_certificate_come_from_the_environment(
    secured: LocalServer, secrets: Secrets, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("YARF_TOKEN", ALICE)
    monkeypatch.setenv("YARF_TLS_CA", str(secrets.cert))
    with Client(secured.address) as client:
        assert client.list_classes().classes


# Roles.


def test_a_submit_token_submits_watches_and_fetches_its_job(
    as_user: dict[str, Client], alice_job: str
) -> None:
    alice = as_user["alice"]
    statuses = list(alice.watch(alice_job, timeout=30))
    assert statuses[-1].state == render_pb2.SUCCEEDED
    assert alice.image(alice_job).shape == (16, 16, 3)


def test_a_submit_token_may_not_load_plugins(as_user: dict[str, Client]) -> None:
    with pytest.raises(grpc.RpcError) as error:
        as_user["alice"].load_plugin("/nowhere/libplugin.so")
    assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED
    assert "admin" in error.value.details()  # type: ignore[attr-defined]


def test_an_admin_token_may_load_plugins(as_user: dict[str, Client]) -> None:
    # The path does not exist: the call gets past the token check and fails there.
    with pytest.raises(grpc.RpcError) as error:
        as_user["root"].load_plugin("/nowhere/libplugin.so")
    assert code_of(error) not in (
        grpc.StatusCode.PERMISSION_DENIED,
        grpc.StatusCode.UNAUTHENTICATED,
    )
    assert "/nowhere/libplugin.so" in error.value.details()  # type: ignore[attr-defined]


def test_a_submit_token_may_not_register_or_unregister_components(
    as_user: dict[str, Client],
) -> None:
    registry = as_user["bob"].registry
    with pytest.raises(grpc.RpcError) as register:
        registry.Register(component_pb2.RegisterRequest(address="127.0.0.1:1", lease_seconds=5))
    with pytest.raises(grpc.RpcError) as unregister:
        registry.Unregister(component_pb2.UnregisterRequest(address="127.0.0.1:1"))
    assert code_of(register) == grpc.StatusCode.PERMISSION_DENIED
    assert code_of(unregister) == grpc.StatusCode.PERMISSION_DENIED


def test_a_submit_token_may_list_classes(as_user: dict[str, Client]) -> None:
    assert any(info.class_name == "lambertian" for info in as_user["bob"].list_classes().classes)


def classes_of(client: Client, address: str) -> list[str]:
    """The classes the server makes in the component process at ``address``."""
    infos = client.list_classes().classes
    return [info.class_name for info in infos if info.origin == f"remote {address}"]


def eventually(check: Callable[[], bool], timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while not check():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def test_a_component_registers_with_an_admin_token(
    secured: LocalServer, secrets: Secrets, as_user: dict[str, Client]
) -> None:
    extra = ["--register", secured.address, "--lease", "5", "--ca", str(secrets.cert)]
    with ComponentProcess.python([HALTON], "127.0.0.1:0", *extra, "--token", ROOT) as process:
        assert eventually(lambda: bool(classes_of(as_user["bob"], process.address))), process.log


def test_a_component_with_a_submit_token_is_not_registered(
    secured: LocalServer, secrets: Secrets, as_user: dict[str, Client]
) -> None:
    extra = ["--register", secured.address, "--lease", "5", "--ca", str(secrets.cert)]
    with ComponentProcess.python([HALTON], "127.0.0.1:0", *extra, "--token", ALICE) as process:
        assert eventually(lambda: "PERMISSION_DENIED" in process.log), process.log
        assert not classes_of(as_user["root"], process.address)


def test_a_python_transport_calls_the_secured_server_back(
    secured: LocalServer, secrets: Secrets, as_user: dict[str, Client]
) -> None:
    # The transport reads the job's scene from yarfd over TLS with an admin
    # token; only an admin may name a component process by address.
    extra = ["--server", secured.address, "--token", ROOT, "--ca", str(secrets.cert)]
    with ComponentProcess.python([AMBIENT_OCCLUSION], "127.0.0.1:0", *extra) as process:
        transport = scene_pb2.ComponentSpec(
            class_name="py_ambient_occlusion", address=process.address
        )
        with pytest.raises(grpc.RpcError) as error:
            as_user["alice"].submit(small_scene(), spp=1, transport=transport)
        assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED
        assert "admin" in (error.value.details() or "")
        root = as_user["root"]
        job_id = root.submit(small_scene(), spp=1, transport=transport)
        status = root.wait(job_id, timeout=120)
    assert status.state == render_pb2.SUCCEEDED, status.error


def test_a_submitter_may_not_read_or_write_running_jobs_scenes(
    secured: LocalServer, secrets: Secrets
) -> None:
    # Scene handles name any user's running job; only admins' component
    # processes may use them.
    credentials = grpc.composite_channel_credentials(
        grpc.ssl_channel_credentials(secrets.cert.read_bytes()),
        grpc.access_token_call_credentials(ALICE),
    )
    with grpc.secure_channel(secured.address, credentials) as channel:
        for service, method in (
            ("SceneView", "Layout"),
            ("Intersect", "Intersect"),
            ("Shape", "Area"),
            ("SampleSurfaceArea", "Sample"),
            ("SampleSurfaceDirection", "Pdf"),
        ):
            call = channel.unary_unary(f"/yarf.v1.{service}/{method}")
            with pytest.raises(grpc.RpcError) as error:
                call(b"", timeout=10)
            assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED, service


# Ownership of jobs.


def test_another_submitter_may_not_fetch_watch_or_cancel_a_job(
    as_user: dict[str, Client], alice_job: str
) -> None:
    bob = as_user["bob"]
    for call in (
        lambda: bob.result(alice_job),
        lambda: bob.details(alice_job),
        lambda: bob.status(alice_job),
        lambda: bob.cancel(alice_job),
        lambda: bob.set_priority(alice_job, 90),
    ):
        with pytest.raises(grpc.RpcError) as error:
            call()
        assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED


def test_another_submitter_does_not_see_a_job_in_the_list(
    as_user: dict[str, Client], alice_job: str
) -> None:
    assert alice_job in [job.job_id for job in as_user["alice"].list()]
    assert alice_job not in [job.job_id for job in as_user["bob"].list()]


def test_one_connection_carries_one_users_token(
    secured: LocalServer, secrets: Secrets, alice_job: str
) -> None:
    # The server's auth context belongs to the connection: the first token
    # binds it, so another user's token on it must not act as the first.
    credentials = grpc.ssl_channel_credentials(secrets.cert.read_bytes())
    with grpc.secure_channel(secured.address, credentials) as channel:
        stub = render_pb2_grpc.RenderServiceStub(channel)
        request = render_pb2.GetResultRequest(job_id=alice_job)

        def get_result(token: str) -> render_pb2.GetResultReply:
            metadata = [("authorization", f"Bearer {token}")]
            return stub.GetResult(request, metadata=metadata, timeout=10)

        assert get_result(ALICE).status.job_id == alice_job
        for token in (BOB, ROOT):
            with pytest.raises(grpc.RpcError) as error:
                get_result(token)
            assert code_of(error) == grpc.StatusCode.UNAUTHENTICATED
            assert "one connection per token" in error.value.details()  # type: ignore[attr-defined]
        assert get_result(ALICE).status.job_id == alice_job


def test_an_admin_sees_every_job_and_cancels_any(as_user: dict[str, Client]) -> None:
    alice, root = as_user["alice"], as_user["root"]
    job_id = alice.submit(small_scene(64), spp=100000, name="long")
    assert job_id in [job.job_id for job in root.list()]
    root.cancel(job_id)
    assert alice.wait(job_id, timeout=60).state == render_pb2.CANCELLED


# Starting yarfd.


@pytest.mark.parametrize("listen", ["localhost:0", "[::1]:0", "127.0.0.2:0", "unix"])
def test_yarfd_serves_loopback_without_tls(listen: str, tmp_path: Path) -> None:
    if listen == "unix":
        listen = f"unix:{tmp_path / 'yarfd.sock'}"
    command = [str(find_yarfd()), "--listen", listen, "--state-dir", str(tmp_path / "state")]
    errors = tmp_path / "stderr"
    with (
        open(errors, "w") as stderr,
        subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, text=True) as yarfd,
    ):
        try:
            assert yarfd.stdout is not None
            first = yarfd.stdout.readline()
        finally:
            yarfd.terminate()
        assert yarfd.wait(REFUSAL_TIMEOUT) == 0
    assert first.startswith(f"yarfd listening on {listen} "), errors.read_text()


# The command line.


def test_the_yarf_command_takes_a_token_and_a_certificate(
    secured: LocalServer, secrets: Secrets, capsys: pytest.CaptureFixture[str]
) -> None:
    server = ["classes", "--server", secured.address]
    assert yarf_main(["--token", BOB, "--ca", str(secrets.cert), *server]) == 0
    assert "lambertian" in capsys.readouterr().out
    assert yarf_main(["--ca", str(secrets.cert), *server]) == 1
    assert "UNAUTHENTICATED" in capsys.readouterr().err


def test_yarfd_refuses_a_public_address_without_tls_and_tokens(tmp_path: Path) -> None:
    message = yarfd_refuses(["--listen", "0.0.0.0:0"], tmp_path)
    assert "--tls-cert FILE --tls-key FILE --tokens FILE" in message


def test_yarfd_refuses_a_public_address_with_tls_but_no_tokens(
    secrets: Secrets, tmp_path: Path
) -> None:
    args = ["--listen", "0.0.0.0:0", "--tls-cert", str(secrets.cert), "--tls-key", str(secrets.key)]
    message = yarfd_refuses(args, tmp_path)
    assert "add --tokens FILE" in message


def test_yarfd_refuses_an_abstract_unix_socket_without_tls_and_tokens(tmp_path: Path) -> None:
    # Abstract sockets have no file permissions: anyone on the machine may connect.
    message = yarfd_refuses(["--listen", f"unix-abstract:yarf-test-{tmp_path.name}"], tmp_path)
    assert "abstract socket" in message, message
    assert "add --tls-cert FILE --tls-key FILE --tokens FILE" in message, message


def test_yarfd_refuses_tokens_without_tls(secrets: Secrets, tmp_path: Path) -> None:
    message = yarfd_refuses(["--listen", "127.0.0.1:0", "--tokens", str(secrets.tokens)], tmp_path)
    assert "--tokens needs TLS" in message


def test_yarfd_serves_a_public_address_with_tls_and_tokens(
    secrets: Secrets, tmp_path: Path
) -> None:
    args = [*secrets.args(), "--listen", "0.0.0.0:0", "--state-dir", str(tmp_path / "state")]
    with LocalServer(extra_args=args, tls_ca=secrets.cert, token=BOB) as server:
        assert "0.0.0.0:0" in server.log
        with server.client() as client:
            assert client.list() == []


# Tokens-file lines yarfd and the farm coordinator refuse, with the complaint.
MALFORMED_TOKEN_LINES = [
    ("carol-secret carol", "expected `TOKEN USER ROLE`"),
    ("carol-secret carol submit extra", "expected `TOKEN USER ROLE`"),
    ("carol-secret carol owner", "role 'owner' is neither submit nor admin"),
    ("alice-secret carol submit", "this token is already given to alice"),
]


@pytest.mark.parametrize(("line", "complaint"), MALFORMED_TOKEN_LINES)
def test_yarfd_names_the_malformed_line_of_a_tokens_file(
    secrets: Secrets, tmp_path: Path, line: str, complaint: str
) -> None:
    tokens = tmp_path / "tokens"
    tokens.write_text(f"{TOKENS}\n{line}\n")
    message = yarfd_refuses(["--listen", "127.0.0.1:0", *secrets.args(tokens)], tmp_path)
    assert f"{tokens} line 6: {complaint}" in message
    assert "carol-secret" not in message


def test_yarfd_refuses_an_empty_tokens_file(secrets: Secrets, tmp_path: Path) -> None:
    tokens = tmp_path / "tokens"
    tokens.write_text("# nobody yet\n")
    message = yarfd_refuses(["--listen", "127.0.0.1:0", *secrets.args(tokens)], tmp_path)
    assert "holds no token" in message


# Ownership of what a user makes and uploads.


def test_an_instance_is_its_creators_alone(as_user: dict[str, Client]) -> None:
    alice, bob = as_user["alice"], as_user["bob"]
    handles = [alice.create("independent").handle for _ in range(3)]
    # Random, not counted: no user can guess the next handle from their own.
    assert all(abs(a - b) > 1 for a, b in itertools.pairwise(handles)), handles
    for handle in handles:
        with pytest.raises(grpc.RpcError) as described:
            bob.describe(handle=handle)
        with pytest.raises(grpc.RpcError) as released:
            bob.release(handle)
        assert code_of(described) == code_of(released) == grpc.StatusCode.NOT_FOUND
        assert alice.describe(handle=handle).class_name == "independent"
        alice.release(handle)


def test_a_submitter_may_not_make_yarfd_dial_an_address(as_user: dict[str, Client]) -> None:
    alice = as_user["alice"]
    integrator = alice.create("mean_sample").handle
    request = math_pb2.IntegrateRequest(
        handle=integrator, function_handle=1, function_address="127.0.0.1:1", evaluations=16
    )
    for call in (
        lambda: math_pb2_grpc.IntegratorStub(alice.channel).Integrate(request, timeout=30),
        lambda: math_pb2_grpc.RootFinderStub(alice.channel).FindRoot(
            math_pb2.FindRootRequest(function_handle=1, function_address="127.0.0.1:1"), timeout=30
        ),
    ):
        with pytest.raises(grpc.RpcError) as error:
            call()
        assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED
        assert "address" in error.value.details()  # type: ignore[attr-defined]


def test_an_asset_is_missing_to_users_who_did_not_upload_it(as_user: dict[str, Client]) -> None:
    alice, bob = as_user["alice"], as_user["bob"]
    mesh = b"v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n# " + os.urandom(8).hex().encode() + b"\n"
    digest = alice.upload_asset(mesh)
    assert alice.missing_assets([digest]) == []
    assert bob.missing_assets([digest]) == [digest]
    scene = small_scene()
    shape = scene.shapes.add(name="alice's mesh", material="grey")
    shape.mesh.asset = digest
    shape.mesh.format = "obj"
    with pytest.raises(grpc.RpcError) as error:
        bob.submit(scene, spp=1)
    assert code_of(error) == grpc.StatusCode.INVALID_ARGUMENT
    assert digest in error.value.details()  # type: ignore[attr-defined]
    # Sending every byte proves bob has them: then it is his too.
    assert bob.upload_asset(mesh) == digest
    assert bob.missing_assets([digest]) == []
    assert bob.wait(bob.submit(scene, spp=1), timeout=60).state == render_pb2.SUCCEEDED
