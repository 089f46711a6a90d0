"""How a client reaches a yarfd that requires TLS and bearer tokens.

A yarfd listening beyond loopback serves TLS only and wants a token on every
call (``authorization: Bearer TOKEN``). The token and the CA certificate
that signed the server's (or the server's own self-signed one) come from
the caller, else from the environment: ``YARF_TOKEN`` and ``YARF_TLS_CA``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import grpc

TOKEN_ENV = "YARF_TOKEN"
TLS_CA_ENV = "YARF_TLS_CA"


def resolve(token: str | None, tls_ca: str | Path | None) -> tuple[str, str]:
    """The token and CA path to use: the arguments, else the environment.

    ``None`` falls back to the environment; ``""`` means none, whatever it holds.
    """
    if token is None:
        token = os.environ.get(TOKEN_ENV, "")
    if tls_ca is None:
        tls_ca = os.environ.get(TLS_CA_ENV, "")
    return token, str(tls_ca)


def channel_credentials(token: str, tls_ca: str) -> grpc.ChannelCredentials | None:
    """TLS, with ``token`` on every call, when either is given; None: plaintext.

    Without ``tls_ca`` the server's certificate is checked against the system's CAs.
    """
    if not token and not tls_ca:
        return None
    try:
        root = Path(tls_ca).read_bytes() if tls_ca else None
    except OSError as error:
        raise OSError(f"cannot read the TLS CA certificate {tls_ca}: {error.strerror}") from None
    tls = grpc.ssl_channel_credentials(root_certificates=root)
    if not token:
        return tls
    return grpc.composite_channel_credentials(tls, grpc.access_token_call_credentials(token))


def open_channel(
    address: str,
    options: Sequence[tuple[str, Any]] = (),
    *,
    token: str | None = None,
    tls_ca: str | Path | None = None,
) -> grpc.Channel:
    """A channel to ``address``: secure when a token or CA is given (or in the environment)."""
    credentials = channel_credentials(*resolve(token, tls_ca))
    if credentials is None:
        return grpc.insecure_channel(address, options=list(options))
    return grpc.secure_channel(address, credentials, options=list(options))


def open_aio_channel(
    address: str,
    options: Sequence[tuple[str, Any]] = (),
    *,
    token: str | None = None,
    tls_ca: str | Path | None = None,
) -> grpc.aio.Channel:
    """``open_channel`` for asyncio code."""
    credentials = channel_credentials(*resolve(token, tls_ca))
    if credentials is None:
        return grpc.aio.insecure_channel(address, options=list(options))
    return grpc.aio.secure_channel(address, credentials, options=list(options))
