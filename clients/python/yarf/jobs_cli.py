"""The ``yarf`` verbs that manage jobs on a running yarfd.

``submit`` queues a scene and prints the job id; ``status``, ``watch``,
``cancel``, ``list``, ``fetch`` and ``priority`` act on jobs by id, and
``dashboard`` serves the web page of the queue. Unlike ``yarf render``
these verbs never start a yarfd of their own: a job must outlive the
command, so without ``--server`` they use the one at 127.0.0.1:50051.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Iterator
from contextlib import closing, contextmanager
from itertools import chain
from pathlib import Path

import grpc
from google.protobuf import json_format
from tqdm import tqdm

from yarf import dashboard
from yarf.cli import (
    CommandError,
    _send_assets,
    check_denoiser,
    checked_settings,
    connect,
    live_view,
    output_settings,
    prepare_job,
    submit_job,
)
from yarf.client import DEFAULT_ADDRESS, FINAL_STATES, Client, RenderError, check_ended
from yarf.denoise import DenoiseError
from yarf.live_view import LiveView
from yarf.render_options import (
    add_denoise_argument,
    add_display_argument,
    add_image_arguments,
    add_render_arguments,
)
from yarf.v1 import render_pb2

# Exit code of `yarf watch` and `yarf submit --watch` for a job that did not succeed.
JOB_DID_NOT_SUCCEED = 1
# Longest job name `yarf list` shows whole.
NAME_COLUMN = 32


def _state(status: render_pb2.JobStatus) -> str:
    return render_pb2.JobState.Name(status.state)


def printable(text: str) -> str:
    """``text`` with control characters replaced: job names come from other users."""
    return "".join(c if c.isprintable() else "?" for c in text)


def format_duration(seconds: float) -> str:
    """``4.2 s``, ``42 s``, ``3 min 07 s`` or ``2 h 05 min``."""
    if seconds < 10:
        return f"{seconds:.1f} s"
    whole = round(seconds)
    if whole < 60:
        return f"{whole} s"
    if whole < 3600:
        return f"{whole // 60} min {whole % 60:02d} s"
    return f"{whole // 3600} h {whole % 3600 // 60:02d} min"


@contextmanager
def _job_server(args: argparse.Namespace) -> Iterator[Client]:
    """A client of --server, else of the yarfd at 127.0.0.1:50051."""
    with connect(args.server or DEFAULT_ADDRESS) as client:
        yield client


@contextmanager
def _about_job(job_id: str) -> Iterator[None]:
    """Turns the rpc errors that concern the job id into one-line command errors."""
    try:
        yield
    except grpc.RpcError as error:
        if not isinstance(error, grpc.Call):
            raise
        if error.code() == grpc.StatusCode.NOT_FOUND:
            raise CommandError(f"no job {job_id!r} on this server ({error.details()})") from None
        if error.code() == grpc.StatusCode.PERMISSION_DENIED:
            raise CommandError(f"job {job_id}: permission denied ({error.details()})") from None
        raise


def follow(
    client: Client,
    job_id: str,
    *,
    quiet: bool = False,
    time_limit: float | None = None,
    view: LiveView | None = None,
) -> render_pb2.JobStatus:
    """Shows a progress bar (samples, the server's ETA), and the image in ``view``, until
    the job ends (cancelled at ``time_limit`` seconds); returns the end."""
    bar_format = "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} spp [{elapsed}{postfix}]"
    with closing(client.watch_within(job_id, time_limit)) as statuses:
        # The first status comes at once and gives the bar its total.
        last = next(statuses, None)
        if last is not None:
            with tqdm(
                desc=job_id,
                total=last.samples_total or None,
                unit="spp",
                bar_format=bar_format,
                disable=quiet,
                dynamic_ncols=True,
            ) as bar:
                for status in chain([last], statuses):
                    last = status
                    _show(bar, status)
                    if view is not None:
                        view.progress(client, status)
    if last is None or last.state not in FINAL_STATES:
        # The stream ended early (the server went away?): ask once more.
        last = client.status(job_id)
    return last


def _show(bar: tqdm[None], status: render_pb2.JobStatus) -> None:
    if status.samples_total and bar.total != status.samples_total:
        bar.total = status.samples_total
    if status.samples_done != bar.n:
        bar.update(status.samples_done - bar.n)
    note = _state(status).lower()
    if status.state == render_pb2.RUNNING and status.eta_seconds > 0:
        note += f", {format_duration(status.eta_seconds)} left"
    bar.set_postfix_str(note, refresh=True)


def _watch_to_end(
    client: Client,
    job_id: str,
    *,
    quiet: bool,
    time_limit: float | None = None,
    view: LiveView | None = None,
) -> int:
    """Follows the job (its image in ``view`` to the last); 0 when it SUCCEEDED (or its
    time limit stopped it with samples done), else a CommandError naming its state and
    error."""
    started = time.monotonic()
    try:
        status = follow(client, job_id, quiet=quiet, time_limit=time_limit, view=view)
    except KeyboardInterrupt:
        raise CommandError(
            f"stopped watching; job {job_id} goes on (`yarf cancel {job_id}` stops it)", 130
        ) from None
    if view is not None:
        view.finish(client, status)
    try:
        check_ended(status, time_limit, time.monotonic() - started)
    except RenderError as error:
        raise CommandError(str(error), JOB_DID_NOT_SUCCEED) from None
    ended = "SUCCEEDED" if status.state == render_pb2.SUCCEEDED else "stopped at its time limit"
    print(
        f"job {job_id} {ended}: {status.samples_done} spp in "
        f"{format_duration(status.elapsed_seconds)}"
    )
    return 0


def submit_command(args: argparse.Namespace) -> int:
    if args.priority is not None and not 1 <= args.priority <= 100:
        raise CommandError(f"--priority must be 1 to 100, not {args.priority}", exit_code=2)
    settings = checked_settings(args)
    if settings.time_limit is not None and not args.watch:
        # The server has no time limit of its own: the command that watches enforces it.
        raise CommandError(
            "--time-limit needs --watch: the job is stopped by the command that follows it",
            exit_code=2,
        )
    job, assets = prepare_job(args, settings)
    base_dir = Path(args.scene).parent
    with _job_server(args) as client:
        _send_assets(client, assets, job.scene, base_dir, quiet=args.quiet)
        job_id = submit_job(
            client,
            job,
            settings,
            name=args.name or Path(args.scene).name,
            priority=args.priority,
            max_retries=args.max_retries,
        )
        # The id alone on stdout, for `JOB=$(yarf submit scene.json)`.
        print(job_id, flush=True)
        if args.watch:
            with _about_job(job_id):
                return _watch_to_end(
                    client, job_id, quiet=args.quiet, time_limit=settings.time_limit
                )
    return 0


def watch_command(args: argparse.Namespace) -> int:
    with live_view(args) as view, _job_server(args) as client, _about_job(args.job):
        return _watch_to_end(client, args.job, quiet=args.quiet, view=view)


def _status_lines(status: render_pb2.JobStatus) -> Iterator[tuple[str, str]]:
    yield "job", status.job_id
    yield "name", printable(status.name)
    yield "owner", printable(status.owner) or "-"
    yield "state", _state(status)
    yield "priority", str(status.priority or "-")
    yield "progress", f"{status.samples_done}/{status.samples_total} spp ({status.percent:.0f}%)"
    yield "elapsed", format_duration(status.elapsed_seconds)
    if status.state == render_pb2.RUNNING and status.eta_seconds > 0:
        yield "eta", format_duration(status.eta_seconds)
    if status.attempts:
        yield "attempts", str(status.attempts)
    if status.submitted_at:
        when = time.strftime("%Y-%m-%d %H:%M:%S %Z", time.localtime(status.submitted_at))
        yield "submitted", when
    if status.error:
        yield "error", printable(status.error)


def status_command(args: argparse.Namespace) -> int:
    with _job_server(args) as client, _about_job(args.job):
        status = client.status(args.job)
    if args.json:
        print(json_format.MessageToJson(status, preserving_proto_field_name=True))
    else:
        for key, value in _status_lines(status):
            print(f"{key:<10} {value}")
    return 0


def cancel_command(args: argparse.Namespace) -> int:
    with _job_server(args) as client, _about_job(args.job):
        status = client.cancel(args.job)
    if status.state == render_pb2.RUNNING:
        print(f"job {args.job}: cancel requested; it stops within a second")
    elif status.state in (render_pb2.SUCCEEDED, render_pb2.FAILED):
        print(f"job {args.job} had already ended: {_state(status)}")
    else:
        print(f"job {args.job} {_state(status)}")
    return 0


def _progress(status: render_pb2.JobStatus) -> str:
    return f"{status.percent:3.0f}% {status.samples_done}/{status.samples_total}"


def _short(name: str) -> str:
    name = printable(name)
    return name if len(name) <= NAME_COLUMN else name[: NAME_COLUMN - 1] + "…"


def list_command(args: argparse.Namespace) -> int:
    with _job_server(args) as client:
        jobs = client.list()
    if args.json:
        for job in jobs:
            print(json_format.MessageToJson(job, preserving_proto_field_name=True, indent=None))
        return 0
    header = ("JOB", "NAME", "OWNER", "STATE", "PRIORITY", "PROGRESS")
    rows = [
        (
            job.job_id,
            _short(job.name),
            printable(job.owner) or "-",
            _state(job),
            str(job.priority or "-"),
            _progress(job),
        )
        for job in jobs
    ]
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]
    for row in [header, *rows]:
        print(
            "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
        )
    return 0


def fetch_command(args: argparse.Namespace) -> int:
    output = Path(args.output)
    image = output_settings(args, output)
    if args.denoise:
        check_denoiser()
    with _job_server(args) as client, _about_job(args.job):
        try:
            status = client.fetch(
                args.job,
                output,
                half=image.half,
                exposure=image.exposure,
                tonemap=image.tonemap,
                denoise=args.denoise,
            )
        except DenoiseError as error:
            raise CommandError(f"--denoise: {error}") from None
        except RuntimeError as error:
            raise CommandError(str(error)) from None
    kind = "image" if status.state == render_pb2.SUCCEEDED else f"{_state(status)} job's image"
    print(
        f"wrote {output.resolve()} ({kind}, {status.samples_done}/{status.samples_total} spp, "
        f"job {args.job})"
    )
    return 0


def priority_command(args: argparse.Namespace) -> int:
    if not 1 <= args.priority <= 100:
        raise CommandError(f"the priority must be 1 to 100, not {args.priority}", exit_code=2)
    with _job_server(args) as client, _about_job(args.job):
        try:
            status = client.set_priority(args.job, args.priority)
        except grpc.RpcError as error:
            if isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.UNIMPLEMENTED:
                raise CommandError("this yarfd cannot change priorities (no SetPriority)") from None
            raise
    print(f"job {status.job_id} priority {status.priority} ({_state(status)})")
    return 0


def dashboard_command(args: argparse.Namespace) -> int:
    try:
        web_dir = dashboard.find_web_dir(Path(args.web_dir) if args.web_dir else None)
        host, port = dashboard.parse_listen(args.listen)
    except (FileNotFoundError, ValueError) as error:
        raise CommandError(str(error), exit_code=2) from None
    with (
        _job_server(args) as client,
        dashboard.DashboardServer((host, port), client, web_dir) as web,
    ):
        print(
            f"dashboard of the yarfd at {client.address}: {web.url} (Ctrl-C stops it)", flush=True
        )
        try:
            web.serve_forever()
        except KeyboardInterrupt:
            pass
    return 0


def add_server_option(command: argparse.ArgumentParser) -> None:
    command.add_argument(
        "--server",
        metavar="ADDR",
        help=f"yarfd address host:port (default: {DEFAULT_ADDRESS})",
    )


def add_job_commands(
    commands: argparse._SubParsersAction[argparse.ArgumentParser],
    add_import_options: Callable[[argparse.ArgumentParser], None],
) -> None:
    """Adds the job verbs to the ``yarf`` parser."""

    def job_command(name: str, summary: str) -> argparse.ArgumentParser:
        command = commands.add_parser(name, help=summary, description=summary)
        command.add_argument("job", help="job id, as `yarf submit` printed it")
        add_server_option(command)
        return command

    submit = commands.add_parser(
        "submit", help="queue a scene file on the server and print the job id"
    )
    submit.add_argument(
        "scene",
        help="scene file: protobuf JSON (.json) or text (.textproto), Mitsuba 3 (.xml) or "
        "pbrt-v4 (.pbrt)",
    )
    add_render_arguments(submit, spp_default="default: the file's, else 16")
    submit.add_argument("--name", help="the job's name in listings (default: the file name)")
    submit.add_argument(
        "--priority", type=int, metavar="P", help="1 (lowest) to 100 (highest); default 50"
    )
    submit.add_argument(
        "--max-retries",
        type=int,
        metavar="N",
        help="queue the job again up to N times (at most 10) if it fails (default 0)",
    )
    submit.add_argument(
        "--watch", action="store_true", help="follow the job to its end, as `yarf watch` does"
    )
    submit.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    add_import_options(submit)
    add_server_option(submit)
    submit.set_defaults(handler=submit_command)

    status = job_command("status", "show a job's state, progress, priority and owner")
    status.add_argument("--json", action="store_true", help="the JobStatus as JSON")
    status.set_defaults(handler=status_command)

    watch = job_command(
        "watch", "follow a job to its end; exit 0 if it SUCCEEDED, 1 if it failed or was cancelled"
    )
    watch.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    add_display_argument(watch)
    watch.set_defaults(handler=watch_command)

    cancel = job_command("cancel", "stop a queued or running job")
    cancel.set_defaults(handler=cancel_command)

    listing = commands.add_parser(
        "list", help="table of the server's jobs, newest first (id, name, owner, state, ...)"
    )
    listing.add_argument("--json", action="store_true", help="one JobStatus as JSON per line")
    add_server_option(listing)
    listing.set_defaults(handler=list_command)

    fetch = job_command("fetch", "write a job's image, final or progressive so far")
    fetch.add_argument("-o", "--output", required=True, help="image to write (.exr or .png)")
    add_image_arguments(fetch)
    add_denoise_argument(fetch)
    fetch.set_defaults(handler=fetch_command)

    priority = job_command("priority", "move a queued job in the queue")
    priority.add_argument("priority", type=int, help="1 (lowest) to 100 (highest)")
    priority.set_defaults(handler=priority_command)

    web = commands.add_parser(
        "dashboard", help="serve a web page of the server's queue, with previews and controls"
    )
    web.add_argument(
        "--listen",
        default=dashboard.DEFAULT_LISTEN,
        metavar="HOST:PORT",
        help=f"where the page is served (default {dashboard.DEFAULT_LISTEN}; port 0: any free)",
    )
    web.add_argument("--web-dir", help="folder of the page's files (default: clients/web)")
    add_server_option(web)
    web.set_defaults(handler=dashboard_command)
