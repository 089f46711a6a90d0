"""Write yarf components in Python.

Subclass an interface, give the class a ``class_name``, take its properties
as keyword arguments of ``__init__``, implement the batch methods on numpy
arrays, and serve it::

    yarf-component serve my_bsdf.py:MyBsdf --listen 127.0.0.1:0 --register 127.0.0.1:50051

or, from Python, ``serve([MyBsdf], "127.0.0.1:0")``.
"""

from __future__ import annotations

from yarf_component.component import Component
from yarf_component.frames import Frame, normalize, reflect
from yarf_component.job_calls import Pending, SceneViewError
from yarf_component.job_emitter import EmitterClient
from yarf_component.job_medium import MediumClient
from yarf_component.job_surface import SurfaceClient
from yarf_component.medium import (
    HenyeyGreensteinMedium,
    Medium,
    henyey_greenstein,
    sample_henyey_greenstein,
)
from yarf_component.mis import power_heuristic, samples_lights
from yarf_component.numerical import (
    Function,
    Generator,
    Integrand,
    Integrator,
    NoRoot,
    PointSource,
    RootFinder,
    Sampler,
    Warp,
)
from yarf_component.properties import PropertyError, Rgb, Transform, Vec3
from yarf_component.scene_view import (
    AT_INFINITY,
    DELTA_DIRECTION,
    DELTA_POSITION,
    MISS,
    NONE,
    CameraConnections,
    Crossings,
    Hits,
    LightPoints,
    LightSamples,
    Rays,
    SceneLayout,
    SceneView,
    SurfaceSamples,
)
from yarf_component.server import Running, serve
from yarf_component.surface import (
    Emitter,
    ScatterFlags,
    SurfaceModel,
    TransportMode,
    lobe_allowed,
)
from yarf_component.texture import SurfacePoints, Texture
from yarf_component.transport import Transport

__all__ = [
    "AT_INFINITY",
    "DELTA_DIRECTION",
    "DELTA_POSITION",
    "MISS",
    "NONE",
    "CameraConnections",
    "Component",
    "Crossings",
    "Emitter",
    "EmitterClient",
    "Frame",
    "Function",
    "Generator",
    "HenyeyGreensteinMedium",
    "Hits",
    "Integrand",
    "Integrator",
    "LightPoints",
    "LightSamples",
    "Medium",
    "MediumClient",
    "NoRoot",
    "Pending",
    "PointSource",
    "PropertyError",
    "Rays",
    "Rgb",
    "RootFinder",
    "Running",
    "Sampler",
    "ScatterFlags",
    "SceneLayout",
    "SceneView",
    "SceneViewError",
    "SurfaceClient",
    "SurfaceModel",
    "SurfacePoints",
    "SurfaceSamples",
    "Texture",
    "Transform",
    "Transport",
    "TransportMode",
    "Vec3",
    "Warp",
    "henyey_greenstein",
    "lobe_allowed",
    "normalize",
    "power_heuristic",
    "reflect",
    "sample_henyey_greenstein",
    "samples_lights",
    "serve",
]

__version__ = "0.1.0"
