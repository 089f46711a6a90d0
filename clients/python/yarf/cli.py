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
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import grpc
from tqdm import tqdm

from yarf.assets import SceneAssets, scene_assets
from yarf.client import DEFAULT_ADDRESS, FINAL_STATES, IMAGE_FORMATS, Client
from yarf.credentials import resolve as resolve_credentials
from yarf.scene import (
    IMPORTED_SUFFIXES,
    JSON_SUFFIXES,
    TEXT_SUFFIXES,
    ImportedScene,
    SceneError,
    import_scene,
    inline_mesh_files,
    load_scene,
    write_scene,
)
from yarf.server import LocalServer, ServerError
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
                raise CommandError(f"no yarfd answers at {address}") from None
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


def _follow(client: Client, job_id: str, *, total: int | None, quiet: bool) -> render_pb2.JobStatus:
    """Shows the job's progress until it ends; returns its final status."""
    last: render_pb2.JobStatus | None = None
    with tqdm(total=total, unit="spp", disable=quiet, dynamic_ncols=True, leave=True) as bar:
        for status in client.watch(job_id):
            last = status
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


def _class_at(text: str) -> tuple[str, str]:
    """CLASS or CLASS@ADDRESS: a class, and the component process serving it (or "")."""
    class_name, _, address = text.partition("@")
    if not class_name:
        raise CommandError(f"expected CLASS or CLASS@ADDRESS, got {text!r}", exit_code=2)
    return class_name, address


def _replace_materials(scene: scene_pb2.Scene, replacements: Sequence[str]) -> None:
    """--material NAME=CLASS[@ADDRESS]: the material NAME, or every material
    of class NAME, becomes CLASS (served at ADDRESS), keeping its properties."""
    for replacement in replacements:
        old, equals, new = replacement.partition("=")
        if not equals or not old:
            raise CommandError(
                f"--material needs NAME=CLASS[@ADDRESS], got {replacement!r}", exit_code=2
            )
        class_name, address = _class_at(new)
        matched = [m for m in scene.materials if old in (m.name, m.class_name)]
        if not matched:
            names = ", ".join(sorted({m.name for m in scene.materials}))
            raise CommandError(
                f"--material {old}: no material or material class of that name (materials: "
                f"{names})",
                exit_code=2,
            )
        for material in matched:
            material.class_name = class_name
            material.address = address


def _transport(args: argparse.Namespace, scene: scene_pb2.Scene) -> scene_pb2.ComponentSpec | None:
    """The job's transport: --transport and --max-depth over the scene's choice."""
    if not args.transport and args.max_depth is None:
        return None
    spec = scene_pb2.ComponentSpec()
    class_name, address = _class_at(args.transport) if args.transport else ("", "")
    if class_name and class_name != scene.transport.class_name:
        spec.class_name = class_name
        spec.address = address
    else:
        spec.CopyFrom(scene.transport)
        spec.class_name = spec.class_name or "path"
    if args.max_depth is not None:
        spec.properties.values["max_depth"].int_value = args.max_depth
    return spec


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


def render_command(args: argparse.Namespace) -> int:
    output = Path(args.output)
    output_format = OUTPUT_FORMATS.get(output.suffix.lower())
    if output_format is None:
        raise CommandError(
            f"cannot write {output}: the output's extension must be one of "
            f"{', '.join(OUTPUT_FORMATS)}",
            exit_code=2,
        )
    scene_path = Path(args.scene)
    spp = args.spp
    if scene_path.suffix.lower() in IMPORTED_SUFFIXES:
        imported = _import(scene_path, args.define, inline_files=False, strict=args.strict)
        scene = imported.scene
        spp = spp or imported.sample_count
    else:
        if args.define:
            raise CommandError("-D sets parameters of Mitsuba scenes only", exit_code=2)
        scene = load_scene(scene_path, inline_files=False)
    _replace_materials(scene, args.material)
    # Before any server is asked for: a missing or misplaced file fails here.
    assets = scene_assets(scene, scene_path.parent)
    with connect(args.server) as client:
        _send_assets(client, assets, scene, scene_path.parent, quiet=args.quiet)
        job_id = client.submit(
            scene,
            spp,
            args.seed,
            name=scene_path.name,
            transport=_transport(args, scene),
            component_retries=args.component_retries,
        )
        try:
            status = _follow(client, job_id, total=spp or None, quiet=args.quiet)
        except KeyboardInterrupt:
            client.cancel(job_id)
            raise
        if status.state != render_pb2.SUCCEEDED:
            state = render_pb2.JobState.Name(status.state)
            raise CommandError(f"job {job_id} {state}: {status.error or 'no message'}")
        image = client.encoded(job_id, output_format)
    if not image:
        raise CommandError(f"the server sent an empty {output.suffix} image for job {job_id}")
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_bytes(image)
    print(
        f"wrote {output.resolve()} ({status.samples_done} spp, "
        f"{status.elapsed_seconds:.2f} s, job {job_id})"
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
    if source.suffix.lower() in IMPORTED_SUFFIXES:
        imported = _import(source, args.define, inline_files=not same_folder, strict=args.strict)
        scene, sample_count = imported.scene, imported.sample_count
    else:
        if args.define:
            raise CommandError("-D sets parameters of Mitsuba scenes only", exit_code=2)
        scene, sample_count = load_scene(source, inline_files=False), 0
        if not same_folder:
            inline_mesh_files(scene, source.parent)
    write_scene(scene, target)
    note = f"; the file asks for {sample_count} spp (--spp {sample_count})" if sample_count else ""
    print(f"wrote {target}{note}")
    return 0


def classes_command(args: argparse.Namespace) -> int:
    with connect(args.server) as client:
        reply = client.list_classes()
    for info in sorted(reply.classes, key=lambda info: info.class_name):
        interfaces = ", ".join(info.interfaces)
        print(f"{info.class_name:<22} {info.version:<9} {interfaces}  [{info.origin}]")
    if reply.plugin_errors:
        print("plugins that failed to load:")
        for error in reply.plugin_errors:
            print(f"  {error.path}: {error.message}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="yarf", description="Render scene files on a yarf render server (yarfd)."
    )
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
    render.add_argument(
        "--spp",
        type=int,
        default=0,
        help="samples per pixel (default: the Mitsuba or pbrt file's, else the server's, 16)",
    )
    add_import_options(render)
    render.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    render.add_argument(
        "--transport",
        metavar="CLASS[@ADDRESS]",
        help="light transport: path, light, bdpt, whitted, distribution, or a class of the "
        "component process at ADDRESS (default: the scene's)",
    )
    render.add_argument(
        "--material",
        action="append",
        default=[],
        metavar="NAME=CLASS[@ADDRESS]",
        help="make the material NAME (or every material of class NAME) a CLASS, served by the "
        "component process at ADDRESS (host:port or unix:/path) when given; its properties stay",
    )
    render.add_argument(
        "--component-retries",
        type=int,
        default=0,
        metavar="N",
        help="retry a call N times on a restarted component process before failing (default 0)",
    )
    render.add_argument(
        "--max-depth",
        type=int,
        metavar="N",
        help="longest path in segments (1: emitters only, -1: unbounded)",
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
    add_server_option(classes)
    classes.set_defaults(handler=classes_command)

    # Imported here: the job verbs use this module's helpers.
    from yarf.jobs_cli import add_job_commands

    add_job_commands(commands, add_import_options)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    credentials = _CREDENTIALS.set((args.token, args.ca))
    try:
        return int(args.handler(args))
    except CommandError as error:
        _say(f"error: {error}")
        return error.exit_code
    except SceneError as error:
        _say(f"error: {error}")
        return 2
    except ServerError as error:
        _say(f"error: {error}")
        return 1
    except grpc.RpcError as error:
        code = error.code().name if isinstance(error, grpc.Call) else "RPC"
        details = error.details() if isinstance(error, grpc.Call) else str(error)
        _say(f"error: {code}: {details}")
        return 1
    except KeyboardInterrupt:
        _say("interrupted")
        return 130
    finally:
        _CREDENTIALS.reset(credentials)


if __name__ == "__main__":
    sys.exit(main())
