"""Keeping a component process registered with a yarfd (Registry.Register, a lease)."""

from __future__ import annotations

import sys
import threading
import typing

import grpc

from yarf.v1 import component_pb2, component_pb2_grpc
from yarf_component.channels import channel

# Deadline of each Register call, seconds.
REGISTER_TIMEOUT = 10.0
# How soon a failed registration is tried again, seconds at most.
RETRY_SECONDS = 2.0


class Registration:
    """Registers ``address`` with the yarfd at ``registry`` now and every lease/3
    seconds in a daemon thread until ``stop``; a failure is one line on stderr,
    and the next attempt comes sooner."""

    def __init__(self, registry: str, address: str, lease_seconds: int) -> None:
        if lease_seconds < 1:
            raise ValueError("the lease must be at least 1 second")
        self.registry = registry
        self.address = address
        self.lease_seconds = lease_seconds
        self.registered = threading.Event()
        self._stub = component_pb2_grpc.RegistryStub(channel(registry))
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="yarf-registration", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _register_once(self) -> float:
        """Seconds until the next attempt."""
        request = component_pb2.RegisterRequest(
            address=self.address, lease_seconds=self.lease_seconds
        )
        try:
            reply = self._stub.Register(request, timeout=REGISTER_TIMEOUT)
        except grpc.RpcError as error:
            call = typing.cast(grpc.Call, error)
            print(
                f"yarf-component: Register with {self.registry} failed: "
                f"{call.code().name}: {call.details()}",
                file=sys.stderr,
                flush=True,
            )
            return min(RETRY_SECONDS, self.lease_seconds / 3)
        self.registered.set()
        return (reply.lease_seconds or self.lease_seconds) / 3

    def _run(self) -> None:
        while not self._stopping.is_set():
            delay = self._register_once()
            self._stopping.wait(delay)

    def stop(self) -> None:
        """Ends the renewals and unregisters (best effort: yarfd may be gone)."""
        self._stopping.set()
        if self._thread.is_alive():
            self._thread.join(timeout=REGISTER_TIMEOUT)
        try:
            self._stub.Unregister(
                component_pb2.UnregisterRequest(address=self.address), timeout=2.0
            )
        except grpc.RpcError:
            pass
