"""One gRPC channel per address, shared by every call this process makes."""

from __future__ import annotations

import threading

import grpc

# Batches of rays and points are large messages.
MAX_MESSAGE_BYTES = 256 * 1024 * 1024
MESSAGE_OPTIONS = [
    ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
    ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
]

_channels: dict[str, grpc.Channel] = {}
_lock = threading.Lock()


def channel(address: str) -> grpc.Channel:
    """The channel to ``address`` ("host:port" or "unix:/path"), made on first use."""
    with _lock:
        found = _channels.get(address)
        if found is None:
            found = grpc.insecure_channel(address, options=MESSAGE_OPTIONS)
            _channels[address] = found
        return found
