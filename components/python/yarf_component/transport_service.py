"""The Transport service (transport.proto) over a Host's instances, with the job scenes
its calls name, on the yarfd this process calls back."""

from __future__ import annotations

from collections import OrderedDict
from threading import Lock

import grpc

from yarf.v1 import transport_pb2, transport_pb2_grpc
from yarf_component.arrays import Batch, float32, uint32
from yarf_component.calls import RpcFailure, rpc, user_code
from yarf_component.host import Host
from yarf_component.scene_view import SceneView
from yarf_component.transport import Transport


class JobScenes:
    """The SceneView of each scene handle of the yarfd that calls; Prepare starts afresh."""

    KEPT = 64

    def __init__(self, address: str | None) -> None:
        self._address = address
        self._scenes: OrderedDict[int, SceneView] = OrderedDict()
        self._lock = Lock()

    def get(self, handle: int, *, fresh: bool = False) -> SceneView:
        if not self._address:
            raise RpcFailure(
                grpc.StatusCode.FAILED_PRECONDITION,
                "this component process knows no yarfd to call back: "
                "start it with --server ADDRESS or --register ADDRESS",
            )
        with self._lock:
            scene = None if fresh else self._scenes.get(handle)
            if scene is None:
                scene = SceneView(self._address, handle)
            self._scenes[handle] = scene
            self._scenes.move_to_end(handle)
            while len(self._scenes) > self.KEPT:
                self._scenes.popitem(last=False)
            return scene


class TransportService(transport_pb2_grpc.TransportServicer):
    def __init__(self, host: Host) -> None:
        self._host = host
        self._scenes = JobScenes(host.server_address)

    @rpc
    def Prepare(
        self, request: transport_pb2.PrepareRequest, context: grpc.ServicerContext
    ) -> transport_pb2.PrepareReply:
        transport = self._host.instance(request.handle, Transport)
        scene = self._scenes.get(request.scene_handle, fresh=True)
        with user_code(transport, "prepare"):
            transport.prepare(scene)
        return transport_pb2.PrepareReply()

    @rpc
    def Dimensions(
        self, request: transport_pb2.TransportDimensionsRequest, context: grpc.ServicerContext
    ) -> transport_pb2.TransportDimensionsReply:
        transport = self._host.instance(request.handle, Transport)
        with user_code(transport, "dimensions"):
            return transport_pb2.TransportDimensionsReply(dimensions=int(transport.dimensions()))

    @rpc
    def Evaluate(
        self, request: transport_pb2.TransportRequest, context: grpc.ServicerContext
    ) -> transport_pb2.TransportReply:
        transport = self._host.instance(request.handle, Transport)
        with user_code(transport, "dimensions"):
            d = int(transport.dimensions())
        points = Batch().floats(request.points, "points", d)
        scene = self._scenes.get(request.scene_handle)
        with user_code(transport, "evaluate"):
            result = transport.evaluate(scene, points)
            reply = transport_pb2.TransportReply(
                contributions=float32(result[0]), splats=bool(result[1])
            )
            if len(result) > 2:
                reply.points.CopyFrom(uint32(result[2]))  # type: ignore[misc]
            return reply
