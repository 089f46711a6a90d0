"""The interface services a component process serves: those of its classes' interfaces."""

from __future__ import annotations

from collections.abc import Callable

import grpc

from yarf.v1 import (
    math_pb2_grpc,
    medium_pb2_grpc,
    surface_pb2_grpc,
    texture_pb2_grpc,
    transport_pb2_grpc,
)
from yarf_component.host import Host
from yarf_component.medium import Medium
from yarf_component.medium_service import MediumService
from yarf_component.numerical import Function, Generator, Integrator, RootFinder, Sampler, Warp
from yarf_component.numerical_services import (
    FunctionService,
    GeneratorService,
    IntegratorService,
    RootFinderService,
    SamplerService,
    WarpService,
)
from yarf_component.surface import Emitter, SurfaceModel
from yarf_component.surface_services import EmitterService, SurfaceModelService
from yarf_component.texture import Texture
from yarf_component.texture_service import TextureService
from yarf_component.transport import Transport
from yarf_component.transport_service import TransportService

# Interface name -> the function adding its servicer to a server, and the servicer.
SERVICES: dict[str, tuple[Callable[[object, grpc.Server], None], Callable[[Host], object]]] = {
    SurfaceModel.interface_name: (
        surface_pb2_grpc.add_SurfaceModelServicer_to_server,
        SurfaceModelService,
    ),
    Emitter.interface_name: (surface_pb2_grpc.add_EmitterServicer_to_server, EmitterService),
    Function.interface_name: (math_pb2_grpc.add_FunctionServicer_to_server, FunctionService),
    Sampler.interface_name: (math_pb2_grpc.add_SamplerServicer_to_server, SamplerService),
    Generator.interface_name: (math_pb2_grpc.add_GeneratorServicer_to_server, GeneratorService),
    Warp.interface_name: (math_pb2_grpc.add_WarpServicer_to_server, WarpService),
    RootFinder.interface_name: (
        math_pb2_grpc.add_RootFinderServicer_to_server,
        RootFinderService,
    ),
    Integrator.interface_name: (math_pb2_grpc.add_IntegratorServicer_to_server, IntegratorService),
    Transport.interface_name: (
        transport_pb2_grpc.add_TransportServicer_to_server,
        TransportService,
    ),
    Texture.interface_name: (texture_pb2_grpc.add_TextureServicer_to_server, TextureService),
    Medium.interface_name: (medium_pb2_grpc.add_MediumServicer_to_server, MediumService),
}


def add_interface_services(host: Host, server: grpc.Server) -> None:
    """The services of the interfaces the host's classes implement, and only those."""
    for name in sorted(host.interfaces):
        add, servicer = SERVICES[name]
        add(servicer(host), server)
