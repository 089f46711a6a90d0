"""The Texture service (texture.proto) over a Host's instances."""

from __future__ import annotations

import grpc
import numpy as np

from yarf.v1 import texture_pb2, texture_pb2_grpc
from yarf_component.arrays import Batch, float32
from yarf_component.calls import rpc, user_code
from yarf_component.host import Host
from yarf_component.texture import Texture


class TextureService(texture_pb2_grpc.TextureServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Channels(
        self, request: texture_pb2.ChannelsRequest, context: grpc.ServicerContext
    ) -> texture_pb2.ChannelsReply:
        texture = self._host.instance(request.handle, Texture)
        with user_code(texture, "channels"):
            return texture_pb2.ChannelsReply(channels=int(texture.channels()))

    @rpc
    def Evaluate(
        self, request: texture_pb2.TextureQuery, context: grpc.ServicerContext
    ) -> texture_pb2.TextureReply:
        texture = self._host.instance(request.handle, Texture)
        batch = Batch()
        uv = batch.floats(request.uv, "uv", 2)
        # An absent footprint is a point lookup.
        footprint = (
            batch.floats(request.footprint, "footprint", 4)
            if request.HasField("footprint")
            else np.zeros((len(uv), 4), np.float32)
        )
        with user_code(texture, "evaluate"):
            return texture_pb2.TextureReply(value=float32(texture.evaluate(uv, footprint)))

    @rpc
    def Mean(
        self, request: texture_pb2.MeanRequest, context: grpc.ServicerContext
    ) -> texture_pb2.MeanReply:
        texture = self._host.instance(request.handle, Texture)
        with user_code(texture, "mean"):
            values = np.asarray(texture.mean(), dtype=np.float32).reshape(-1)
            return texture_pb2.MeanReply(mean=values.tolist())
