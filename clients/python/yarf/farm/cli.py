"""yarf-farm: run the farm's coordinator or a render node."""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import os
import re
import signal
import socket
import sys
import tempfile
import time
from pathlib import Path

import nats
from nats.aio.client import Client as Nats
from nats.errors import Error as NatsError

from yarf.credentials import channel_credentials, resolve
from yarf.farm.access import AccessError
from yarf.farm.cache import DEFAULT_CACHE_BYTES
from yarf.farm.coordinator import Coordinator, Retention
from yarf.farm.listen import ListenSecurity, listen_security
from yarf.farm.loops import run
from yarf.farm.node import DEFAULT_TASK_TIMEOUT, Node
from yarf.farm.service import start_server
from yarf.farm.store import JobStore
from yarf.farm.streams import ensure_resources
from yarf.farm.tasks import SplitPolicy
from yarf.server import LocalServer

log = logging.getLogger("yarf.farm")

DEFAULT_NATS = "nats://127.0.0.1:4222"
NATS_HELP = "NATS server URL: nats://[USER:PASSWORD@]HOST:PORT or tls://... (default %(default)s)"
# How long a process waits for NATS at start.
CONNECT_SECONDS = 30.0


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="yarf-farm", description="A yarf render farm on NATS JetStream."
    )
    commands = parser.add_subparsers(dest="command", required=True)
    defaults = SplitPolicy()

    coordinator = commands.add_parser(
        "coordinator", help="serve RenderService, split jobs into tasks, merge their images"
    )
    coordinator.add_argument("--nats", default=DEFAULT_NATS, help=NATS_HELP)
    coordinator.add_argument(
        "--listen", default="127.0.0.1:50051", help="gRPC address (port 0: any free port)"
    )
    coordinator.add_argument(
        "--state-dir", type=Path, required=True, help="folder of the job table (SQLite)"
    )
    coordinator.add_argument("--port-file", type=Path, help="write the bound port here")
    coordinator.add_argument(
        "--tls-cert",
        type=Path,
        metavar="FILE",
        help="serve TLS with this PEM certificate (with --tls-key); "
        "required, with --tokens, on a non-loopback address",
    )
    coordinator.add_argument("--tls-key", type=Path, metavar="FILE", help="its PEM private key")
    coordinator.add_argument(
        "--tokens",
        type=Path,
        metavar="FILE",
        help="bearer tokens, yarfd's format: `TOKEN USER ROLE` per line, ROLE submit|admin "
        "(needs TLS)",
    )
    retention = Retention()
    coordinator.add_argument(
        "--keep-finished-hours",
        type=float,
        default=retention.keep_finished_hours,
        metavar="H",
        help="ended jobs and their images are deleted after H hours "
        f"(default {retention.keep_finished_hours:g})",
    )
    coordinator.add_argument(
        "--max-finished-jobs",
        type=int,
        default=retention.max_finished_jobs,
        metavar="N",
        help=f"and beyond N ended jobs, the oldest first (default {retention.max_finished_jobs})",
    )
    coordinator.add_argument(
        "--shares",
        type=int,
        default=defaults.shares,
        help=f"sample-pass tasks per job, about twice the nodes (default {defaults.shares})",
    )
    coordinator.add_argument(
        "--min-task-work",
        type=int,
        default=defaults.min_task_work,
        help="pixel samples below which a task is not split further "
        f"(default {defaults.min_task_work})",
    )
    coordinator.add_argument(
        "--tile-pixels",
        type=int,
        default=defaults.tile_pixels,
        help=f"images above this many pixels are also cut into tiles "
        f"(default {defaults.tile_pixels})",
    )
    coordinator.add_argument(
        "--tile-size",
        type=int,
        default=defaults.tile_size,
        help=f"tile side in pixels (default {defaults.tile_size})",
    )

    node = commands.add_parser("node", help="render tasks on a yarfd")
    node.add_argument("--nats", default=DEFAULT_NATS, help=NATS_HELP)
    node.add_argument(
        "--yarfd", help="address of the yarfd to render on (default: start one as a child)"
    )
    node.add_argument(
        "--token",
        metavar="TOKEN",
        help="bearer token for a --yarfd that requires TLS and tokens (default: $YARF_TOKEN)",
    )
    node.add_argument(
        "--ca",
        metavar="PEM",
        help="certificate the --yarfd's TLS certificate is checked against "
        "(default: $YARF_TLS_CA, else the system's CAs when a token is given)",
    )
    node.add_argument("--threads", type=int, help="render threads of the child yarfd")
    node.add_argument("--name", help="the node's name in logs and results (default host-pid)")
    node.add_argument(
        "--cache-dir", type=Path, help="scene cache (default: a folder in the temp directory)"
    )
    node.add_argument(
        "--cache-bytes",
        type=int,
        default=DEFAULT_CACHE_BYTES,
        metavar="N",
        help="the scene cache's size limit: least recently used scenes are deleted "
        f"beyond it; 0: no limit (default {DEFAULT_CACHE_BYTES})",
    )
    node.add_argument(
        "--task-timeout",
        type=float,
        default=DEFAULT_TASK_TIMEOUT,
        metavar="SECONDS",
        help="a task rendering longer is cancelled and reported failed (the job's "
        f"max_retries apply); 0: no limit (default {DEFAULT_TASK_TIMEOUT:g})",
    )
    return parser


def _without_secrets(url: str) -> str:
    """``url`` for a log line: nats://user:password@host becomes nats://***@host."""
    return re.sub(r"//[^/@]*@", "//***@", url)


async def _connect(url: str, name: str) -> Nats:
    """Connects, retrying while NATS starts; reconnects forever afterwards.

    ``url`` goes to nats-py as it is: nats://user:password@host:4222 and
    tls://host:4222 (checked against the system's CAs, or $SSL_CERT_FILE) work.
    """
    deadline = time.monotonic() + CONNECT_SECONDS
    while True:
        try:
            return await nats.connect(
                url,
                name=name,
                max_reconnect_attempts=-1,
                reconnect_time_wait=0.5,
                connect_timeout=2,
            )
        except Exception as error:
            if time.monotonic() > deadline:
                where = _without_secrets(url)
                raise SystemExit(f"cannot connect to NATS at {where}: {error}") from error
            await asyncio.sleep(0.25)


async def _close(nc: Nats) -> None:
    """Closes the connection; with NATS gone its last flush fails, which is no error here."""
    try:
        await nc.close()
    except (OSError, NatsError) as error:
        log.info("NATS connection closed without its last flush: %r", error)


def _stop_event() -> asyncio.Event:
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for number in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(number, stop.set)
    return stop


async def _run_coordinator(args: argparse.Namespace, security: ListenSecurity) -> int:
    stop = _stop_event()
    policy = SplitPolicy(
        shares=max(1, args.shares),
        min_task_work=max(1, args.min_task_work),
        tile_pixels=args.tile_pixels,
        tile_size=max(1, args.tile_size),
    )
    nc = await _connect(args.nats, "yarf-farm coordinator")
    buckets = await ensure_resources(nc.jetstream())
    store = JobStore(args.state_dir)
    retention = Retention(args.keep_finished_hours, args.max_finished_jobs)
    coordinator = Coordinator(nc, store, buckets, policy, retention)
    await coordinator.start()
    server, port = await start_server(coordinator, args.listen, security)
    if args.port_file is not None:
        # Written whole or not at all: a reader never sees half a number.
        partial = args.port_file.with_suffix(".part")
        partial.write_text(f"{port}\n")
        partial.replace(args.port_file)
    access = "TLS and tokens" if security.tokens else "TLS" if security.credentials else "plaintext"
    log.info("coordinator serving on port %d, %s (state %s)", port, access, args.state_dir)
    await stop.wait()
    await server.stop(grace=1.0)
    await coordinator.stop()
    # Everything is committed and acked, or will be redelivered: no drain.
    await _close(nc)
    store.close()
    return 0


async def _watch_child(server: LocalServer, stop: asyncio.Event) -> None:
    """Stops the node when its own yarfd exits (a supervisor restarts the pair)."""
    while not stop.is_set():
        if not server.is_running():
            log.error("the node's yarfd exited:\n%s", server.log[-2000:])
            stop.set()
            return
        await asyncio.sleep(1.0)


async def _run_node(args: argparse.Namespace, token: str, tls_ca: str) -> int:
    stop = _stop_event()
    name = args.name or f"{socket.gethostname()}-{os.getpid()}"
    cache_dir = args.cache_dir or Path(tempfile.gettempdir()) / "yarf-farm-scenes"
    server: LocalServer | None = None
    address = args.yarfd
    if address is None:
        # Its job table is private and starts empty: tasks it had queued
        # before a restart were redelivered elsewhere meanwhile.
        server = LocalServer(threads=args.threads)
        await asyncio.to_thread(server.start)
        address = server.address
        fields = {"node": name, "pid": server.pid, "address": address}
        log.info("yarfd started %s", json.dumps(fields))
    watchdog = asyncio.create_task(_watch_child(server, stop)) if server is not None else None
    try:
        nc = await _connect(args.nats, f"yarf-farm node {name}")
        buckets = await ensure_resources(nc.jetstream())
        node = Node(
            nc,
            buckets,
            address,
            name=name,
            cache_dir=cache_dir,
            cache_bytes=args.cache_bytes,
            task_timeout=args.task_timeout,
            token=token,
            tls_ca=tls_ca,
        )
        try:
            await node.check_yarfd()
        except PermissionError as error:
            raise SystemExit(f"yarf-farm: {error}") from None
        await node.run(stop)
        await _close(nc)
    finally:
        if watchdog is not None:
            watchdog.cancel()
        crashed = server is not None and not server.is_running()
        if server is not None:
            await asyncio.to_thread(server.stop)
    return 1 if crashed else 0


def _node_credentials(args: argparse.Namespace) -> tuple[str, str]:
    """The token and CA for --yarfd: the flags, else $YARF_TOKEN and $YARF_TLS_CA."""
    if args.yarfd is None:
        # The node's own yarfd listens on loopback in plaintext.
        return "", ""
    token, tls_ca = resolve(args.token, args.ca)
    channel_credentials(token, tls_ca)  # reads the CA now: a bad path fails at start
    return token, tls_ca


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    if args.command == "coordinator":
        if args.keep_finished_hours < 0 or args.max_finished_jobs < 0:
            _parser().error("--keep-finished-hours and --max-finished-jobs must be 0 or more")
        try:
            # Checked before NATS is reached: a wrong command line fails at once.
            security = listen_security(args.listen, args.tls_cert, args.tls_key, args.tokens)
        except AccessError as error:
            print(f"yarf-farm: {error}", file=sys.stderr)
            return 2
        return run(_run_coordinator(args, security))
    if args.cache_bytes < 0 or args.task_timeout < 0:
        _parser().error("--cache-bytes and --task-timeout must be 0 or more")
    if args.yarfd is not None and args.threads is not None:
        _parser().error("--threads applies to the node's own yarfd, not to --yarfd")
    if args.yarfd is None and (args.token is not None or args.ca is not None):
        _parser().error("--token and --ca apply to --yarfd, not to the node's own yarfd")
    try:
        token, tls_ca = _node_credentials(args)
    except OSError as error:
        print(f"yarf-farm: {error}", file=sys.stderr)
        return 2
    return run(_run_node(args, token, tls_ca))
