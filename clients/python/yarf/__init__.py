"""Python client of the yarf render server.

The gRPC stubs (``yarf.v1.*_pb2``) are generated from ``proto/yarf/v1`` at
build time into this package's ``v1`` folder::

    python -m grpc_tools.protoc -I proto --python_out=clients/python \\
        --grpc_python_out=clients/python --pyi_out=clients/python proto/yarf/v1/*.proto
"""

from __future__ import annotations

try:
    from yarf.v1 import render_pb2 as _render_pb2  # noqa: F401
except ImportError as error:  # pragma: no cover - depends on the build
    raise ImportError(
        "the yarf gRPC stubs (yarf.v1.*_pb2) are missing: generate them from proto/yarf/v1 "
        "with grpc_tools.protoc into clients/python (see yarf/__init__.py), e.g. with `make`"
    ) from error

from yarf.client import Client, RenderError, RenderResult, SubmitWarning, array_to_numpy
from yarf.integrate import Integral, IntegrationWarning, integrate
from yarf.notebook import Image, Scene, embedded_server, load, render
from yarf.params import SceneParameters, UnknownParameterError
from yarf.render_options import OptionError
from yarf.scene import (
    SceneError,
    component,
    inline_mesh_files,
    load_scene,
    properties,
    rgb,
    transform,
    vec3,
)
from yarf.server import LocalServer, ServerError, find_yarfd

__all__ = [
    "Client",
    "Image",
    "Integral",
    "IntegrationWarning",
    "LocalServer",
    "OptionError",
    "RenderError",
    "RenderResult",
    "Scene",
    "SceneError",
    "SceneParameters",
    "ServerError",
    "SubmitWarning",
    "UnknownParameterError",
    "array_to_numpy",
    "component",
    "embedded_server",
    "find_yarfd",
    "inline_mesh_files",
    "integrate",
    "load",
    "load_scene",
    "properties",
    "render",
    "rgb",
    "transform",
    "vec3",
]

__version__ = "0.1.0"
