"""yarf.v1.RenderService served by the coordinator, so that clients cannot tell it from a yarfd."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator

import grpc

from yarf.client import MAX_MESSAGE_BYTES, numpy_to_array
from yarf.farm.access import Caller, Role, may_act_on
from yarf.farm.assets import FarmAssetService
from yarf.farm.auth import TokenCheck, TokenInterceptor, Unauthenticated
from yarf.farm.coordinator import FINAL_STATES, Coordinator, Job, UnknownJob
from yarf.farm.images import encode_exr, encode_png
from yarf.farm.listen import ListenSecurity
from yarf.farm.validation import AddressNotAllowed, InvalidRequest
from yarf.v1 import asset_pb2_grpc, render_pb2, render_pb2_grpc

# A serialized grpc.health.v1.HealthCheckResponse{status: SERVING}: the
# health protocol's one message, without the grpcio-health-checking package.
_SERVING = b"\x08\x01"
# A Watch stream with no news still looks at the job this often.
WATCH_IDLE_SECONDS = 1.0


class FarmRenderService(render_pb2_grpc.RenderServiceServicer):
    """RenderService on the coordinator's asyncio loop; each job is its owner's (and admins')."""

    def __init__(self, coordinator: Coordinator, check: TokenCheck) -> None:
        self._coordinator = coordinator
        self._check = check

    async def _caller(self, context: grpc.aio.ServicerContext) -> Caller:
        try:
            return self._check.caller(context.invocation_metadata())
        except Unauthenticated as error:
            # The interceptor turned such calls away already; this is a second lock.
            await context.abort(grpc.StatusCode.UNAUTHENTICATED, str(error))
            raise

    async def _job(self, job_id: str, context: grpc.aio.ServicerContext) -> Job:
        """The job, if the caller may act on it; else NOT_FOUND or PERMISSION_DENIED."""
        caller = await self._caller(context)
        try:
            job = self._coordinator.job(job_id)
        except UnknownJob:
            await context.abort(grpc.StatusCode.NOT_FOUND, f"no job '{job_id}'")
            raise
        if not may_act_on(caller, job.record.owner):
            await context.abort(
                grpc.StatusCode.PERMISSION_DENIED, f"job '{job_id}' is not {caller.user}'s"
            )
        return job

    async def Submit(
        self, request: render_pb2.SubmitRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.SubmitReply:
        caller = await self._caller(context)
        try:
            reply = await self._coordinator.submit(
                request, caller.user, admin=caller.role is Role.ADMIN
            )
        except AddressNotAllowed as error:
            await context.abort(grpc.StatusCode.PERMISSION_DENIED, str(error))
            raise
        except InvalidRequest as error:
            await context.abort(grpc.StatusCode.INVALID_ARGUMENT, str(error))
            raise
        return reply

    async def Watch(
        self, request: render_pb2.WatchRequest, context: grpc.aio.ServicerContext
    ) -> AsyncIterator[render_pb2.JobStatus]:
        job = await self._job(request.job_id, context)
        while True:
            changed = job.changed
            status = self._coordinator.status(job)
            yield status
            if status.state in FINAL_STATES:
                return
            # Waits for a change; the timeout only notices a client that left.
            while not changed.is_set():
                try:
                    await asyncio.wait_for(changed.wait(), WATCH_IDLE_SECONDS)
                except TimeoutError:
                    if context.done():
                        return

    async def GetResult(
        self, request: render_pb2.GetResultRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.GetResultReply:
        job = await self._job(request.job_id, context)
        reply = render_pb2.GetResultReply(status=self._coordinator.status(job))
        image = self._coordinator.image(job)
        if image is None:
            error = f": {job.record.error}" if job.record.error else ""
            await context.abort(
                grpc.StatusCode.FAILED_PRECONDITION,
                f"job '{request.job_id}' has no image{error}",
            )
        assert image is not None
        pixels, variance = image
        if request.format == render_pb2.GetResultRequest.EXR:
            reply.image = await asyncio.to_thread(encode_exr, pixels)
        elif request.format == render_pb2.GetResultRequest.PNG:
            reply.image = await asyncio.to_thread(encode_png, pixels)
        else:
            reply.pixels.CopyFrom(numpy_to_array(pixels))
            reply.variance.CopyFrom(numpy_to_array(variance))
        return reply

    async def Cancel(
        self, request: render_pb2.CancelRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.CancelReply:
        job = await self._job(request.job_id, context)
        await self._coordinator.cancel(job)
        return render_pb2.CancelReply(status=self._coordinator.status(job))

    async def List(
        self, request: render_pb2.ListJobsRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.ListJobsReply:
        caller = await self._caller(context)
        jobs = [job for job in self._coordinator.list() if may_act_on(caller, job.owner)]
        return render_pb2.ListJobsReply(jobs=jobs)

    async def SetPriority(
        self, request: render_pb2.SetPriorityRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.JobStatus:
        job = await self._job(request.job_id, context)
        if not 1 <= request.priority <= 100:
            await context.abort(
                grpc.StatusCode.INVALID_ARGUMENT, f"priority {request.priority} is not 1 to 100"
            )
        await self._coordinator.set_priority(job, request.priority)
        return self._coordinator.status(job)

    async def GetJob(
        self, request: render_pb2.GetJobRequest, context: grpc.aio.ServicerContext
    ) -> render_pb2.JobDetails:
        job = await self._job(request.job_id, context)
        details = render_pb2.JobDetails(
            status=self._coordinator.status(job), log=self._coordinator.log(job)
        )
        # The options after Submit's defaults, as stored: what every task is cut from.
        details.options.ParseFromString(job.record.options)
        summary = await self._coordinator.scene_summary(job)
        if summary is not None:
            details.scene.CopyFrom(summary)
        return details


async def _health_check(request: bytes, context: grpc.aio.ServicerContext) -> bytes:
    return _SERVING


async def start_server(
    coordinator: Coordinator, listen: str, security: ListenSecurity
) -> tuple[grpc.aio.Server, int]:
    """Serves RenderService, AssetService and the health check at ``listen``; returns
    the server and its port."""
    check = TokenCheck(security.tokens)
    server = grpc.aio.server(
        interceptors=[TokenInterceptor(check)] if check.enabled else [],
        options=[
            ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
            ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
            # As yarfd: a second coordinator on a port in use fails to
            # start rather than sharing its clients.
            ("grpc.so_reuseport", 0),
        ],
    )
    render_pb2_grpc.add_RenderServiceServicer_to_server(
        FarmRenderService(coordinator, check), server
    )
    asset_pb2_grpc.add_AssetServiceServicer_to_server(FarmAssetService(coordinator.assets), server)
    health = grpc.method_handlers_generic_handler(
        "grpc.health.v1.Health", {"Check": grpc.unary_unary_rpc_method_handler(_health_check)}
    )
    server.add_generic_rpc_handlers((health,))
    if security.credentials is None:
        port = server.add_insecure_port(listen)
    else:
        port = server.add_secure_port(listen, security.credentials)
    if port == 0:
        raise OSError(f"cannot listen at {listen}")
    await server.start()
    return server, port
