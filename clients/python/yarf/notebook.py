"""Rendering in one call, as a notebook wants it: ``yarf.render(yarf.load(path))``.

``load`` reads a scene file of any format yarf reads into a ``Scene``,
whose ``params`` view changes its materials, emitters and camera.
``render`` renders a scene (or a scene file) and returns an ``Image``: the
pixels as a numpy array, their variance, and a PNG for Jupyter to show.
Without ``server=``, the renders of a process share one yarfd started on
first use (``embedded_server()``) and stopped when the process exits.
"""

from __future__ import annotations

import atexit
import base64
import tempfile
import threading
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from yarf import denoise as denoising
from yarf.client import IMAGE_FORMATS, Client
from yarf.images import write_image
from yarf.params import SceneParameters
from yarf.render_options import CropWindow, ImageSettings, RenderSettings, Tonemap
from yarf.scene import IMPORTED_SUFFIXES, import_scene, load_scene
from yarf.server import LocalServer
from yarf.v1 import render_pb2, scene_pb2


class Scene:
    """A scene loaded by ``yarf.load``: the ``yarf.v1.Scene`` message it renders
    (``message``) and a view of its parameters (``params``).

    Setting ``scene.params[key]`` changes ``message``; the next
    ``yarf.render(scene)`` renders the change.
    """

    def __init__(
        self,
        message: scene_pb2.Scene,
        *,
        path: Path | None = None,
        sample_count: int = 0,
        warnings: list[str] | None = None,
    ) -> None:
        self.message = message
        # The file it was read from, if any.
        self.path = path
        # Samples per pixel a Mitsuba or pbrt file asks for; 0 when it does not say.
        self.sample_count = sample_count
        # What the importer ignored or approximated ("file:line: message").
        self.warnings = list(warnings or [])

    @property
    def params(self) -> SceneParameters:
        """Every material, emitter, light, texture, medium and camera parameter."""
        return SceneParameters(self.message)

    @property
    def size(self) -> tuple[int, int]:
        """The film's (width, height) in pixels."""
        return self.message.film.width, self.message.film.height

    def copy(self) -> Scene:
        """An independent copy: edits of one leave the other alone."""
        message = scene_pb2.Scene()
        message.CopyFrom(self.message)
        return Scene(
            message, path=self.path, sample_count=self.sample_count, warnings=self.warnings
        )

    def __repr__(self) -> str:
        width, height = self.size
        source = f" from {self.path}" if self.path else ""
        return (
            f"<yarf.Scene{source}: {width}x{height}, {len(self.message.materials)} materials, "
            f"{len(self.message.shapes)} shapes, {len(self.params)} parameters>"
        )


def load(path: str | Path, *, parameters: Mapping[str, str] | None = None) -> Scene:
    """Reads a scene file: yarf's JSON or text format, Mitsuba 3 XML or pbrt-v4.

    Mesh files are inlined, so the scene renders on any server.
    ``parameters`` set a Mitsuba file's ``$name`` parameters. Raises
    SceneError for a file that cannot be read.
    """
    path = Path(path)
    if path.suffix.lower() in IMPORTED_SUFFIXES:
        imported = import_scene(path, parameters=parameters)
        return Scene(
            imported.scene,
            path=path,
            sample_count=imported.sample_count,
            warnings=imported.warnings,
        )
    return Scene(load_scene(path), path=path)


@dataclass(frozen=True)
class Image:
    """A rendered image: ``np.asarray(image)`` is its float32 linear RGB [H, W, 3].

    ``variance``: the variance of each pixel's estimate [H, W, 3] (None when
    the server did not give it). ``spp``: samples per pixel done;
    ``seconds``: the render's time on the server. ``aovs``: the arbitrary
    output variables the render asked for (``aovs=``, and albedo and
    sh_normal for ``denoise=True``), float32 [H, W, 3] by name. ``raw``:
    the image as the server rendered it, when ``pixels`` is its denoised
    copy (else None; ``variance`` is the raw image's). Jupyter shows it as
    an sRGB PNG (``png()``).
    """

    pixels: np.ndarray
    variance: np.ndarray | None = None
    spp: int = 0
    seconds: float = 0.0
    aovs: dict[str, np.ndarray] = field(default_factory=dict)
    status: render_pb2.JobStatus | None = field(default=None, repr=False, compare=False)
    raw: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.pixels.shape)

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])

    def __array__(self, dtype: npt.DTypeLike | None = None, copy: bool | None = None) -> np.ndarray:
        if copy is False and dtype is not None and np.dtype(dtype) != self.pixels.dtype:
            raise ValueError("the pixels are float32: a copy is needed for another dtype")
        pixels = self.pixels if dtype is None else self.pixels.astype(dtype, copy=False)
        return pixels.copy() if copy else pixels

    def mean(self) -> float:
        """The mean of every pixel and channel."""
        return float(self.pixels.mean(dtype=np.float64))

    def save(
        self,
        path: str | Path,
        *,
        half: bool = False,
        exposure: float = 0.0,
        tonemap: Tonemap = "linear",
    ) -> None:
        """Writes an .exr (32-bit floats; ``half``: 16-bit; the AOVs as channels
        NAME.R, NAME.G, NAME.B after R, G, B) or .png file (the radiance scaled by
        2^``exposure``, mapped by ``tonemap``, sRGB)."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in IMAGE_FORMATS:
            raise ValueError(
                f"cannot write {path}: the extension must be one of {', '.join(IMAGE_FORMATS)}"
            )
        settings = ImageSettings(half=half, exposure=exposure, tonemap=tonemap)
        settings.check(suffix)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_image(path, self.pixels, settings, aovs=self.aovs)

    def png(self, *, exposure: float = 0.0, tonemap: Tonemap = "linear") -> bytes:
        """The image as PNG file bytes (as ``save`` writes a .png)."""
        with tempfile.TemporaryDirectory(prefix="yarf-") as folder:
            path = Path(folder) / "image.png"
            self.save(path, exposure=exposure, tonemap=tonemap)
            return path.read_bytes()

    def _repr_png_(self) -> bytes:
        return self.png()

    def _repr_html_(self) -> str:
        data = base64.b64encode(self.png()).decode("ascii")
        caption = f"{self.width}×{self.height}"
        if self.spp:
            caption += f", {self.spp} spp, {self.seconds:.2f} s"
        return (
            f'<figure style="margin:0"><img src="data:image/png;base64,{data}" '
            f'style="image-rendering:pixelated"/><figcaption>{caption}</figcaption></figure>'
        )

    def __repr__(self) -> str:
        rendered = f", {self.spp} spp, {self.seconds:.2f} s" if self.spp else ""
        return f"<yarf.Image {self.width}x{self.height}{rendered}, mean {self.mean():.4g}>"


_embedded: LocalServer | None = None
_embedded_lock = threading.Lock()


def embedded_server() -> LocalServer:
    """The yarfd this process renders with when no server is given: started on
    first use, restarted if it stopped, stopped when the process exits."""
    global _embedded
    with _embedded_lock:
        if _embedded is None or not _embedded.is_running():
            if _embedded is not None:
                _embedded.stop()
            else:
                atexit.register(_stop_embedded_server)
            server = LocalServer()
            server.start()
            _embedded = server
        return _embedded


def _stop_embedded_server() -> None:
    global _embedded
    with _embedded_lock:
        if _embedded is not None:
            _embedded.stop()
            _embedded = None


def _scene_of(scene: Scene | scene_pb2.Scene | str | Path) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, scene_pb2.Scene):
        return Scene(scene)
    if isinstance(scene, str | Path):
        return load(scene)
    raise TypeError(
        f"expected a yarf.Scene, a yarf.v1.Scene message or a scene file's path, "
        f"not {type(scene).__name__}"
    )


def render(
    scene: Scene | scene_pb2.Scene | str | Path,
    spp: int | None = None,
    seed: int = 0,
    *,
    transport: str | scene_pb2.ComponentSpec | None = None,
    res: str | tuple[int, int] | None = None,
    crop: str | tuple[float, float, float, float] | CropWindow | None = None,
    time_limit: float | None = None,
    max_depth: int | None = None,
    materials: Mapping[str, str] | None = None,
    aovs: str | Iterable[str] | None = None,
    threads: int | None = None,
    denoise: bool = False,
    integrator: scene_pb2.ComponentSpec | None = None,
    sampler: scene_pb2.ComponentSpec | None = None,
    server: str | Client | LocalServer | None = None,
    timeout: float | None = None,
) -> Image:
    """Renders a scene, a scene message or a scene file; returns the Image.

    The options are those of ``yarf render`` and ``Client.render``
    (``RenderSettings``): ``spp`` (None: the file's sample count, else the
    server's 16), ``seed``, ``transport`` ("CLASS[@ADDRESS]"),
    ``res`` ((width, height) or "WxH"), ``crop``, ``time_limit`` seconds,
    ``max_depth``, ``materials`` ({name or class: CLASS[@ADDRESS]}),
    ``aovs`` (names of AOV_NAMES, as a list or "albedo,depth": Image.aovs),
    ``threads`` (the job's worker threads on the server); a bad value
    raises OptionError before anything starts. ``denoise``: the image
    denoised on this machine's CPU with Intel Open Image Denoise (``pip
    install 'yarf[denoise]'``), guided by the albedo and sh_normal AOVs
    (asked for too); the server's image is in Image.raw. ``server``: the
    address of a yarfd, a Client or a LocalServer; None renders with the
    process's embedded yarfd (``embedded_server()``). ``timeout``: seconds
    to wait for the job. Raises RenderError when the job fails.
    """
    loaded = _scene_of(scene)
    spp = spp if spp is not None else (loaded.sample_count or None)
    options: dict[str, Any] = {
        "transport": transport,
        "res": res,
        "crop": crop,
        "time_limit": time_limit,
        "max_depth": max_depth,
        "materials": materials,
        "threads": threads,
    }
    # Every value checked before a server is started or asked.
    settings = RenderSettings.of(spp=spp, seed=seed, aovs=aovs, **options)
    if denoise:
        denoising.denoiser()
        settings = settings.with_aovs(denoising.DENOISE_AOVS)
    options["aovs"] = settings.aovs
    if isinstance(server, Client):
        return _render_with(
            server, loaded, spp, seed, integrator, sampler, timeout, options, denoise
        )
    if isinstance(server, str):
        client = Client(server)
    else:
        # The server's own client carries its token and certificate, if any.
        client = (server or embedded_server()).client()
    with client:
        return _render_with(
            client, loaded, spp, seed, integrator, sampler, timeout, options, denoise
        )


def _render_with(
    client: Client,
    scene: Scene,
    spp: int | None,
    seed: int,
    integrator: scene_pb2.ComponentSpec | None,
    sampler: scene_pb2.ComponentSpec | None,
    timeout: float | None,
    options: dict[str, Any],
    denoised: bool,
) -> Image:
    result = client.render(
        scene.message,
        spp,  # type: ignore[arg-type]  # None: the server's default
        seed,
        integrator=integrator,
        sampler=sampler,
        timeout=timeout,
        **options,
    )
    variance = result.variance if result.variance.size else None
    pixels, raw = result.pixels, None
    if denoised:
        missing = denoising.missing_aovs(result.aovs)
        if missing:
            warnings.warn(
                f"not denoised: the job stopped (at its time limit) before rendering the "
                f"{' and '.join(missing)} AOVs the denoiser takes",
                stacklevel=3,
            )
        else:
            pixels, raw = denoising.denoise(result.pixels, result.aovs), result.pixels
    return Image(
        pixels=pixels,
        variance=variance,
        spp=int(result.status.samples_done),
        seconds=float(result.status.elapsed_seconds),
        aovs=dict(result.aovs),
        status=result.status,
        raw=raw,
    )
