"""Access control and retention of the farm's coordinator, with real processes.

The coordinator takes yarfd's rules: TLS and bearer tokens (alice and bob
submit, root is admin), required beyond loopback; each job is its owner's.
Its one node renders on a yarfd that requires TLS and tokens too. Ended
jobs beyond --max-finished-jobs are deleted, at start and as jobs end.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import grpc
import pytest
from conftest import small_scene
from farm_processes import Coordinator, Farm, NatsServer
from test_access import (
    ALICE,
    BOB,
    MALFORMED_TOKEN_LINES,
    ROOT,
    TOKENS,
    Secrets,
    code_of,
)

from yarf import Client, LocalServer
from yarf.v1 import render_pb2

# Small tasks: a test job still makes several.
SPLIT_ARGS = ["--shares", "4", "--min-task-work", "256"]
NODE_TOKEN = "node-secret"
# How long the coordinator may take to refuse a command line.
REFUSAL_TIMEOUT = 60.0


@pytest.fixture(scope="module")
def secrets(tmp_path_factory: pytest.TempPathFactory) -> Secrets:
    return Secrets(tmp_path_factory.mktemp("secrets"))


@pytest.fixture(scope="module")
def node_yarfd(secrets: Secrets, tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalServer]:
    """The node's yarfd: TLS, and a tokens file of its own that knows the node only."""
    folder = tmp_path_factory.mktemp("node-yarfd")
    tokens = folder / "tokens"
    tokens.write_text(f"{NODE_TOKEN} farm-node submit\n{ROOT} root admin\n")
    args = [*secrets.args(tokens), "--state-dir", str(folder / "state"), "--threads", "1"]
    with LocalServer(extra_args=args, tls_ca=secrets.cert, token=ROOT) as server:
        yield server


@pytest.fixture(scope="module")
def farm(
    secrets: Secrets, node_yarfd: LocalServer, request: pytest.FixtureRequest
) -> Iterator[Farm]:
    """A coordinator with TLS and tokens, and one node on the secured yarfd."""
    failed_before = request.session.testsfailed
    args = [*SPLIT_ARGS, *secrets.args()]
    with Farm(coordinator_args=args, tls_ca=secrets.cert) as running:
        running.start_coordinator()
        node_args = ["--token", NODE_TOKEN, "--ca", str(secrets.cert)]
        running.start_node(yarfd=node_yarfd.address, yarfd_args=node_args)
        yield running
        if request.session.testsfailed > failed_before:
            print(running.log_tail())


@pytest.fixture(scope="module")
def as_user(farm: Farm) -> Iterator[dict[str, Client]]:
    """A client of the coordinator per token: "alice", "bob", "root"."""
    clients = {
        name: farm.client(token=token)
        for name, token in (("alice", ALICE), ("bob", BOB), ("root", ROOT))
    }
    yield clients
    for client in clients.values():
        client.close()


@pytest.fixture(scope="module")
def alice_job(as_user: dict[str, Client]) -> str:
    """A job of alice's, finished."""
    alice = as_user["alice"]
    job_id = alice.submit(small_scene(), spp=4, name="alice's")
    status = alice.wait(job_id, timeout=120)
    assert status.state == render_pb2.SUCCEEDED, status.error
    return job_id


# Authentication.


@pytest.mark.parametrize("token", ["", "guessed"])
def test_a_call_without_a_known_token_is_unauthenticated(
    farm: Farm, secrets: Secrets, token: str
) -> None:
    with farm.client(timeout=10, token=token) as client:
        for call in (client.list, lambda: client.submit(small_scene(), spp=1)):
            with pytest.raises(grpc.RpcError) as error:
                call()
            assert code_of(error) == grpc.StatusCode.UNAUTHENTICATED


def test_the_health_check_needs_no_token(farm: Farm) -> None:
    with farm.client(timeout=10, token="") as anonymous:
        assert anonymous.health() == "SERVING"


def test_a_plaintext_client_gets_no_answer(farm: Farm) -> None:
    assert farm.coordinator is not None
    with Client(farm.coordinator.address, token="", tls_ca="", timeout=5) as plaintext:
        with pytest.raises(grpc.RpcError) as error:
            plaintext.list()
        assert not plaintext.is_serving()
    assert code_of(error) == grpc.StatusCode.UNAVAILABLE


# Ownership of jobs.


def test_a_submitter_watches_and_fetches_its_job(
    as_user: dict[str, Client], alice_job: str
) -> None:
    alice = as_user["alice"]
    statuses = list(alice.watch(alice_job, timeout=30))
    assert statuses[-1].state == render_pb2.SUCCEEDED
    assert statuses[-1].owner == "alice"
    assert alice.image(alice_job).shape == (16, 16, 3)
    assert alice_job in [job.job_id for job in alice.list()]


def test_the_node_renders_as_its_own_user_on_the_secured_yarfd(
    node_yarfd: LocalServer, alice_job: str
) -> None:
    with node_yarfd.client() as root:
        owners = {job.owner for job in root.list()}
    assert owners == {"farm-node"}


def test_another_submitter_may_not_fetch_watch_cancel_or_reprioritize_a_job(
    as_user: dict[str, Client], alice_job: str
) -> None:
    bob = as_user["bob"]
    for call in (
        lambda: bob.result(alice_job),
        lambda: bob.status(alice_job),
        lambda: bob.cancel(alice_job),
        lambda: bob.set_priority(alice_job, 90),
    ):
        with pytest.raises(grpc.RpcError) as error:
            call()
        assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED
        assert "bob" in error.value.details()  # type: ignore[attr-defined]


def test_only_an_admin_may_name_a_component_process(as_user: dict[str, Client]) -> None:
    scene = small_scene()
    scene.materials[0].address = "127.0.0.1:1"
    with pytest.raises(grpc.RpcError) as error:
        as_user["alice"].submit(scene, spp=1)
    assert code_of(error) == grpc.StatusCode.PERMISSION_DENIED
    assert "admin" in error.value.details()  # type: ignore[attr-defined]
    # An admin's job is accepted (it fails on the node, where nothing listens).
    assert as_user["root"].submit(scene, spp=1)


def test_another_submitter_does_not_see_a_job_in_the_list(
    as_user: dict[str, Client], alice_job: str
) -> None:
    assert alice_job not in [job.job_id for job in as_user["bob"].list()]


def test_an_admin_sees_every_job_and_cancels_any(
    as_user: dict[str, Client], alice_job: str
) -> None:
    alice, root = as_user["alice"], as_user["root"]
    job_id = alice.submit(small_scene(64), spp=100000, name="long")
    assert {alice_job, job_id} <= {job.job_id for job in root.list()}
    root.cancel(job_id)
    assert alice.wait(job_id, timeout=60).state == render_pb2.CANCELLED


# Starting the coordinator.


def coordinator_refuses(args: list[str], tmp_path: Path) -> str:
    """Runs the coordinator with ``args``, expects exit 2 before it serves; returns stderr.

    The NATS URL leads nowhere: the checks come before NATS is reached.
    """
    command = [sys.executable, "-m", "yarf.farm", "coordinator", "--nats", "nats://127.0.0.1:1"]
    done = subprocess.run(
        [*command, "--state-dir", str(tmp_path / "state"), *args],
        capture_output=True,
        text=True,
        timeout=REFUSAL_TIMEOUT,
    )
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    assert "serving" not in done.stderr
    return done.stderr


def test_the_coordinator_refuses_a_public_address_without_tls_and_tokens(tmp_path: Path) -> None:
    message = coordinator_refuses(["--listen", "0.0.0.0:0"], tmp_path)
    assert "--listen 0.0.0.0:0 is reachable from other machines" in message
    assert "add --tls-cert FILE --tls-key FILE --tokens FILE" in message


def test_the_coordinator_refuses_an_abstract_unix_socket_without_tls_and_tokens(
    tmp_path: Path,
) -> None:
    message = coordinator_refuses(["--listen", "unix-abstract:yarf-farm-test"], tmp_path)
    assert "--tls-cert" in message


def test_the_coordinator_refuses_a_public_address_with_tls_but_no_tokens(
    secrets: Secrets, tmp_path: Path
) -> None:
    tls = ["--tls-cert", str(secrets.cert), "--tls-key", str(secrets.key)]
    message = coordinator_refuses(["--listen", "0.0.0.0:0", *tls], tmp_path)
    assert "add --tokens FILE" in message


@pytest.mark.parametrize(
    ("flags", "complaint"),
    [
        (["--tokens"], "--tokens needs TLS"),
        (["--tls-cert"], "--tls-cert and --tls-key go together: add --tls-key FILE"),
    ],
)
def test_the_coordinator_refuses_half_the_flags(
    secrets: Secrets, tmp_path: Path, flags: list[str], complaint: str
) -> None:
    files = {"--tokens": secrets.tokens, "--tls-cert": secrets.cert}
    args = [arg for flag in flags for arg in (flag, str(files[flag]))]
    assert complaint in coordinator_refuses(["--listen", "127.0.0.1:0", *args], tmp_path)


@pytest.mark.parametrize(("line", "complaint"), MALFORMED_TOKEN_LINES)
def test_the_coordinator_names_the_malformed_line_of_a_tokens_file(
    secrets: Secrets, tmp_path: Path, line: str, complaint: str
) -> None:
    tokens = tmp_path / "tokens"
    tokens.write_text(f"{TOKENS}\n{line}\n")
    message = coordinator_refuses(["--listen", "127.0.0.1:0", *secrets.args(tokens)], tmp_path)
    assert f"{tokens} line 6: {complaint}" in message
    assert "carol-secret" not in message


def test_the_coordinator_refuses_an_empty_tokens_file(secrets: Secrets, tmp_path: Path) -> None:
    tokens = tmp_path / "tokens"
    tokens.write_text("# nobody yet\n")
    message = coordinator_refuses(["--listen", "127.0.0.1:0", *secrets.args(tokens)], tmp_path)
    assert "holds no token" in message


def test_the_coordinator_serves_a_public_address_with_tls_and_tokens(
    secrets: Secrets, tmp_path: Path
) -> None:
    # A NATS of its own: two coordinators on one NATS would take each other's results.
    nats = NatsServer(tmp_path)
    # The second --listen wins over the helper's 127.0.0.1:0.
    args = [*secrets.args(), "--listen", "0.0.0.0:0"]
    try:
        public = Coordinator(nats.url, tmp_path / "state", tmp_path / "log", args, secrets.cert)
        try:
            with public.client(timeout=10, token=BOB) as bob:
                assert bob.list() == []
            assert "TLS and tokens" in public.log
        finally:
            public.stop()
    finally:
        nats.stop()


def test_a_node_with_a_token_yarfd_refuses_does_not_start(
    farm: Farm, node_yarfd: LocalServer, secrets: Secrets
) -> None:
    command = [sys.executable, "-m", "yarf.farm", "node", "--nats", farm.nats_url]
    command += ["--yarfd", node_yarfd.address, "--token", "guessed", "--ca", str(secrets.cert)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=REFUSAL_TIMEOUT)
    assert done.returncode != 0
    assert "yarfd refuses the node: UNAUTHENTICATED" in done.stderr
    assert "node ready" not in done.stderr


# Retention.


@pytest.fixture
def keeps_two(request: pytest.FixtureRequest) -> Iterator[Farm]:
    """A plaintext farm on loopback that keeps 2 ended jobs; its logs print on failure."""
    failed_before = request.session.testsfailed
    with Farm(coordinator_args=[*SPLIT_ARGS, "--max-finished-jobs", "2"]) as running:
        running.start_coordinator()
        running.start_node()
        yield running
        if request.session.testsfailed > failed_before:
            print(running.log_tail())


def test_only_the_newest_ended_jobs_are_kept(keeps_two: Farm) -> None:
    farm = keeps_two
    with farm.client() as client:
        jobs = []
        for number in range(3):
            jobs.append(client.submit(small_scene(), spp=2, name=f"job {number}"))
            assert client.wait(jobs[-1], timeout=120).state == render_pb2.SUCCEEDED
        assert [job.job_id for job in client.list()] == [jobs[2], jobs[1]]
        with pytest.raises(grpc.RpcError) as error:
            client.result(jobs[0])
        assert code_of(error) == grpc.StatusCode.NOT_FOUND
        assert client.image(jobs[1]).shape == (16, 16, 3)
    # At start too; and a deleted job's id is never given again.
    assert farm.coordinator is not None
    farm.coordinator.stop()
    farm.coordinator_args[-1] = "1"
    farm.start_coordinator()
    with farm.client() as client:
        assert [job.job_id for job in client.list()] == [jobs[2]]
        newer = client.submit(small_scene(), spp=1)
        assert newer not in jobs
        assert client.wait(newer, timeout=120).state == render_pb2.SUCCEEDED
        assert [job.job_id for job in client.list()] == [newer]
