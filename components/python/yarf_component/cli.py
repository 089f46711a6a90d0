"""The yarf-component command: serve component classes written in Python.

    yarf-component serve examples/lambertian.py:Lambertian --listen 127.0.0.1:0 \\
        [--register YARFD] [--lease SECONDS] [--server YARFD] [--token TOKEN] [--ca PEM]

Prints ``yarf-component listening on ADDRESS`` once serving, and stops on
SIGINT or SIGTERM (unregistering first).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType

from yarf.credentials import resolve as resolve_credentials
from yarf_component.loading import TargetError, load_target
from yarf_component.server import serve


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="yarf-component", description="Serve yarf components written in Python."
    )
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("serve", help="serve component classes over gRPC")
    run.add_argument(
        "targets",
        nargs="+",
        metavar="TARGET",
        help="package.module:ClassName or path/to/file.py:ClassName",
    )
    run.add_argument(
        "--listen", required=True, help="host:port (port 0 picks a free one) or unix:/path"
    )
    run.add_argument("--register", metavar="YARFD", help="register the classes with this yarfd")
    run.add_argument(
        "--lease", type=int, default=30, metavar="SECONDS", help="registration lease (30)"
    )
    run.add_argument(
        "--server",
        metavar="YARFD",
        help="the yarfd whose job scenes transports call (default: --register's)",
    )
    run.add_argument(
        "--token",
        metavar="TOKEN",
        help="bearer token for a yarfd that requires TLS and tokens; registering needs an "
        "admin token (default: $YARF_TOKEN)",
    )
    run.add_argument(
        "--ca",
        metavar="PEM",
        help="certificate the yarfd's TLS certificate is checked against (default: $YARF_TLS_CA)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="yarf-component: %(message)s")
    try:
        classes = [cls for target in args.targets for cls in load_target(target)]
        token, tls_ca = resolve_credentials(args.token, args.ca)
        running = serve(
            classes,
            args.listen,
            register=args.register,
            lease=args.lease,
            server=args.server,
            token=token,
            tls_ca=tls_ca,
        )
    except (TargetError, TypeError, ValueError, OSError, ImportError, SyntaxError) as error:
        print(f"yarf-component: {error}", file=sys.stderr)
        return 2
    stopping = threading.Event()

    def stop(signum: int, frame: FrameType | None) -> None:
        stopping.set()

    signal.signal(signal.SIGINT, stop)
    signal.signal(signal.SIGTERM, stop)
    print(f"yarf-component listening on {running.address}", flush=True)
    # A timeout keeps the main thread waking up for the signal handlers.
    while not stopping.wait(0.5):
        pass
    running.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
