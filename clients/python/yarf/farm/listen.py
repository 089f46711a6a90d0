"""What the coordinator's listen address demands: yarfd's rules (server_credentials.cc).

Beyond loopback it serves TLS only and wants a token on every call; tokens
always need TLS. Everything is read and checked before the coordinator
connects to anything, so a wrong command line fails at once.
"""

from __future__ import annotations

import ipaddress
from dataclasses import dataclass
from pathlib import Path

import grpc

from yarf.farm.access import AccessError, TokenTable, read_token_file


def is_loopback(listen: str) -> bool:
    """Whether ``listen`` (HOST:PORT, [IPV6]:PORT, HOST or unix:PATH) is this machine only."""
    # An abstract socket (unix-abstract:) has no file permissions: any
    # process in the network namespace reaches it, so it is not "local".
    if listen.startswith("unix:"):
        return True
    host = listen[: listen.rfind(":")] if ":" in listen else listen
    if len(host) >= 2 and host[0] == "[" and host[-1] == "]":
        host = host[1:-1]
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class ListenSecurity:
    """Server credentials (None: plaintext) and the tokens (None: every caller is admin)."""

    credentials: grpc.ServerCredentials | None
    tokens: TokenTable | None


def _read_pem(path: Path, flag: str) -> bytes:
    try:
        data = path.read_bytes()
    except OSError:
        raise AccessError(f"cannot read {flag} {path}") from None
    if b"-----BEGIN " not in data:
        raise AccessError(f"{flag} {path} is not a PEM file")
    return data


def listen_security(
    listen: str, tls_cert: Path | None, tls_key: Path | None, tokens_file: Path | None
) -> ListenSecurity:
    """The credentials to serve ``listen`` with; AccessError when the flags fall short."""
    if (tls_cert is None) != (tls_key is None):
        missing = "--tls-cert FILE" if tls_cert is None else "--tls-key FILE"
        raise AccessError(f"--tls-cert and --tls-key go together: add {missing}")
    tls = tls_cert is not None
    # A token sent in plaintext can be read, and reused, by anyone on the way.
    if tokens_file is not None and not tls:
        raise AccessError("--tokens needs TLS: add --tls-cert FILE --tls-key FILE")
    if not is_loopback(listen) and not (tls and tokens_file is not None):
        missing_flags = []
        if not tls:
            missing_flags.append("--tls-cert FILE --tls-key FILE")
        if tokens_file is None:
            missing_flags.append("--tokens FILE")
        raise AccessError(
            f"--listen {listen} is reachable from other machines, which needs TLS and bearer "
            f"tokens: add {' '.join(missing_flags)} (or listen on 127.0.0.1 or unix:PATH)"
        )
    tokens = read_token_file(tokens_file) if tokens_file is not None else None
    if tls_cert is None or tls_key is None:
        return ListenSecurity(None, tokens)
    pair = (_read_pem(tls_key, "--tls-key"), _read_pem(tls_cert, "--tls-cert"))
    return ListenSecurity(grpc.ssl_server_credentials([pair]), tokens)
