"""The ``yarf`` command: render a scene file on a yarfd, list its classes and jobs.

Without ``--server`` the command uses a yarfd on 127.0.0.1:50051 when one
answers there, and otherwise starts one on this machine for the command's
duration (the embedded default).

Mitsuba 3 (.xml) and pbrt-v4 (.pbrt) scenes render directly: yarf-import
converts them (its warnings are shown), and their sample count is the
default of ``--spp``. ``yarf convert`` writes the converted scene.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import NoReturn

import grpc
import numpy as np
from tqdm import tqdm

from yarf.assets import SceneAssets, scene_assets
from yarf.class_reference import describe_class, find_class, markdown_reference
from yarf.client import (
    DEFAULT_ADDRESS,
    FINAL_STATES,
    IMAGE_FORMATS,
    Client,
    RenderError,
    SubmitWarning,
    check_ended,
)
from yarf.credentials import resolve as resolve_credentials
from yarf.denoise import DENOISE_AOVS, DenoiseError, denoise, denoiser, missing_aovs
from yarf.images import check_writable, write_image
from yarf.live_view import LiveView
from yarf.render_options import (
    ImageSettings,
    OptionError,
    PreparedJob,
    RenderSettings,
    add_denoise_argument,
    add_display_argument,
    add_image_arguments,
    add_render_arguments,
    display_address,
    image_settings,
    render_settings,
)
from yarf.scene import (
    JSON_SUFFIXES,
    TEXT_SUFFIXES,
    ImportedScene,
    SceneError,
    import_scene,
    inline_mesh_files,
    is_imported_scene,
    load_scene,
    write_scene,
)
from yarf.server import LocalServer, ServerError
from yarf.tev import TevError
from yarf.v1 import render_pb2, scene_pb2

OUTPUT_FORMATS = IMAGE_FORMATS
CONNECT_TIMEOUT = 5.0
# The global --token and --ca of the running command (None: $YARF_TOKEN,
# $YARF_TLS_CA), for every connect() of its subcommand.
_CREDENTIALS: ContextVar[tuple[str | None, str | None]] = ContextVar(
    "yarf_credentials", default=(None, None)
)


class CommandError(Exception):
    """A failure the command reports in one line, with an exit code."""

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code


def _say(message: str) -> None:
    print(f"yarf: {message}", file=sys.stderr)


def start_hint(address: str) -> str:
    """How to start a yarfd at ``address``, for a command that found none."""
    return (
        f"start one with `yarfd --listen {address}` (build/bin/yarfd in a source tree), "
        "or name another with --server HOST:PORT"
    )


@contextmanager
def connect(address: str | None, *, say: Callable[[str], None] = _say) -> Iterator[Client]:
    """A client of ``address``; without one, of 127.0.0.1:50051 or a local yarfd."""
    token, tls_ca = _CREDENTIALS.get()
    ca_file = resolve_credentials(token, tls_ca)[1]
    if ca_file and not Path(ca_file).is_file():
        raise CommandError(f"cannot read the TLS CA certificate {ca_file}")
    if address:
        with Client(address, token=token, tls_ca=tls_ca) as client:
            try:
                grpc.channel_ready_future(client.channel).result(timeout=CONNECT_TIMEOUT)
            except grpc.FutureTimeoutError:
                raise CommandError(
                    f"no yarfd answers at {address}: {start_hint(address)}"
                ) from None
            yield client
        return
    with Client(DEFAULT_ADDRESS, token=token, tls_ca=tls_ca) as client:
        if client.is_serving(timeout=0.5):
            say(f"using the yarfd at {DEFAULT_ADDRESS}")
            yield client
            return
    say("no yarfd at 127.0.0.1:50051: starting one for this command")
    with LocalServer() as server, server.client() as client:
        yield client


@contextmanager
def live_view(args: argparse.Namespace) -> Iterator[LiveView | None]:
    """The tev viewer of ``--display``, connected before anything renders; None without
    the option."""
    try:
        address = display_address(args)
    except OptionError as error:
        raise CommandError(error.for_command_line(), exit_code=2) from None
    if address is None:
        yield None
        return
    try:
        view = LiveView.connect(*address)
    except TevError as error:
        raise CommandError(
            f"--display: {error}: start tev first, or leave out --display", exit_code=2
        ) from None
    with view:
        yield view


def _follow(
    client: Client,
    job_id: str,
    *,
    total: int | None,
    quiet: bool,
    time_limit: float | None,
    view: LiveView | None = None,
) -> render_pb2.JobStatus:
    """Shows the job's progress (and its image in ``view``) until it ends (cancelled at
    ``time_limit`` seconds); returns its final status."""
    last: render_pb2.JobStatus | None = None
    with tqdm(total=total, unit="spp", disable=quiet, dynamic_ncols=True, leave=True) as bar:
        for status in client.watch_within(job_id, time_limit):
            last = status
            if view is not None:
                view.progress(client, status)
            if status.samples_total and bar.total != status.samples_total:
                bar.total = status.samples_total
                bar.refresh()
            if status.samples_done > bar.n:
                bar.update(status.samples_done - bar.n)
            bar.set_postfix_str(render_pb2.JobState.Name(status.state).lower(), refresh=True)
    if last is None or last.state not in FINAL_STATES:
        last = client.status(job_id)
    return last


def _parameters(definitions: Sequence[str]) -> dict[str, str]:
    """``["res=64", ...]`` from ``-D`` options as a mapping."""
    parameters: dict[str, str] = {}
    for definition in definitions:
        name, equals, value = definition.partition("=")
        if not equals or not name:
            raise CommandError(f"-D needs NAME=VALUE, got {definition!r}", exit_code=2)
        parameters[name] = value
    return parameters


def _import(
    path: Path, definitions: Sequence[str], *, inline_files: bool, strict: bool = False
) -> ImportedScene:
    """Converts a Mitsuba or pbrt scene, showing what was ignored or approximated
    (``strict``: refusing it)."""
    imported = import_scene(
        path, parameters=_parameters(definitions), inline_files=inline_files, strict=strict
    )
    for warning in imported.warnings:
        _say(f"warning: {warning}")
    return imported


def load_scene_file(args: argparse.Namespace) -> ImportedScene:
    """The scene file of ``args.scene`` (mesh files still files), with the spp and
    crop a Mitsuba or pbrt file asks for."""
    path = Path(args.scene)
    if is_imported_scene(path):
        return _import(path, args.define, inline_files=False, strict=args.strict)
    if args.define:
        raise CommandError("-D sets parameters of Mitsuba scenes only", exit_code=2)
    return ImportedScene(load_scene(path, inline_files=False))


def checked_settings(args: argparse.Namespace) -> RenderSettings:
    """The command's render options, each checked."""
    try:
        return render_settings(args)
    except OptionError as error:
        raise CommandError(error.for_command_line(), exit_code=2) from None


def prepare_job(
    args: argparse.Namespace, settings: RenderSettings
) -> tuple[PreparedJob, SceneAssets]:
    """The scene file with the options applied, and its mesh and texture files: every
    failure here comes before any server is asked for."""
    loaded = load_scene_file(args)
    try:
        job = settings.prepare(
            loaded.scene, default_spp=loaded.sample_count, default_crop=loaded.crop
        )
    except OptionError as error:
        raise CommandError(error.for_command_line(), exit_code=2) from None
    return job, scene_assets(job.scene, Path(args.scene).parent)


def output_settings(args: argparse.Namespace, output: Path) -> ImageSettings:
    """The image options for ``output``, checked, and ``output`` checked writable."""
    suffix = output.suffix.lower()
    if suffix not in OUTPUT_FORMATS:
        raise CommandError(
            f"cannot write {output}: the output's extension must be one of "
            f"{', '.join(OUTPUT_FORMATS)}",
            exit_code=2,
        )
    try:
        settings = image_settings(args, suffix)
    except OptionError as error:
        raise CommandError(error.for_command_line(), exit_code=2) from None
    try:
        check_writable(output)
    except OSError as error:
        raise CommandError(f"cannot write {output}: {error.strerror or error}", 2) from None
    return settings


def submit_job(
    client: Client,
    job: PreparedJob,
    settings: RenderSettings,
    *,
    name: str,
    component_retries: int = 0,
    priority: int | None = None,
    max_retries: int | None = None,
) -> str:
    """Submits the prepared job, saying what the server warns of; a request
    the server refuses is a usage error."""
    try:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always", SubmitWarning)
            job_id = client.submit(
                job.scene,
                job.spp,
                settings.seed,
                name=name,
                transport=job.transport,
                crop=job.crop,
                aovs=job.aovs,
                threads=job.threads,
                component_retries=component_retries,
                priority=priority,
                max_retries=max_retries,
            )
        for warning in said:
            _say(f"warning: {warning.message}")
        return job_id
    except grpc.RpcError as error:
        if isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.INVALID_ARGUMENT:
            raise CommandError(f"the server refused the job: {error.details()}", 2) from None
        raise


def _send_assets(
    client: Client, assets: SceneAssets, scene: scene_pb2.Scene, base_dir: Path, *, quiet: bool
) -> None:
    """Uploads the mesh and texture files the server lacks and names each by its hash.

    A server without AssetService gets the mesh files' bytes inline instead.
    """
    try:
        uploaded = assets.upload(client)
    except grpc.RpcError as error:
        if not (isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.UNIMPLEMENTED):
            raise
        inline_mesh_files(scene, base_dir)
        return
    if uploaded and not quiet:
        _say(f"uploaded {uploaded} file{'s' if uploaded > 1 else ''} the server lacked")


def check_denoiser() -> None:
    """A one-line error, before anything renders, when the denoiser is missing."""
    try:
        denoiser()
    except DenoiseError as error:
        raise CommandError(f"--denoise: {error}") from None


def denoised(pixels: np.ndarray, aovs: dict[str, np.ndarray], job: PreparedJob) -> np.ndarray:
    """The job's image denoised; the image as it is, with a warning, when the job
    stopped before its AOVs were rendered."""
    missing = missing_aovs(aovs)
    if missing:
        _say(
            f"warning: not denoised: the job stopped (at its time limit) before rendering the "
            f"{' and '.join(missing)} AOVs the denoiser takes"
        )
        return pixels
    return denoise(pixels, aovs, window=job.crop)


def render_command(args: argparse.Namespace) -> int:
    output = Path(args.output)
    settings = checked_settings(args)
    image_options = output_settings(args, output)
    if args.denoise:
        check_denoiser()
        settings = settings.with_aovs(DENOISE_AOVS)
    job, assets = prepare_job(args, settings)
    scene_path = Path(args.scene)
    with live_view(args) as view, connect(args.server) as client:
        _send_assets(client, assets, job.scene, scene_path.parent, quiet=args.quiet)
        job_id = submit_job(
            client,
            job,
            settings,
            name=scene_path.name,
            component_retries=args.component_retries,
        )
        started = time.monotonic()
        try:
            status = _follow(
                client,
                job_id,
                total=job.spp or None,
                quiet=args.quiet,
                time_limit=settings.time_limit,
                view=view,
            )
        except KeyboardInterrupt:
            client.cancel(job_id)
            raise
        try:
            check_ended(status, settings.time_limit, time.monotonic() - started)
        except RenderError as error:
            raise CommandError(str(error)) from None
        try:
            final, pixels, aovs, exact = client.image_layers(job_id)
        except RuntimeError as error:
            raise CommandError(str(error)) from None
        if args.denoise:
            pixels = denoised(pixels, aovs, job)
        if view is not None:
            view.finish(client, final, pixels)
    if not exact and output.suffix.lower() == ".exr" and not image_options.half:
        _say("warning: the film is too large for float pixels in one reply: its values are halves")
    write_image(output, pixels, image_options, window=job.crop, aovs=aovs)
    stopped = ", stopped at the time limit" if status.state != render_pb2.SUCCEEDED else ""
    print(
        f"wrote {output.resolve()} ({status.samples_done} spp, "
        f"{status.elapsed_seconds:.2f} s{stopped}, job {job_id})"
    )
    return 0


def convert_command(args: argparse.Namespace) -> int:
    source, target = Path(args.input), Path(args.output)
    if target.suffix.lower() not in JSON_SUFFIXES + TEXT_SUFFIXES:
        expected = ", ".join(JSON_SUFFIXES + TEXT_SUFFIXES)
        raise CommandError(f"cannot write {target}: the extension must be one of {expected}", 2)
    # Mesh files stay files when the output sits beside the input (their
    # names are relative to its folder); elsewhere they are inlined.
    same_folder = source.resolve().parent == target.resolve().parent
    if is_imported_scene(source):
        imported = _import(source, args.define, inline_files=not same_folder, strict=args.strict)
        scene, sample_count, crop = imported.scene, imported.sample_count, imported.crop
    else:
        if args.define:
            raise CommandError("-D sets parameters of Mitsuba scenes only", exit_code=2)
        scene, sample_count, crop = load_scene(source, inline_files=False), 0, ""
        if not same_folder:
            inline_mesh_files(scene, source.parent)
    write_scene(scene, target)
    note = f"; the file asks for {sample_count} spp (--spp {sample_count})" if sample_count else ""
    note += f"; it renders only --crop {crop}" if crop else ""
    print(f"wrote {target}{note}")
    return 0


def classes_command(args: argparse.Namespace) -> int:
    if args.class_name and not args.verbose:
        raise CommandError("a CLASS is described with -v: yarf classes -v CLASS", exit_code=2)
    with connect(args.server) as client:
        reply = client.list_classes()
    if args.markdown:
        # The plugins' classes: a component process's come and go.
        plugins = [info for info in reply.classes if not info.origin.startswith("remote ")]
        print(markdown_reference(plugins), end="")
        return 0
    if args.verbose:
        try:
            shown = (
                [find_class(reply.classes, args.class_name)] if args.class_name else reply.classes
            )
        except LookupError as error:
            raise CommandError(str(error), exit_code=2) from None
        for info in sorted(shown, key=lambda info: info.class_name):
            print("\n".join(describe_class(info)))
        return 0
    for info in sorted(reply.classes, key=lambda info: info.class_name):
        interfaces = ", ".join(info.interfaces)
        print(f"{info.class_name:<22} {info.version:<9} {interfaces}  [{info.origin}]")
    if reply.plugin_errors:
        print("plugins that failed to load:")
        for error in reply.plugin_errors:
            print(f"  {error.path}: {error.message}")
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line: what is wrong, and where help is."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (`{self.prog} --help` lists the options)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="yarf", description="Render scene files on a yarf render server (yarfd).")
    parser.add_argument(
        "--token",
        metavar="TOKEN",
        help="bearer token for a yarfd that requires one (default: $YARF_TOKEN)",
    )
    parser.add_argument(
        "--ca",
        metavar="PEM",
        help="CA or self-signed certificate the yarfd's TLS certificate is checked against "
        "(default: $YARF_TLS_CA, else the system's CAs when a token is given)",
    )
    commands = parser.add_subparsers(dest="command", required=True)

    def add_server_option(command: argparse.ArgumentParser) -> None:
        command.add_argument(
            "--server",
            metavar="ADDR",
            help="yarfd address host:port (default: 127.0.0.1:50051 if it answers, "
            "else a yarfd started for this command)",
        )

    def add_import_options(command: argparse.ArgumentParser) -> None:
        command.add_argument(
            "-D",
            "--define",
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help="set a Mitsuba scene parameter ($NAME), overriding its <default>",
        )
        command.add_argument(
            "--strict",
            action="store_true",
            help="refuse a Mitsuba or pbrt scene with anything that would be ignored or "
            "approximated (every warning an error)",
        )

    render = commands.add_parser("render", help="render a scene file into an EXR or PNG image")
    render.add_argument(
        "scene",
        help="scene file: protobuf JSON (.json) or text (.textproto), Mitsuba 3 (.xml) or "
        "pbrt-v4 (.pbrt)",
    )
    render.add_argument("-o", "--output", required=True, help="image to write (.exr or .png)")
    add_render_arguments(
        render, spp_default="default: the Mitsuba or pbrt file's, else the server's, 16"
    )
    add_image_arguments(render)
    add_denoise_argument(render)
    add_display_argument(render)
    add_import_options(render)
    render.add_argument(
        "--component-retries",
        type=int,
        default=0,
        metavar="N",
        help="retry a call N times on a restarted component process before failing (default 0)",
    )
    render.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    add_server_option(render)
    render.set_defaults(handler=render_command)

    convert = commands.add_parser(
        "convert", help="convert a Mitsuba (.xml) or pbrt (.pbrt) scene into a yarf scene file"
    )
    convert.add_argument("input", help="scene file (.xml, .pbrt, .json or .textproto)")
    convert.add_argument("output", help="yarf scene to write (.json or .textproto)")
    add_import_options(convert)
    convert.set_defaults(handler=convert_command)

    classes = commands.add_parser("classes", help="list the server's classes and plugin errors")
    classes.add_argument(
        "class_name", nargs="?", metavar="CLASS", help="with -v: describe this class alone"
    )
    classes.add_argument(
        "-v", "--verbose", action="store_true", help="each class's parameters: type, default, range"
    )
    classes.add_argument(
        "--markdown",
        action="store_true",
        help="the plugin reference of the plugins' classes in Markdown (docs/plugins.md)",
    )
    add_server_option(classes)
    classes.set_defaults(handler=classes_command)

    # Imported here: the job verbs use this module's helpers.
    from yarf.jobs_cli import add_job_commands

    add_job_commands(commands, add_import_options)
    return parser


def _stdout_gone() -> None:
    """After a reader of stdout went away (``yarf list | head -1``): later writes,
    and the flush at exit, go nowhere instead of failing again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass  # stdout is not a file descriptor (captured): nothing is flushed to it
    finally:
        os.close(devnull)


def main(argv: Sequence[str] | None = None) -> int:
    """Runs one ``yarf`` command; every failure is one line on stderr and an exit code
    (2: a bad command line or value, 1: a failure, 130: interrupted, 141: stdout closed)."""
    args = build_parser().parse_args(argv)
    credentials = _CREDENTIALS.set((args.token, args.ca))
    try:
        code = int(args.handler(args))
        sys.stdout.flush()
        return code
    except CommandError as error:
        _say(f"error: {error}")
        return error.exit_code
    except (SceneError, OptionError) as error:
        _say(f"error: {error}")
        return 2
    except ServerError as error:
        _say(f"error: {error}")
        return 1
    except grpc.RpcError as error:
        code_name = error.code().name if isinstance(error, grpc.Call) else "RPC"
        details = error.details() if isinstance(error, grpc.Call) else str(error)
        message = f"error: {code_name}: {details}"
        if isinstance(error, grpc.Call) and error.code() == grpc.StatusCode.UNAVAILABLE:
            address = getattr(args, "server", None) or DEFAULT_ADDRESS
            message += f" (is a yarfd running at {address}? {start_hint(address)})"
        _say(message)
        return 1
    except BrokenPipeError:
        _stdout_gone()
        return 141
    except KeyboardInterrupt:
        _say("interrupted")
        return 130
    except OSError as error:
        _say(f"error: {error}")
        return 1
    except Exception as error:  # no traceback reaches a user
        if os.environ.get("YARF_TRACEBACK"):
            raise
        _say(
            f"error: unexpected {type(error).__name__}: {error} "
            "(YARF_TRACEBACK=1 shows where; please report it)"
        )
        return 1
    finally:
        _CREDENTIALS.reset(credentials)


if __name__ == "__main__":
    sys.exit(main())
