"""Bearer tokens on the coordinator's gRPC calls: a server interceptor and the caller lookup.

The interceptor turns away every call without a known token before any
service sees it (the health check excepted), so a method added later is
covered too; the service then asks ``TokenCheck.caller`` who is calling
to decide about ownership.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Awaitable, Callable, Sequence

import grpc

from yarf.farm.access import LOCAL_ADMIN, Caller, TokenTable

_BEARER = "bearer "
# Probes (a load balancer's, the kubelet's) call these without a token.
_OPEN_PREFIXES = ("/grpc.health.v1.Health/", "/grpc.reflection.")

Metadata = Sequence[tuple[str, str | bytes]]


class Unauthenticated(Exception):
    """No token, or one the tokens file does not hold (UNAUTHENTICATED)."""


def is_open_method(method: str) -> bool:
    return method.startswith(_OPEN_PREFIXES)


def _authorization(metadata: Metadata | None) -> str:
    for key, value in metadata or ():
        if key == "authorization":
            return value.decode(errors="replace") if isinstance(value, bytes) else value
    return ""


class TokenCheck:
    """The callers of a tokens file; without one, every caller is the local admin."""

    def __init__(self, tokens: TokenTable | None) -> None:
        self._tokens = tokens

    @property
    def enabled(self) -> bool:
        return self._tokens is not None

    def caller(self, metadata: Metadata | None) -> Caller:
        """The caller a call's metadata names; Unauthenticated if none."""
        if self._tokens is None:
            return LOCAL_ADMIN
        header = _authorization(metadata)
        if not header:
            raise Unauthenticated(
                "the coordinator needs a token: send `authorization: Bearer TOKEN`"
            )
        # The scheme in any case, as HTTP allows.
        if len(header) <= len(_BEARER) or header[: len(_BEARER)].lower() != _BEARER:
            raise Unauthenticated("the authorization header must read `Bearer TOKEN`")
        found = self._tokens.get(header[len(_BEARER) :])
        if found is None:
            raise Unauthenticated("unknown token")
        return found


def _refusal(handler: grpc.RpcMethodHandler, message: str) -> grpc.RpcMethodHandler:
    """A handler of the same kind as ``handler`` that ends the call UNAUTHENTICATED."""

    async def refuse(request: object, context: grpc.aio.ServicerContext) -> None:
        await context.abort(grpc.StatusCode.UNAUTHENTICATED, message)

    async def refuse_stream(
        request: object, context: grpc.aio.ServicerContext
    ) -> AsyncIterator[bytes]:
        await context.abort(grpc.StatusCode.UNAUTHENTICATED, message)
        yield  # never reached: makes this an async generator, as streaming handlers are

    if handler.request_streaming and handler.response_streaming:
        return grpc.stream_stream_rpc_method_handler(refuse_stream)
    if handler.request_streaming:
        return grpc.stream_unary_rpc_method_handler(refuse)
    if handler.response_streaming:
        return grpc.unary_stream_rpc_method_handler(refuse_stream)
    return grpc.unary_unary_rpc_method_handler(refuse)


class TokenInterceptor(grpc.aio.ServerInterceptor):
    """UNAUTHENTICATED for any call but the open ones that carries no known token."""

    def __init__(self, check: TokenCheck) -> None:
        self._check = check

    async def intercept_service(
        self,
        continuation: Callable[[grpc.HandlerCallDetails], Awaitable[grpc.RpcMethodHandler]],
        handler_call_details: grpc.HandlerCallDetails,
    ) -> grpc.RpcMethodHandler:
        handler = await continuation(handler_call_details)
        method: str = handler_call_details.method  # type: ignore[attr-defined]
        if handler is None or is_open_method(method):
            return handler
        try:
            self._check.caller(handler_call_details.invocation_metadata)  # type: ignore[attr-defined]
        except Unauthenticated as error:
            return _refusal(handler, str(error))
        return handler
