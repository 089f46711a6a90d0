"""A scene's Properties as the keyword arguments of a component's ``__init__``.

Values arrive as Python values: float, int, bool and str as themselves, a
vec3 and an rgb as a tuple of 3 floats, a transform as a 4x4 float64 numpy
array, a float array as a 1-D float32 numpy array, a reference as str. Each
is checked against the annotation of the parameter it fills:

    float          a float, or an int
    int, bool      exactly that
    str            a string or a reference
    Rgb            an rgb, or a float or int f as grey (f, f, f)
    Vec3           a vec3
    tuple[...]     a vec3 or an rgb
    Transform      a transform
    np.ndarray     a transform or a float array
    Literal[...]   one of the values listed
    X | Y          whichever arm accepts it
A parameter without annotation takes any value. A key no parameter reads
(unless ``__init__`` has ``**kwargs``), a value of the wrong type or a
required parameter left out is a PropertyError naming the key and class.
"""

from __future__ import annotations

import enum
import inspect
import math
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Literal, Union, get_args, get_origin

import numpy as np

from yarf.v1 import component_pb2


class PropertyKind(enum.Enum):
    """Markers that tell colours, vectors and placements apart in annotations."""

    RGB = "rgb"
    VEC3 = "vec3"
    TRANSFORM = "transform"


Rgb = Annotated[tuple[float, float, float], PropertyKind.RGB]
Vec3 = Annotated[tuple[float, float, float], PropertyKind.VEC3]
Transform = Annotated[np.ndarray, PropertyKind.TRANSFORM]

# The proto's oneof cases as people write them in messages.
KIND_NAMES = {
    "float_value": "float",
    "int_value": "int",
    "bool_value": "bool",
    "string_value": "string",
    "vec3_value": "vec3",
    "rgb_value": "rgb",
    "transform_value": "transform",
    "reference": "reference",
    "float_array_value": "float array",
}


class PropertyError(ValueError):
    """A property the class cannot take; the message names the key and the class."""


class _Mismatch(Exception):
    """The value does not fit the annotation."""


def natural_value(key: str, prop: component_pb2.Property) -> tuple[str, object]:
    """(oneof case, Python value) of one property."""
    kind = prop.WhichOneof("value")
    if kind == "float_value":
        return kind, float(prop.float_value)
    if kind == "int_value":
        return kind, int(prop.int_value)
    if kind == "bool_value":
        return kind, bool(prop.bool_value)
    if kind == "string_value":
        return kind, str(prop.string_value)
    if kind == "reference":
        return kind, str(prop.reference)
    if kind == "vec3_value":
        v = prop.vec3_value
        return kind, (float(v.x), float(v.y), float(v.z))
    if kind == "rgb_value":
        c = prop.rgb_value
        return kind, (float(c.r), float(c.g), float(c.b))
    if kind == "transform_value":
        m = np.array(prop.transform_value.m, dtype=np.float64)
        if m.size != 16:
            raise PropertyError(f"property '{key}': a transform has 16 values, not {m.size}")
        return kind, m.reshape(4, 4)
    if kind == "float_array_value":
        return kind, np.array(prop.float_array_value.values, dtype=np.float32)
    raise PropertyError(f"property '{key}' has no value")


def _marker(metadata: tuple[object, ...]) -> PropertyKind | None:
    return next((m for m in metadata if isinstance(m, PropertyKind)), None)


def _fit_marked(marker: PropertyKind, kind: str, value: object) -> object:
    if marker is PropertyKind.RGB:
        if kind == "rgb_value":
            return value
        if kind in ("float_value", "int_value"):
            grey = float(typing.cast(float, value))
            return (grey, grey, grey)
    elif marker is PropertyKind.VEC3:
        if kind == "vec3_value":
            return value
    elif kind == "transform_value":
        return value
    raise _Mismatch


def fit(annotation: object, kind: str, value: object) -> object:
    """``value`` converted for a parameter annotated ``annotation``; _Mismatch if it cannot be."""
    if annotation in (inspect.Parameter.empty, typing.Any, object):
        return value
    origin = get_origin(annotation)
    if origin is Annotated:
        base, *metadata = get_args(annotation)
        marker = _marker(tuple(metadata))
        return _fit_marked(marker, kind, value) if marker else fit(base, kind, value)
    if origin in (Union, types.UnionType):
        for arm in get_args(annotation):
            if arm is type(None):
                continue
            try:
                return fit(arm, kind, value)
            except _Mismatch:
                pass
        raise _Mismatch
    if origin is Literal:
        if value in get_args(annotation) and not isinstance(value, tuple | np.ndarray):
            return value
        raise _Mismatch
    if annotation is float and kind in ("float_value", "int_value"):
        return float(typing.cast(float, value))
    if annotation is int and kind == "int_value":
        return value
    if annotation is bool and kind == "bool_value":
        return value
    if annotation is str and kind in ("string_value", "reference"):
        return value
    if (annotation is tuple or origin is tuple) and kind in ("vec3_value", "rgb_value"):
        return value
    array_kinds = ("transform_value", "float_array_value")
    if (annotation is np.ndarray or origin is np.ndarray) and kind in array_kinds:
        return value
    if annotation in (float, int, bool, str, tuple, np.ndarray) or origin in (tuple, np.ndarray):
        raise _Mismatch
    # An annotation this module does not know: the class checks the value itself.
    return value


def describe(annotation: object) -> str:
    """The types an annotation accepts, as the message of a mismatch says them."""
    origin = get_origin(annotation)
    if origin is Annotated:
        base, *metadata = get_args(annotation)
        marker = _marker(tuple(metadata))
        if marker is PropertyKind.RGB:
            return "rgb (or float)"
        return marker.value if marker else describe(base)
    if origin in (Union, types.UnionType):
        return " or ".join(describe(a) for a in get_args(annotation) if a is not type(None))
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(annotation))
    if annotation is tuple or origin is tuple:
        return "vec3 or rgb"
    if annotation is np.ndarray or origin is np.ndarray:
        return "transform"
    if annotation is str:
        return "string"
    return getattr(annotation, "__name__", str(annotation))


@dataclass(frozen=True)
class Signature:
    """What a class's ``__init__`` accepts: its keyword parameters and their annotations."""

    class_name: str
    parameters: Mapping[str, inspect.Parameter]
    annotations: Mapping[str, object]
    # Annotation of **kwargs, when __init__ takes any other key.
    extra: object | None

    @classmethod
    def of(cls, class_name: str, init: Callable[..., object]) -> Signature:
        try:
            hints = typing.get_type_hints(init, include_extras=True)
        except Exception:  # names the class cannot resolve: leave those values unchecked
            hints = {}
        parameters: dict[str, inspect.Parameter] = {}
        extra: object | None = None
        for parameter in list(inspect.signature(init).parameters.values())[1:]:
            annotation = hints.get(parameter.name, inspect.Parameter.empty)
            if parameter.kind is inspect.Parameter.VAR_KEYWORD:
                extra = annotation
            elif parameter.kind in (
                inspect.Parameter.POSITIONAL_OR_KEYWORD,
                inspect.Parameter.KEYWORD_ONLY,
            ):
                parameters[parameter.name] = parameter
        annotations = {name: hints.get(name, inspect.Parameter.empty) for name in parameters}
        return cls(class_name, parameters, annotations, extra)

    def arguments(self, properties: component_pb2.Properties) -> dict[str, object]:
        """The keyword arguments of ``__init__`` for ``properties``; PropertyError if none fit."""
        arguments: dict[str, object] = {}
        unknown = sorted(k for k in properties.values if k not in self.parameters)
        if unknown and self.extra is None:
            keys = ", ".join(f"'{k}'" for k in unknown)
            raise PropertyError(
                f"component '{self.class_name}' does not understand property {keys}"
            )
        for key in sorted(properties.values):
            kind, value = natural_value(key, properties.values[key])
            annotation = self.annotations.get(key, self.extra)
            try:
                arguments[key] = fit(annotation, kind, value)
            except _Mismatch:
                raise PropertyError(
                    f"component '{self.class_name}': property '{key}' must be of type "
                    f"{describe(annotation)}, not {KIND_NAMES[kind]}"
                ) from None
        missing = [
            name
            for name, parameter in self.parameters.items()
            if parameter.default is inspect.Parameter.empty and name not in arguments
        ]
        if missing:
            raise PropertyError(f"component '{self.class_name}': missing property '{missing[0]}'")
        return arguments


def _parameter_type(annotation: object) -> tuple[str, list[str], str] | None:
    """The ParameterInfo type, choices and doc of an annotation; None when no one type
    of the IDL says what it accepts (a union of several kinds, no annotation)."""
    origin = get_origin(annotation)
    if origin is Annotated:
        base, *metadata = get_args(annotation)
        doc = " ".join(m for m in metadata if isinstance(m, str))
        marker = _marker(tuple(metadata))
        if marker is not None:
            return {"rgb": "rgb", "vec3": "vector", "transform": "transform"}[marker.value], [], doc
        found = _parameter_type(base)
        return (found[0], found[1], doc or found[2]) if found else None
    if origin in (Union, types.UnionType):
        arms = [a for a in get_args(annotation) if a is not type(None)]
        return _parameter_type(arms[0]) if len(arms) == 1 else None
    if origin is Literal:
        values = get_args(annotation)
        return ("string", list(values), "") if all(isinstance(v, str) for v in values) else None
    names = {float: "float", int: "int", bool: "bool", str: "string", np.ndarray: "float array"}
    return (names[annotation], [], "") if annotation in names else None  # type: ignore[index]


def _default_text(value: object) -> str | None:
    """A default as ParameterInfo.default_value writes it; None when it has none to give."""
    if value is inspect.Parameter.empty or value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return ""  # the IDL's defaults are finite: an infinite one goes unsaid
    if isinstance(value, int | float):
        return repr(float(value)) if isinstance(value, float) else str(value)
    if isinstance(value, str):
        return value
    if (
        isinstance(value, tuple)
        and len(value) == 3
        and all(isinstance(v, int | float) for v in value)
    ):
        return ", ".join(repr(float(v)) for v in value)
    return None


def parameter_infos(signature: Signature) -> list[component_pb2.ParameterInfo] | None:
    """The parameters a class declares through its ``__init__``, for Describe; None when
    the signature cannot be said in the IDL's types (``**kwargs``, an annotation of
    several kinds): the class then takes what its ``__init__`` accepts, unchecked."""
    if signature.extra is not None:
        return None
    infos = []
    for name, parameter in signature.parameters.items():
        found = _parameter_type(signature.annotations.get(name, inspect.Parameter.empty))
        default = _default_text(parameter.default)
        if found is None or default is None:
            return None
        type_name, choices, doc = found
        infos.append(
            component_pb2.ParameterInfo(
                name=name,
                type=type_name,
                default_value=default if type_name != "float array" else "",
                required=parameter.default is inspect.Parameter.empty,
                choices=choices,
                doc=doc,
            )
        )
    return infos
