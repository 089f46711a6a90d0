"""Serving component classes: one gRPC server per process."""

from __future__ import annotations

from collections.abc import Sequence
from concurrent import futures
from types import TracebackType
from typing import Self

import grpc

from yarf_component.channels import MESSAGE_OPTIONS, secure
from yarf_component.component_services import add_component_services
from yarf_component.host import Host
from yarf_component.interface_services import add_interface_services
from yarf_component.registration import Registration

WORKERS = 4
# A second process must not silently share a port with this one.
SERVER_OPTIONS = [*MESSAGE_OPTIONS, ("grpc.so_reuseport", 0)]


def _wildcard_to_loopback(host: str) -> str:
    return {"0.0.0.0": "127.0.0.1", "[::]": "[::1]", "": "127.0.0.1"}.get(host, host)


def bind(server: grpc.Server, listen: str) -> str:
    """Adds the listening port; returns the address callers reach it at (the real port)."""
    try:
        port = server.add_insecure_port(listen)
    except RuntimeError as error:
        raise OSError(f"cannot listen on {listen}: {error}") from None
    if listen.startswith("unix:"):
        if port == 0:
            raise OSError(f"cannot listen on {listen}")
        return listen
    if port == 0:
        raise OSError(f"cannot listen on {listen}")
    host = listen.rsplit(":", 1)[0]
    return f"{_wildcard_to_loopback(host)}:{port}"


class Running:
    """A serving component process: its ``address``, its ``host`` and the registration."""

    def __init__(
        self,
        server: grpc.Server,
        host: Host,
        address: str,
        registration: Registration | None,
    ) -> None:
        self.server = server
        self.host = host
        self.address = address
        self.registration = registration

    def stop(self, grace: float | None = 1.0) -> None:
        """Unregisters (best effort) and stops serving; calls in flight get ``grace`` seconds."""
        if self.registration is not None:
            self.registration.stop()
        self.server.stop(grace).wait()

    def wait(self, timeout: float | None = None) -> bool:
        """Blocks until the server stops; False when ``timeout`` ran out first."""
        return self.server.wait_for_termination(timeout)

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.stop()


def serve(
    classes: Sequence[type],
    listen: str,
    register: str | None = None,
    lease: int = 30,
    server: str | None = None,
    *,
    token: str = "",
    tls_ca: str = "",
) -> Running:
    """Serves ``classes`` on ``listen`` ("host:port", port 0 picks one, or "unix:/path").

    ``register``: a yarfd to register with (and renew every lease/3 seconds);
    ``server``: the yarfd whose job scenes transports call (default: the
    one registered with). ``token`` and ``tls_ca`` (its CA certificate, PEM)
    reach a yarfd that requires TLS and tokens; registering needs an admin token.
    """
    for yarfd in (register, server):
        if yarfd and (token or tls_ca):
            secure(yarfd, token=token, tls_ca=tls_ca)
    host = Host(classes, server_address=server or register)
    grpc_server = grpc.server(
        futures.ThreadPoolExecutor(max_workers=WORKERS, thread_name_prefix="yarf-component"),
        options=SERVER_OPTIONS,
    )
    add_component_services(host, grpc_server)
    add_interface_services(host, grpc_server)
    address = bind(grpc_server, listen)
    grpc_server.start()
    registration = None
    if register:
        registration = Registration(register, address, lease)
        registration.start()
    return Running(grpc_server, host, address, registration)
