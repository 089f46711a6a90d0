"""The options of a render, defined once for ``yarf render``, ``yarf submit`` and
``Client.render``.

``RenderSettings`` says what to render (samples, seed, film size, crop
window, time limit, transport, materials, path depth, arbitrary output
variables) and ``ImageSettings``
how to write the image (float or half EXR; PNG exposure and tone curve).
Both check every value before any server is asked for; a bad one raises
``OptionError`` naming the option. ``add_render_arguments`` and
``add_image_arguments`` give the same options to an argparse command, and
``render_settings`` / ``image_settings`` read them back.
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Literal

from yarf.v1 import render_pb2, scene_pb2

# The ranges the IDL states: RenderOptions.spp, Film.width and Film.height.
MAX_SPP = 1 << 20
MAX_FILM_SIDE = 16384
MAX_FILM_PIXELS = 1 << 26
# A sanity bound: the server runs a job on at most its own threads.
MAX_THREADS = 1 << 16

# The arbitrary output variables a job can ask for (RenderOptions.aovs), in the
# order the server lists them: kAovNames of server/include/yarf/aov.h, which
# tests/test_denoise_and_aov_cli.py checks this against.
AOV_NAMES: tuple[str, ...] = (
    "albedo",
    "sh_normal",
    "geo_normal",
    "depth",
    "position",
    "uv",
    "shape_index",
    "material_index",
)

Tonemap = Literal["linear", "aces"]
TONEMAPS: tuple[Tonemap, ...] = ("linear", "aces")


class OptionError(ValueError):
    """A bad value of a render or image option; ``option`` is its keyword name."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{option}: {message}")
        self.option = option
        self.message = message

    def for_command_line(self) -> str:
        """The message with the option as the command line spells it (``--max-depth``)."""
        return f"--{self.option.replace('_', '-')}: {self.message}"


@dataclass(frozen=True)
class CropWindow:
    """pbrt's --pixelbounds (pixels, ``fraction`` False) or --cropwindow (fractions of
    the film, ``fraction`` True): x0 ≤ x < x1, y0 ≤ y < y1, y down."""

    x0: float
    x1: float
    y0: float
    y1: float
    fraction: bool = False

    def pixels(self, width: int, height: int) -> render_pb2.PixelWindow:
        """The window in pixels of a width × height film; OptionError when it is not inside."""
        if self.fraction:
            # pbrt-v4's rounding of a crop window to pixels.
            x0, x1 = (math.ceil(width * v) for v in (self.x0, self.x1))
            y0, y1 = (math.ceil(height * v) for v in (self.y0, self.y1))
        else:
            x0, x1, y0, y1 = int(self.x0), int(self.x1), int(self.y0), int(self.y1)
        if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
            raise OptionError(
                "crop",
                f"[{x0}, {x1}) x [{y0}, {y1}) is not a window of the {width}x{height} film",
            )
        return render_pb2.PixelWindow(x0=x0, x1=x1, y0=y0, y1=y1)


def parse_res(text: str) -> tuple[int, int]:
    """``"640x480"`` as (640, 480)."""
    width, x, height = text.lower().partition("x")
    if not x or not width.strip().isdigit() or not height.strip().isdigit():
        raise OptionError("res", f"expected WIDTHxHEIGHT (e.g. 640x480), got {text!r}")
    return int(width), int(height)


def parse_crop(text: str) -> CropWindow:
    """``"x0,x1,y0,y1"``: pixels as integers, or fractions of the film with a decimal point."""
    parts = [part.strip() for part in text.split(",")]
    if len(parts) != 4:
        raise OptionError("crop", f"expected x0,x1,y0,y1, got {text!r}")
    fraction = any("." in part for part in parts)
    try:
        values = [float(part) if fraction else int(part) for part in parts]
    except ValueError:
        raise OptionError("crop", f"expected four numbers x0,x1,y0,y1, got {text!r}") from None
    if fraction and not all(0.0 <= v <= 1.0 for v in values):
        raise OptionError("crop", f"fractions of the film must lie in [0, 1], got {text!r}")
    return CropWindow(*values, fraction=fraction)


def parse_materials(definitions: Iterable[str]) -> tuple[tuple[str, str], ...]:
    """``["NAME=CLASS[@ADDRESS]", ...]`` as (NAME, CLASS[@ADDRESS]) pairs."""
    pairs = []
    for definition in definitions:
        old, equals, new = definition.partition("=")
        if not equals or not old or not new.partition("@")[0]:
            raise OptionError("material", f"expected NAME=CLASS[@ADDRESS], got {definition!r}")
        pairs.append((old, new))
    return tuple(pairs)


def parse_aovs(names: str | Iterable[str]) -> tuple[str, ...]:
    """``"albedo,depth"`` (or ``["albedo", "depth"]``) as names of AOV_NAMES, each once."""
    items = names.split(",") if isinstance(names, str) else list(names)
    chosen: list[str] = []
    for item in items:
        name = item.strip()
        if not name:
            raise OptionError("aov", f"expected names separated by commas, got {names!r}")
        if name not in AOV_NAMES:
            close = difflib.get_close_matches(name, AOV_NAMES, n=1, cutoff=0.5)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise OptionError(
                "aov", f"unknown output {name!r} ({hint}known: {', '.join(AOV_NAMES)})"
            )
        if name in chosen:
            raise OptionError("aov", f"{name!r} is named twice")
        chosen.append(name)
    return tuple(chosen)


def class_at(option: str, text: str) -> tuple[str, str]:
    """CLASS or CLASS@ADDRESS: a class, and the component process serving it (or "")."""
    class_name, _, address = text.partition("@")
    if not class_name:
        raise OptionError(option, f"expected CLASS or CLASS@ADDRESS, got {text!r}")
    return class_name, address


@dataclass(frozen=True)
class PreparedJob:
    """A scene with the settings applied, and the RenderOptions fields they set."""

    scene: scene_pb2.Scene
    spp: int
    transport: scene_pb2.ComponentSpec | None
    crop: render_pb2.PixelWindow | None
    aovs: tuple[str, ...] = ()
    threads: int = 0


@dataclass(frozen=True)
class RenderSettings:
    """What to render. ``None`` keeps the scene's (or the server's) choice.

    ``spp``: 1 to 2^20 samples per pixel. ``res``: the film's (width, height).
    ``crop``: only these pixels get samples (an integrator that declares
    sample_passes, as mean_sample).
    ``time_limit``: seconds, after which the job is cancelled and the image
    holds the samples done so far. ``transport``: CLASS[@ADDRESS] or a
    ComponentSpec. ``materials``: (NAME, CLASS[@ADDRESS]) pairs, each making
    the material NAME (or every material of class NAME) a CLASS, its
    properties kept. ``max_depth``: longest path in segments (-1: unbounded).
    ``aovs``: names of AOV_NAMES, rendered beside the image. ``threads``: the
    job's worker threads on the server, at most the server's own.
    """

    spp: int | None = None
    seed: int = 0
    res: tuple[int, int] | None = None
    crop: CropWindow | None = None
    time_limit: float | None = None
    transport: str | scene_pb2.ComponentSpec | None = None
    materials: tuple[tuple[str, str], ...] = field(default_factory=tuple)
    max_depth: int | None = None
    aovs: tuple[str, ...] = ()
    threads: int | None = None

    @classmethod
    def of(
        cls,
        *,
        spp: int | None = None,
        seed: int = 0,
        res: str | tuple[int, int] | None = None,
        crop: str | tuple[float, float, float, float] | CropWindow | None = None,
        time_limit: float | None = None,
        transport: str | scene_pb2.ComponentSpec | None = None,
        materials: Mapping[str, str] | Iterable[str] | None = None,
        max_depth: int | None = None,
        aovs: str | Iterable[str] | None = None,
        threads: int | None = None,
    ) -> RenderSettings:
        """Settings from Python values as a user writes them (``res="640x480"`` or
        ``(640, 480)``, ``crop=(x0, x1, y0, y1)``, ``materials={"red": "plastic"}``,
        ``aovs="albedo,depth"`` or ``["albedo", "depth"]``), checked."""
        if isinstance(res, str):
            res = parse_res(res)
        if isinstance(crop, str):
            crop = parse_crop(crop)
        elif crop is not None and not isinstance(crop, CropWindow):
            values = tuple(crop)
            if len(values) != 4:
                raise OptionError("crop", f"expected (x0, x1, y0, y1), got {crop!r}")
            fraction = any(isinstance(v, float) for v in values)
            crop = parse_crop(",".join(str(float(v) if fraction else v) for v in values))
        if isinstance(materials, Mapping):
            pairs = parse_materials(f"{k}={v}" for k, v in materials.items())
        else:
            pairs = parse_materials(materials or ())
        settings = cls(
            spp=spp,
            seed=seed,
            res=res,
            crop=crop,
            time_limit=time_limit,
            transport=transport,
            materials=pairs,
            max_depth=max_depth,
            aovs=parse_aovs(aovs) if aovs is not None else (),
            threads=threads,
        )
        settings.check()
        return settings

    def check(self) -> None:
        """Raises OptionError for the first value out of its range."""
        if self.spp is not None and not (isinstance(self.spp, int) and 1 <= self.spp <= MAX_SPP):
            raise OptionError("spp", f"must be 1 to {MAX_SPP}, not {self.spp}")
        if not (isinstance(self.seed, int) and 0 <= self.seed < 1 << 64):
            raise OptionError("seed", f"must be 0 to 2^64 - 1, not {self.seed}")
        if self.res is not None:
            width, height = self.res
            if not (1 <= width <= MAX_FILM_SIDE and 1 <= height <= MAX_FILM_SIDE):
                raise OptionError(
                    "res", f"each side must be 1 to {MAX_FILM_SIDE} pixels, not {width}x{height}"
                )
            if width * height > MAX_FILM_PIXELS:
                raise OptionError(
                    "res", f"{width}x{height} has more than 2^26 ({MAX_FILM_PIXELS}) pixels"
                )
        if self.time_limit is not None and not (
            math.isfinite(self.time_limit) and self.time_limit > 0
        ):
            raise OptionError(
                "time_limit", f"must be a positive number of seconds, not {self.time_limit}"
            )
        if isinstance(self.transport, str):
            class_at("transport", self.transport)
        if self.max_depth is not None and self.max_depth < -1:
            raise OptionError(
                "max_depth", f"must be -1 (unbounded) or at least 0, not {self.max_depth}"
            )
        parse_aovs(self.aovs)
        if self.threads is not None and not (
            isinstance(self.threads, int) and 1 <= self.threads <= MAX_THREADS
        ):
            raise OptionError("threads", f"must be 1 to {MAX_THREADS}, not {self.threads}")

    def with_aovs(self, names: Iterable[str]) -> RenderSettings:
        """These settings with the AOVs ``names`` added to theirs (those absent)."""
        extra = tuple(name for name in names if name not in self.aovs)
        return dataclasses.replace(self, aovs=self.aovs + extra)

    def prepare(
        self,
        scene: scene_pb2.Scene,
        *,
        default_spp: int = 0,
        default_crop: str = "",
    ) -> PreparedJob:
        """A copy of ``scene`` with the film size and materials set, the transport and
        crop window for RenderOptions (``default_crop``, as --crop writes it, when unset:
        the part of the film a scene file renders), and the spp (``default_spp`` when
        unset, 0: the server's). OptionError when a setting does not fit the scene."""
        self.check()
        prepared = scene_pb2.Scene()
        prepared.CopyFrom(scene)
        if self.res is not None:
            prepared.film.width, prepared.film.height = self.res
        _replace_materials(prepared, self.materials)
        crop = None
        window = (
            self.crop
            if self.crop is not None
            else parse_crop(default_crop)
            if default_crop
            else None
        )
        if window is not None:
            if not prepared.film.width or not prepared.film.height:
                raise OptionError("crop", "the scene's film has no size: give --res too")
            # Whether the job's integrator can render a crop is the server's
            # check (its class's capabilities).
            crop = window.pixels(prepared.film.width, prepared.film.height)
        return PreparedJob(
            scene=prepared,
            spp=self.spp or default_spp,
            transport=self._transport(prepared),
            crop=crop,
            aovs=self.aovs,
            threads=self.threads or 0,
        )

    def _transport(self, scene: scene_pb2.Scene) -> scene_pb2.ComponentSpec | None:
        """The job's transport: ``transport`` and ``max_depth`` over the scene's choice."""
        if self.transport is None and self.max_depth is None:
            return None
        spec = scene_pb2.ComponentSpec()
        if isinstance(self.transport, scene_pb2.ComponentSpec):
            spec.CopyFrom(self.transport)
        elif self.transport and class_at("transport", self.transport)[0] != (
            scene.transport.class_name
        ):
            spec.class_name, spec.address = class_at("transport", self.transport)
        else:
            # The scene's transport (path when it names none), with its properties.
            spec.CopyFrom(scene.transport)
            spec.class_name = spec.class_name or "path"
        if self.max_depth is not None:
            spec.properties.values["max_depth"].int_value = self.max_depth
        return spec


def _replace_materials(scene: scene_pb2.Scene, replacements: Iterable[tuple[str, str]]) -> None:
    for old, new in replacements:
        class_name, address = class_at("material", new)
        matched = [m for m in scene.materials if old in (m.name, m.class_name)]
        if not matched:
            names = ", ".join(sorted({m.name for m in scene.materials}))
            raise OptionError(
                "material", f"{old}: no material or material class of that name ({names})"
            )
        for material in matched:
            material.class_name = class_name
            material.address = address


@dataclass(frozen=True)
class ImageSettings:
    """How an image file is written: EXR as float32 (``half``: 16-bit floats); PNG
    scaled by 2^``exposure`` then mapped by ``tonemap`` (linear: clamped; aces:
    the ACES filmic curve) before the sRGB transfer."""

    half: bool = False
    exposure: float = 0.0
    tonemap: Tonemap = "linear"

    def check(self, suffix: str) -> None:
        """Raises OptionError for a value out of range or one the file format ignores."""
        if not math.isfinite(self.exposure):
            raise OptionError("exposure", f"must be a finite number of stops, not {self.exposure}")
        if self.tonemap not in TONEMAPS:
            raise OptionError(
                "tonemap", f"must be one of {', '.join(TONEMAPS)}, not {self.tonemap!r}"
            )
        if suffix == ".exr" and (self.exposure != 0.0 or self.tonemap != "linear"):
            option = "exposure" if self.exposure != 0.0 else "tonemap"
            raise OptionError(option, "applies to PNG images; an EXR keeps linear radiance")
        if suffix == ".png" and self.half:
            raise OptionError("half", "applies to EXR images; a PNG has 8-bit values")


def add_render_arguments(command: argparse.ArgumentParser, *, spp_default: str) -> None:
    """The options of RenderSettings, as ``yarf render`` and ``yarf submit`` take them."""
    command.add_argument(
        "--spp", type=int, metavar="N", help=f"samples per pixel, 1 to {MAX_SPP} ({spp_default})"
    )
    command.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    command.add_argument(
        "--res",
        metavar="WxH",
        help="film size in pixels, for every scene format (default: the scene's)",
    )
    command.add_argument(
        "--crop",
        metavar="x0,x1,y0,y1",
        help="render only pixels x0 <= x < x1, y0 <= y < y1 (y down; pbrt's --pixelbounds), "
        "or fractions of the film when written with a decimal point (pbrt's --cropwindow, "
        "e.g. 0.25,0.75,0.0,0.5); the image holds the window alone",
    )
    command.add_argument(
        "--time-limit",
        type=float,
        metavar="SECONDS",
        help="stop the render after SECONDS; the image holds the samples done by then",
    )
    command.add_argument(
        "--transport",
        metavar="CLASS[@ADDRESS]",
        help="light transport: path, light, bdpt, whitted, distribution, or a class of the "
        "component process at ADDRESS (default: the scene's)",
    )
    command.add_argument(
        "--material",
        action="append",
        default=[],
        metavar="NAME=CLASS[@ADDRESS]",
        help="make the material NAME (or every material of class NAME) a CLASS, served by the "
        "component process at ADDRESS (host:port or unix:/path) when given; its properties stay",
    )
    command.add_argument(
        "--max-depth",
        type=int,
        metavar="N",
        help="longest path in segments (1: emitters only, -1: unbounded)",
    )
    command.add_argument(
        "--aov",
        metavar="LIST",
        help="arbitrary output variables rendered beside the image, comma-separated: "
        f"{', '.join(AOV_NAMES)}; an EXR holds each as channels NAME.R, NAME.G, NAME.B "
        "after R, G, B (a PNG holds the image alone)",
    )
    command.add_argument(
        "--threads",
        type=int,
        metavar="N",
        help="worker threads the server renders the job with, at most its own "
        "(default: all of the server's)",
    )


def add_denoise_argument(command: argparse.ArgumentParser) -> None:
    """``--denoise``: the image denoised in the client (``yarf render`` and ``yarf fetch``)."""
    command.add_argument(
        "--denoise",
        action="store_true",
        help="denoise the image on this machine's CPU with Intel Open Image Denoise "
        "(pip install 'yarf[denoise]'), guided by the albedo and sh_normal AOVs, which "
        "yarf render asks for too (an EXR holds them); the server keeps the raw image",
    )


def add_image_arguments(command: argparse.ArgumentParser) -> None:
    """The options of ImageSettings."""
    command.add_argument(
        "--half", action="store_true", help="EXR: 16-bit half floats (default: 32-bit floats)"
    )
    command.add_argument(
        "--exposure",
        type=float,
        default=0.0,
        metavar="STOPS",
        help="PNG: scale the radiance by 2^STOPS before the tone curve (default 0)",
    )
    command.add_argument(
        "--tonemap",
        choices=TONEMAPS,
        default="linear",
        help="PNG: linear (clamped at 1) or aces (the ACES filmic curve) (default linear)",
    )


def parse_display(text: str) -> tuple[str, int]:
    """``"HOST:PORT"`` (``"[::1]:PORT"`` for an IPv6 address) of a tev viewer as
    (HOST, PORT)."""
    host, colon, port = text.strip().rpartition(":")
    host = host.removeprefix("[").removesuffix("]")
    if not colon or not host or not port.isdigit() or not 0 < int(port) < 1 << 16:
        raise OptionError(
            "display",
            f"expected HOST:PORT of a tev viewer (tev listens on 127.0.0.1:14158), got {text!r}",
        )
    return host, int(port)


def add_display_argument(command: argparse.ArgumentParser) -> None:
    """``--display HOST:PORT``: the live view of ``yarf render`` and ``yarf watch``."""
    command.add_argument(
        "--display",
        metavar="HOST:PORT",
        help="show the image as it renders in the tev viewer listening at HOST:PORT "
        "(tev's default: 127.0.0.1:14158; pbrt's --display-server)",
    )


def display_address(args: argparse.Namespace) -> tuple[str, int] | None:
    """The tev viewer of a command's ``--display``, checked; None without one."""
    return parse_display(args.display) if args.display is not None else None


def render_settings(args: argparse.Namespace) -> RenderSettings:
    """The RenderSettings of a command's options, checked."""
    return RenderSettings.of(
        spp=args.spp,
        seed=args.seed,
        res=args.res,
        crop=args.crop,
        time_limit=args.time_limit,
        transport=args.transport,
        materials=args.material,
        max_depth=args.max_depth,
        aovs=args.aov,
        threads=args.threads,
    )


def image_settings(args: argparse.Namespace, suffix: str) -> ImageSettings:
    """The ImageSettings of a command's options, checked for a file of ``suffix``."""
    settings = ImageSettings(half=args.half, exposure=args.exposure, tonemap=args.tonemap)
    settings.check(suffix)
    return settings
