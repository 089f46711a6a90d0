"""gRPC health probe for yarfd and the farm coordinator, for containers and pods.

Calls grpc.health.v1.Health/Check for the whole server ("") with the grpcio
the image already has (the health stubs are not installed, so the request
and reply are encoded by hand: both are one small protobuf message).
Exit 0: the server is SERVING, or it answered but refused an anonymous
health call (it is up, and the token check is its own). Exit 1 otherwise.

Kubernetes' own gRPC probe cannot be used: it speaks neither TLS nor bearer
tokens, and a server on a non-loopback address requires both.

Settings, from the environment:
  YARF_HEALTH_ADDRESS  host:port to call (default localhost:50051)
  YARF_HEALTH_CA       PEM file to trust (the server's certificate or its CA);
                       unset: plaintext, for a server on loopback
  YARF_HEALTH_TIMEOUT  seconds (default 3)
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import grpc

CHECK = "/grpc.health.v1.Health/Check"
# HealthCheckResponse.status (field 1, varint): 1 is SERVING.
SERVING = b"\x08\x01"
# Codes that prove a live gRPC server over a working (TLS) channel.
ANSWERED = {
    grpc.StatusCode.UNAUTHENTICATED,
    grpc.StatusCode.PERMISSION_DENIED,
    grpc.StatusCode.UNIMPLEMENTED,
}


def channel(address: str, ca_file: str | None) -> grpc.Channel:
    if not ca_file:
        return grpc.insecure_channel(address)
    root = Path(ca_file).read_bytes()
    return grpc.secure_channel(address, grpc.ssl_channel_credentials(root_certificates=root))


def main() -> int:
    address = os.environ.get("YARF_HEALTH_ADDRESS", "localhost:50051")
    timeout = float(os.environ.get("YARF_HEALTH_TIMEOUT", "3"))
    with channel(address, os.environ.get("YARF_HEALTH_CA")) as chan:
        # No serializers: the empty HealthCheckRequest (service "") is b"".
        check = chan.unary_unary(CHECK)
        try:
            reply: bytes = check(b"", timeout=timeout)
        except grpc.RpcError as error:
            code = error.code()  # type: ignore[attr-defined]
            if code in ANSWERED:
                print(f"{address}: up ({code.name} to an anonymous health check)")
                return 0
            print(f"{address}: {code.name}: {error.details()}", file=sys.stderr)  # type: ignore[attr-defined]
            return 1
    if reply == SERVING:
        print(f"{address}: SERVING")
        return 0
    print(f"{address}: not serving (reply {reply.hex() or 'empty'})", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
