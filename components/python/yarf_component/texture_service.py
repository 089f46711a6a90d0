"""The Texture service (texture.proto) over a Host's instances."""

from __future__ import annotations

import grpc
import numpy as np

from yarf.client import array_to_numpy
from yarf.v1 import component_pb2, texture_pb2, texture_pb2_grpc
from yarf_component.arrays import Batch, float32
from yarf_component.calls import invalid, rpc, user_code
from yarf_component.host import Host
from yarf_component.texture import SurfacePoints, Texture


def indices(batch: Batch, array: component_pb2.Array, name: str) -> np.ndarray:
    """``array`` as uint32 [N], N the batch's rows; INVALID_ARGUMENT naming it when it is not."""
    if array.dtype != component_pb2.Array.UINT32 or len(array.shape) != 1:
        raise invalid(f"{name}: expected a UINT32 array of shape [N]")
    try:
        values = array_to_numpy(array)
    except ValueError as error:
        raise invalid(f"{name}: {error}") from None
    if len(values) != batch.rows:
        raise invalid(f"{name} has {len(values)} rows, the batch {batch.rows}")
    return values


def surface_points(request: texture_pb2.TextureQuery, attributes: list[str]) -> SurfacePoints:
    """The query's points; the fields it lacks are None, the attributes it lacks 0."""
    batch = Batch()
    uv = batch.floats(request.uv, "uv", 2)
    # An absent footprint is a point lookup.
    footprint = (
        batch.floats(request.footprint, "footprint", 4)
        if request.HasField("footprint")
        else np.zeros((len(uv), 4), np.float32)
    )
    position = (
        batch.floats(request.position, "position", 3) if request.HasField("position") else None
    )
    located = request.HasField("shape")
    return SurfacePoints(
        uv=uv,
        footprint=footprint,
        position=position,
        shape=indices(batch, request.shape, "shape") if located else None,
        primitive=indices(batch, request.primitive, "primitive") if located else None,
        barycentrics=batch.floats(request.barycentrics, "barycentrics", 2) if located else None,
        attributes={
            name: batch.floats(request.attributes[name], f"attributes[{name}]", 3)
            if name in request.attributes
            else np.zeros((len(uv), 3), np.float32)
            for name in attributes
        },
    )


class TextureService(texture_pb2_grpc.TextureServicer):
    def __init__(self, host: Host) -> None:
        self._host = host

    @rpc
    def Channels(
        self, request: texture_pb2.ChannelsRequest, context: grpc.ServicerContext
    ) -> texture_pb2.ChannelsReply:
        texture = self._host.instance(request.handle, Texture)
        with user_code(texture, "channels"):
            channels = int(texture.channels())
        with user_code(texture, "attributes"):
            attributes = [str(name) for name in texture.attributes()]
        return texture_pb2.ChannelsReply(channels=channels, attributes=attributes)

    @rpc
    def Evaluate(
        self, request: texture_pb2.TextureQuery, context: grpc.ServicerContext
    ) -> texture_pb2.TextureReply:
        texture = self._host.instance(request.handle, Texture)
        with user_code(texture, "attributes"):
            attributes = [str(name) for name in texture.attributes()]
        at = surface_points(request, attributes)
        with user_code(texture, "evaluate"):
            return texture_pb2.TextureReply(value=float32(texture.evaluate(at)))

    @rpc
    def Mean(
        self, request: texture_pb2.MeanRequest, context: grpc.ServicerContext
    ) -> texture_pb2.MeanReply:
        texture = self._host.instance(request.handle, Texture)
        with user_code(texture, "mean"):
            values = np.asarray(texture.mean(), dtype=np.float32).reshape(-1)
            return texture_pb2.MeanReply(mean=values.tolist())
