"""The classes a component process serves and the instances it has made."""

from __future__ import annotations

import itertools
import secrets
import threading
from collections.abc import Sequence
from typing import TypeVar

import grpc

from yarf.v1 import component_pb2
from yarf_component.calls import RpcFailure
from yarf_component.component import Component, check_component_class
from yarf_component.properties import PropertyError, Signature

Instance = TypeVar("Instance", bound=Component)


class Host:
    """Classes by name, instances by handle (non-zero, never reused), and the yarfd
    address transports call back (None when the process was given none)."""

    def __init__(self, classes: Sequence[type], server_address: str | None = None) -> None:
        self.server_address = server_address
        self._classes: dict[str, type[Component]] = {}
        self._signatures: dict[str, Signature] = {}
        for candidate in classes:
            cls = check_component_class(candidate)
            if cls.class_name in self._classes:
                raise ValueError(f"two classes are named '{cls.class_name}'")
            self._classes[cls.class_name] = cls
            self._signatures[cls.class_name] = Signature.of(cls.class_name, cls.__init__)
        if not self._classes:
            raise ValueError("no component class to serve")
        self._instances: dict[int, Component] = {}
        # Handles start at a random number so that a restarted process never
        # gives out a handle a caller may still hold from its predecessor.
        self._handles = itertools.count(secrets.randbelow(1 << 62) + 1)
        self._lock = threading.Lock()

    @property
    def classes(self) -> list[type[Component]]:
        return list(self._classes.values())

    @property
    def interfaces(self) -> set[str]:
        """Every interface some class implements: the services to serve."""
        return {name for cls in self._classes.values() for name in cls.interfaces()}

    def describe(self, class_name: str, handle: int) -> component_pb2.ComponentInfo:
        if handle:
            return type(self.find(handle)).info()
        cls = self._classes.get(class_name)
        if cls is None:
            raise RpcFailure(grpc.StatusCode.NOT_FOUND, f"unknown component class '{class_name}'")
        return cls.info()

    def create(
        self, class_name: str, properties: component_pb2.Properties
    ) -> component_pb2.CreateReply:
        cls = self._classes.get(class_name)
        if cls is None:
            raise RpcFailure(grpc.StatusCode.NOT_FOUND, f"unknown component class '{class_name}'")
        try:
            arguments = self._signatures[class_name].arguments(properties)
        except PropertyError as error:
            raise RpcFailure(grpc.StatusCode.INVALID_ARGUMENT, str(error)) from None
        try:
            instance = cls(**arguments)
        except Exception as error:  # the class's own checks of its properties
            raise RpcFailure(
                grpc.StatusCode.INVALID_ARGUMENT,
                f"component '{class_name}': {type(error).__name__}: {error}",
            ) from error
        with self._lock:
            handle = next(self._handles)
            self._instances[handle] = instance
        return component_pb2.CreateReply(handle=handle, info=cls.info())

    def release(self, handle: int) -> None:
        with self._lock:
            if self._instances.pop(handle, None) is None:
                raise RpcFailure(grpc.StatusCode.NOT_FOUND, f"no instance {handle}")

    def find(self, handle: int) -> Component:
        with self._lock:
            instance = self._instances.get(handle)
        if instance is None:
            raise RpcFailure(grpc.StatusCode.NOT_FOUND, f"no instance {handle}")
        return instance

    def instance(self, handle: int, interface: type[Instance]) -> Instance:
        """Instance ``handle`` as ``interface``: NOT_FOUND when unknown, INVALID_ARGUMENT
        when it implements another interface."""
        instance = self.find(handle)
        if not isinstance(instance, interface):
            raise RpcFailure(
                grpc.StatusCode.INVALID_ARGUMENT,
                f"instance {handle} ('{instance.class_name}') does not implement "
                f"{interface.interface_name}",
            )
        return instance
