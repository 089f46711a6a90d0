"""Component, Factory and Registry (component.proto) over a Host."""

from __future__ import annotations

import grpc

from yarf.v1 import component_pb2, component_pb2_grpc
from yarf_component.calls import RpcFailure, rpc
from yarf_component.host import Host


class ComponentService(component_pb2_grpc.ComponentServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Describe(
        self, request: component_pb2.DescribeRequest, context: grpc.ServicerContext
    ) -> component_pb2.ComponentInfo:
        return self._host.describe(request.class_name, request.handle)


class FactoryService(component_pb2_grpc.FactoryServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Create(
        self, request: component_pb2.CreateRequest, context: grpc.ServicerContext
    ) -> component_pb2.CreateReply:
        return self._host.create(request.class_name, request.properties)

    @rpc
    def Release(
        self, request: component_pb2.ReleaseRequest, context: grpc.ServicerContext
    ) -> component_pb2.ReleaseReply:
        self._host.release(request.handle)
        return component_pb2.ReleaseReply()


def _not_here(what: str) -> RpcFailure:
    return RpcFailure(grpc.StatusCode.UNIMPLEMENTED, f"a Python component process {what}")


class RegistryService(component_pb2_grpc.RegistryServicer):
    """Lists the process's classes; loading and registering are yarfd's business."""

    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def ListClasses(
        self, request: component_pb2.ListClassesRequest, context: grpc.ServicerContext
    ) -> component_pb2.ListClassesReply:
        return component_pb2.ListClassesReply(classes=[cls.info() for cls in self._host.classes])

    @rpc
    def LoadPlugin(
        self, request: component_pb2.LoadPluginRequest, context: grpc.ServicerContext
    ) -> component_pb2.LoadPluginReply:
        raise _not_here("loads no C++ plugins")

    @rpc
    def Register(
        self, request: component_pb2.RegisterRequest, context: grpc.ServicerContext
    ) -> component_pb2.RegisterReply:
        raise _not_here("takes no registrations: register with a yarfd")

    @rpc
    def Unregister(
        self, request: component_pb2.UnregisterRequest, context: grpc.ServicerContext
    ) -> component_pb2.UnregisterReply:
        raise _not_here("takes no registrations: register with a yarfd")


def add_component_services(host: Host, server: grpc.Server) -> None:
    component_pb2_grpc.add_ComponentServicer_to_server(ComponentService(host), server)
    component_pb2_grpc.add_FactoryServicer_to_server(FactoryService(host), server)
    component_pb2_grpc.add_RegistryServicer_to_server(RegistryService(host), server)
