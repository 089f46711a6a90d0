"""One gRPC channel per address, shared by every call this process makes."""

from __future__ import annotations

import threading

import grpc

from yarf.credentials import open_channel

# Batches of rays and points are large messages.
MAX_MESSAGE_BYTES = 256 * 1024 * 1024
MESSAGE_OPTIONS = [
    ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
    ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
]

_channels: dict[str, grpc.Channel] = {}
# Token and CA certificate of the addresses that want TLS (a yarfd beyond loopback).
_secured: dict[str, tuple[str, str]] = {}
_lock = threading.Lock()


def secure(address: str, *, token: str = "", tls_ca: str = "") -> None:
    """Makes the channel to ``address`` TLS (checked against ``tls_ca``, else the
    system's CAs), with ``token`` on every call."""
    with _lock:
        _secured[address] = (token, tls_ca)
        _channels.pop(address, None)


def channel(address: str) -> grpc.Channel:
    """The channel to ``address`` ("host:port" or "unix:/path"), made on first use."""
    with _lock:
        found = _channels.get(address)
        if found is None:
            token, tls_ca = _secured.get(address, ("", ""))
            found = open_channel(address, MESSAGE_OPTIONS, token=token, tls_ca=tls_ca)
            _channels[address] = found
        return found
