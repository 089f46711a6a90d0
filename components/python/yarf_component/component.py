"""The base of every component class, and the checks a class must pass to be served."""

from __future__ import annotations

import abc
import re
from typing import ClassVar

from yarf.v1 import component_pb2
from yarf_component.properties import Signature, parameter_infos

CLASS_NAME = re.compile(r"[a-z][a-z0-9]*(_[a-z0-9]+)*")
VERSION = re.compile(r"\d+\.\d+\.\d+")
# What a class may declare it can do (ComponentInfo.capabilities); the
# server refuses a registration naming another.
CAPABILITIES = frozenset({"sample_passes", "pixel_local"})


class Component(abc.ABC):
    """A component class: subclass an interface (SurfaceModel, Sampler...), not this.

    ``class_name`` names the class on a host (lower_snake_case, required);
    ``version`` is "MAJOR.MINOR.PATCH"; ``summary`` is one line for people;
    ``capabilities`` what it can do beyond its interface (a Transport whose
    samples land only in their own pixels declares "pixel_local", and the
    farm may then render its jobs in tiles).
    An instance is made from a scene's Properties passed to ``__init__`` as
    keyword arguments, checked against its annotations (see properties.py).
    """

    class_name: ClassVar[str]
    version: ClassVar[str] = "1.0.0"
    summary: ClassVar[str] = ""
    capabilities: ClassVar[tuple[str, ...]] = ()
    # Full service name, set by each interface's base class only.
    interface_name: ClassVar[str] = ""

    def __init__(self) -> None:  # noqa: B027 - the constructor of classes without properties
        """No properties: a class that reads none rejects every key."""

    @classmethod
    def interfaces(cls) -> list[str]:
        """Full names of the services the class implements, e.g. ["yarf.v1.SurfaceModel"]."""
        names: list[str] = []
        for base in cls.__mro__:
            name = base.__dict__.get("interface_name", "")
            if name and name not in names:
                names.append(name)
        return names

    @classmethod
    def origin(cls) -> str:
        return f"python {cls.__module__}"

    @classmethod
    def info(cls) -> component_pb2.ComponentInfo:
        """Describe's answer, the parameters those ``__init__`` declares (properties.py)."""
        parameters = parameter_infos(Signature.of(cls.class_name, cls.__init__))
        return component_pb2.ComponentInfo(
            class_name=cls.class_name,
            version=cls.version,
            interfaces=cls.interfaces(),
            summary=cls.summary,
            origin=cls.origin(),
            declares_parameters=parameters is not None,
            parameters=parameters or [],
            capabilities=list(cls.capabilities),
        )


def check_component_class(cls: object) -> type[Component]:
    """``cls`` if it can be served; else a TypeError saying what is wrong with it."""
    if not (isinstance(cls, type) and issubclass(cls, Component)):
        raise TypeError(f"{cls!r} is not a subclass of yarf_component.Component")
    name = cls.__dict__.get("class_name")
    if not isinstance(name, str) or not CLASS_NAME.fullmatch(name):
        raise TypeError(
            f"{cls.__qualname__} needs its own class_name in lower_snake_case, e.g. 'py_lambertian'"
        )
    if not isinstance(cls.version, str) or not VERSION.fullmatch(cls.version):
        raise TypeError(f"{cls.__qualname__}.version must be 'MAJOR.MINOR.PATCH'")
    unknown = sorted(set(cls.capabilities) - CAPABILITIES)
    if unknown:
        raise TypeError(
            f"{cls.__qualname__} declares unknown capabilities {unknown}; "
            f"there are {sorted(CAPABILITIES)}"
        )
    if not cls.interfaces():
        raise TypeError(f"{cls.__qualname__} implements no interface (subclass e.g. SurfaceModel)")
    missing = sorted(getattr(cls, "__abstractmethods__", ()))
    if missing:
        raise TypeError(f"{cls.__qualname__} does not implement {', '.join(missing)}")
    return cls
