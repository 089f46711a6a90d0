"""How a failed call reaches the caller: a gRPC status with a message that says why."""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

import grpc

log = logging.getLogger("yarf_component")

Servicer = TypeVar("Servicer")
Request = TypeVar("Request")
Reply = TypeVar("Reply")


class RpcFailure(Exception):
    """Ends the call with ``code`` and ``message``."""

    def __init__(self, code: grpc.StatusCode, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@contextmanager
def user_code(instance: object, method: str, *, unimplemented: bool = False) -> Iterator[None]:
    """Runs a component's own code: its exceptions become INTERNAL naming class and method.

    With ``unimplemented``, NotImplementedError means the optional method is
    missing (UNIMPLEMENTED).
    """
    name = f"{type(instance).__name__}.{method}"
    try:
        yield
    except RpcFailure:
        raise
    except NotImplementedError as error:
        if not unimplemented:
            log.exception("%s failed", name)
            raise RpcFailure(
                grpc.StatusCode.INTERNAL, f"{name}: NotImplementedError: {error}"
            ) from error
        raise RpcFailure(grpc.StatusCode.UNIMPLEMENTED, f"{name} is not implemented") from error
    except Exception as error:
        log.exception("%s failed", name)
        raise RpcFailure(
            grpc.StatusCode.INTERNAL, f"{name}: {type(error).__name__}: {error}"
        ) from error


def rpc(
    method: Callable[[Servicer, Request, grpc.ServicerContext], Reply],
) -> Callable[[Servicer, Request, grpc.ServicerContext], Reply]:
    """A servicer method whose RpcFailure ends the call with its status."""

    @functools.wraps(method)
    def answer(self: Servicer, request: Request, context: grpc.ServicerContext) -> Reply:
        try:
            return method(self, request, context)
        except RpcFailure as failure:
            context.abort(failure.code, failure.message)

    return answer


def invalid(message: str) -> RpcFailure:
    return RpcFailure(grpc.StatusCode.INVALID_ARGUMENT, message)
