"""A scene's parameters as one flat, typed mapping (Mitsuba's ``mi.traverse``).

Every property of a material, emitter, light, texture and medium of a
``yarf.v1.Scene`` message, and the camera's placement and lens, under a key
``OBJECT.PROPERTY``: ``"red.reflectance"``, ``"luminaire.radiance"``,
``"camera.fov"``, ``"camera.to_world"``. The object is named as the scene
names it (a material's or medium's name, a shape's or light's name for its
emitter); an object without a name, or whose name another object of the
scene also has, is named by its place (``"shapes[3].radiance"``).

The view reads and writes the message itself: a value set here is what the
next render of the scene submits. A value keeps its key's type and shape;
anything else is refused with an error that says what the key holds.
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections import Counter
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass

import numpy as np

from yarf.v1 import component_pb2, scene_pb2

# What a parameter reads as: numbers, text, or numpy arrays for vectors,
# colours, matrices and float arrays.
ParameterValue = float | int | bool | str | np.ndarray

# The type of each Property variant, as keys report it.
_PROPERTY_TYPES = {
    "float_value": "float",
    "int_value": "int",
    "bool_value": "bool",
    "string_value": "string",
    "vec3_value": "vec3",
    "rgb_value": "rgb",
    "transform_value": "transform",
    "reference": "reference",
    "float_array_value": "float_array",
}

# The camera's numbers that mean something for each model (scene.proto's Camera).
_CAMERA_PLACEMENT = ("origin", "target", "up", "to_world")
_CAMERA_CLIPPING = ("near_clip", "far_clip", "shutter")
_CAMERA_FIELDS: dict[int, tuple[str, ...]] = {
    scene_pb2.Camera.PINHOLE: (*_CAMERA_PLACEMENT, "fov", *_CAMERA_CLIPPING),
    scene_pb2.Camera.THIN_LENS: (
        *_CAMERA_PLACEMENT,
        "fov",
        "lens_radius",
        "focus_distance",
        *_CAMERA_CLIPPING,
    ),
    scene_pb2.Camera.ORTHOGRAPHIC: (*_CAMERA_PLACEMENT, "view_size", *_CAMERA_CLIPPING),
    scene_pb2.Camera.RADIANCE_METER: ("origin", "target"),
    scene_pb2.Camera.IRRADIANCE_METER: (),
    scene_pb2.Camera.SPHERICAL: (*_CAMERA_PLACEMENT, *_CAMERA_CLIPPING),
}


class UnknownParameterError(KeyError):
    """A key the scene has no parameter of; the message suggests the closest keys."""

    def __init__(self, key: str, known: list[str]) -> None:
        close = difflib.get_close_matches(key, known, n=3, cutoff=0.5)
        message = f"the scene has no parameter {key!r}"
        if close:
            names = [repr(k) for k in close]
            choices = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"
            message += f"; did you mean {choices}?"
        else:
            message += f" ({len(known)} parameters: see params.keys())"
        super().__init__(message)
        self.key = key
        self.suggestions = close

    def __str__(self) -> str:
        # KeyError would print the repr of its message, quotes and all.
        return str(self.args[0])


@dataclass(frozen=True)
class _Parameter:
    """Where one parameter lives: its type, and how to read and write it."""

    type: str
    get: Callable[[], ParameterValue]
    set: Callable[[object], None]


def _vector(key: str, value: object, length: int) -> np.ndarray:
    """``value`` as ``length`` finite float64 numbers, or TypeError / ValueError."""
    if isinstance(value, str | bytes) or not _is_array_like(value):
        raise TypeError(
            f"{key} is a sequence of {length} numbers, not {type(value).__name__} {value!r}"
        )
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"{key} is a sequence of {length} numbers, not an array of {array.dtype}")
    if array.shape != (length,):
        raise ValueError(f"{key} has shape ({length},), not {array.shape}")
    values = array.astype(np.float64)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{key} must be finite, not {values.tolist()}")
    return values


def _is_array_like(value: object) -> bool:
    return isinstance(value, np.ndarray | list | tuple) or hasattr(value, "__array__")


def _real(key: str, value: object) -> float:
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise TypeError(f"{key} is a float, not {type(value).__name__} {value!r}")
    if not math.isfinite(float(value)):
        raise ValueError(f"{key} must be finite, not {value}")
    return float(value)


def _rgb_values(key: str, value: object) -> np.ndarray:
    # A single number is grey, as the server reads a float where an rgb is expected.
    if isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_):
        return np.full(3, _real(key, value))
    return _vector(key, value, 3)


def _property_parameter(key: str, holder: component_pb2.Properties, name: str) -> _Parameter:
    """A parameter stored as ``holder.values[name]``, keeping that Property's variant."""
    prop = holder.values[name]
    variant = prop.WhichOneof("value") or "float_value"
    kind = _PROPERTY_TYPES[variant]

    def get() -> ParameterValue:
        if variant == "vec3_value":
            return np.array([prop.vec3_value.x, prop.vec3_value.y, prop.vec3_value.z])
        if variant == "rgb_value":
            return np.array([prop.rgb_value.r, prop.rgb_value.g, prop.rgb_value.b])
        if variant == "transform_value":
            return np.array(prop.transform_value.m, dtype=np.float64).reshape(4, 4)
        if variant == "float_array_value":
            return np.array(prop.float_array_value.values, dtype=np.float32)
        return getattr(prop, variant)

    def set_(value: object) -> None:
        if variant == "float_value":
            prop.float_value = _real(key, value)
        elif variant == "int_value":
            if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Integral):
                raise TypeError(f"{key} is an int, not {type(value).__name__} {value!r}")
            prop.int_value = int(value)
        elif variant == "bool_value":
            if not isinstance(value, bool | np.bool_):
                raise TypeError(f"{key} is a bool, not {type(value).__name__} {value!r}")
            prop.bool_value = bool(value)
        elif variant in ("string_value", "reference"):
            if not isinstance(value, str):
                raise TypeError(f"{key} is a {kind} (text), not {type(value).__name__} {value!r}")
            setattr(prop, variant, value)
        elif variant == "vec3_value":
            x, y, z = _vector(key, value, 3)
            prop.vec3_value.x, prop.vec3_value.y, prop.vec3_value.z = x, y, z
        elif variant == "rgb_value":
            r, g, b = _rgb_values(key, value)
            prop.rgb_value.r, prop.rgb_value.g, prop.rgb_value.b = r, g, b
        elif variant == "transform_value":
            prop.transform_value.m[:] = _matrix(key, value).ravel().tolist()
        else:
            length = len(prop.float_array_value.values)
            prop.float_array_value.values[:] = _vector(key, np.ravel(value), length).tolist()

    return _Parameter(kind, get, set_)


def _matrix(key: str, value: object) -> np.ndarray:
    if not _is_array_like(value):
        raise TypeError(f"{key} is a 4x4 matrix, not {type(value).__name__} {value!r}")
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"{key} is a 4x4 matrix of numbers, not an array of {array.dtype}")
    if array.shape != (4, 4):
        raise ValueError(f"{key} has shape (4, 4), not {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{key} must be finite")
    return array.astype(np.float64)


def _transform_parameter(key: str, owner: scene_pb2.Light, field: str) -> _Parameter:
    """A Transform field of a message (identity when absent), as a 4x4 matrix."""

    def get() -> np.ndarray:
        if not owner.HasField(field):
            return np.eye(4)
        return np.array(getattr(owner, field).m, dtype=np.float64).reshape(4, 4)

    def set_(value: object) -> None:
        getattr(owner, field).m[:] = _matrix(key, value).ravel().tolist()

    return _Parameter("transform", get, set_)


def look_at_matrix(origin: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The camera-to-world matrix of a look-at placement (Mitsuba's ``look_at``):
    columns left, up, forward (+z toward the target) and the origin."""
    forward = target - origin
    forward = forward / np.linalg.norm(forward)
    left = np.cross(up, forward)
    norm = np.linalg.norm(left)
    if norm == 0.0 or not np.isfinite(norm):
        raise ValueError("the camera's up is parallel to its view direction")
    left = left / norm
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2] = left, np.cross(forward, left), forward
    matrix[:3, 3] = origin
    return matrix


def _camera_parameter(key: str, camera: scene_pb2.Camera, field: str) -> _Parameter:
    if field == "to_world":
        # Derived from the look-at placement the scene stores; setting it sets
        # origin, target (one unit ahead) and up.
        def get() -> np.ndarray:
            origin, target, up = (_vec3(getattr(camera, f)) for f in ("origin", "target", "up"))
            return look_at_matrix(origin, target, up)

        def set_(value: object) -> None:
            matrix = _matrix(key, value)
            origin, up, forward = matrix[:3, 3], matrix[:3, 1], matrix[:3, 2]
            if np.linalg.norm(forward) == 0.0 or np.linalg.norm(np.cross(up, forward)) == 0.0:
                raise ValueError(
                    f"{key}: the third column (view direction) must be non-zero "
                    "and not parallel to the second (up)"
                )
            _set_vec3(camera.origin, origin)
            _set_vec3(camera.target, origin + forward / np.linalg.norm(forward))
            _set_vec3(camera.up, up)

        return _Parameter("transform", get, set_)
    if field in ("origin", "target", "up"):
        vector = getattr(camera, field)
        return _Parameter(
            "vec3",
            lambda: _vec3(vector),
            lambda value: _set_vec3(vector, _vector(key, value, 3)),
        )
    return _Parameter(
        "float",
        lambda: float(getattr(camera, field)),
        lambda value: setattr(camera, field, _real(key, value)),
    )


def _vec3(vector: component_pb2.Vec3) -> np.ndarray:
    return np.array([vector.x, vector.y, vector.z])


def _set_vec3(vector: component_pb2.Vec3, values: np.ndarray) -> None:
    vector.x, vector.y, vector.z = (float(v) for v in values)


def _objects(
    scene: scene_pb2.Scene,
) -> Iterator[tuple[str, str, component_pb2.Properties, scene_pb2.Light | None, str | None]]:
    """(name, place, properties, owner of a to_world, its field) of every object
    with parameters."""
    for index, material in enumerate(scene.materials):
        yield material.name, f"materials[{index}]", material.properties, None, None
    for index, texture in enumerate(scene.textures):
        yield texture.name, f"textures[{index}]", texture.texture.properties, None, None
    for index, shape in enumerate(scene.shapes):
        if shape.HasField("emitter"):
            yield shape.name, f"shapes[{index}]", shape.emitter.properties, None, None
    for index, light in enumerate(scene.lights):
        yield light.name, f"lights[{index}]", light.emitter.properties, light, "to_world"
    for index, medium in enumerate(scene.media):
        yield medium.name, f"media[{index}]", medium.medium.properties, None, None


def _parameters(scene: scene_pb2.Scene) -> dict[str, _Parameter]:
    objects = list(_objects(scene))
    names = Counter(name for name, *_ in objects)
    names["camera"] += 1
    found: dict[str, _Parameter] = {}
    for name, place, props, owner, field in objects:
        label = name if name and names[name] == 1 else place
        for key in sorted(props.values):
            found[f"{label}.{key}"] = _property_parameter(f"{label}.{key}", props, key)
        if owner is not None and field is not None:
            found[f"{label}.{field}"] = _transform_parameter(f"{label}.{field}", owner, field)
    if scene.HasField("camera"):
        for field in _CAMERA_FIELDS.get(scene.camera.model, ()):
            found[f"camera.{field}"] = _camera_parameter(f"camera.{field}", scene.camera, field)
    return found


def _short(value: object) -> str:
    if isinstance(value, np.ndarray):
        if value.shape == (4, 4):
            rows = "; ".join(" ".join(f"{v:.4g}" for v in row) for row in value)
            return f"[{rows}]"
        if value.size > 6:
            return f"[{value.size} values]"
        return "(" + ", ".join(f"{v:.4g}" for v in value) + ")"
    if isinstance(value, float):
        return f"{value:.6g}"
    return repr(value)


class SceneParameters(MutableMapping[str, object]):
    """The parameters of a ``yarf.v1.Scene`` message: key → value, each with a type.

    ``params["red.reflectance"]`` is a numpy array of 3 numbers;
    ``params["red.reflectance"] = [0.1, 0.1, 0.1]`` (or ``0.1``, grey) sets
    it in the message. Types: ``float``, ``int``, ``bool``, ``string``,
    ``reference`` (the name of a texture or other object), ``vec3``,
    ``rgb``, ``transform`` (a 4x4 matrix, row-major, column vectors) and
    ``float_array`` (its length fixed). An unknown key raises
    UnknownParameterError (a KeyError) naming the closest keys; a value of
    another type raises TypeError, of another shape or not finite
    ValueError. Values read are copies: set them back to change the scene.
    Parameters cannot be added or removed.
    """

    def __init__(self, scene: scene_pb2.Scene) -> None:
        self._scene = scene

    def _lookup(self, key: str) -> _Parameter:
        parameters = _parameters(self._scene)
        if not isinstance(key, str) or key not in parameters:
            raise UnknownParameterError(str(key), list(parameters))
        return parameters[key]

    def __getitem__(self, key: str) -> ParameterValue:
        return self._lookup(key).get()

    def __setitem__(self, key: str, value: object) -> None:
        self._lookup(key).set(value)

    def __delitem__(self, key: str) -> None:
        raise TypeError(f"scene parameters cannot be removed ({key!r})")

    def __iter__(self) -> Iterator[str]:
        return iter(_parameters(self._scene))

    def __len__(self) -> int:
        return len(_parameters(self._scene))

    def type_of(self, key: str) -> str:
        """The type of ``key``'s values: "float", "rgb", "transform"..."""
        return self._lookup(key).type

    def types(self) -> dict[str, str]:
        """Every key with its type, in the order of ``keys()``."""
        return {key: parameter.type for key, parameter in _parameters(self._scene).items()}

    def table(self) -> list[tuple[str, str, str]]:
        """(key, type, value as text) of every parameter."""
        return [
            (key, parameter.type, _short(parameter.get()))
            for key, parameter in _parameters(self._scene).items()
        ]

    def __repr__(self) -> str:
        rows = self.table()
        if not rows:
            return "SceneParameters (none)"
        width = max(len(key) for key, _, _ in rows)
        kinds = max(len(kind) for _, kind, _ in rows)
        lines = [f"SceneParameters ({len(rows)})"]
        lines += [f"  {key:<{width}}  {kind:<{kinds}}  {value}" for key, kind, value in rows]
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        import html

        cells = "".join(
            f"<tr><td><code>{html.escape(key)}</code></td><td>{kind}</td>"
            f"<td><code>{html.escape(value)}</code></td></tr>"
            for key, kind, value in self.table()
        )
        return (
            "<table><thead><tr><th>key</th><th>type</th><th>value</th></tr></thead>"
            f"<tbody>{cells}</tbody></table>"
        )
