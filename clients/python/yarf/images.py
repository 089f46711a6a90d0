"""Image files of a render, written with OpenImageIO.

An EXR holds the linear radiance as 32-bit floats (or halves on request),
and the job's arbitrary output variables (AOVs) as channels NAME.R,
NAME.G, NAME.B after R, G, B, as the server's EXR does; a PNG holds 8-bit
sRGB values of the radiance scaled by the exposure and mapped by a tone
curve. A crop window's image holds the window alone; its EXR records where
the window lies in the whole film (data and display windows), as pbrt
writes a cropped render.
"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from yarf.render_options import ImageSettings, Tonemap
from yarf.v1 import render_pb2

# Stephen Hill's fit of the ACES reference rendering transform and sRGB
# output transform (the "ACES filmic" curve of game engines and Blender's
# ACES view): linear sRGB into the RRT's space with its saturation ...
_ACES_INPUT = np.array(
    [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]],
    dtype=np.float32,
)
# ... and out of the ODT's space back to linear sRGB.
_ACES_OUTPUT = np.array(
    [[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]],
    dtype=np.float32,
)


def aces_filmic(linear: np.ndarray) -> np.ndarray:
    """The ACES filmic curve of linear sRGB [..., 3]: display-linear values in [0, 1]."""
    v = np.maximum(linear, 0.0) @ _ACES_INPUT.T
    a = v * (v + 0.0245786) - 0.000090537
    b = v * (0.983729 * v + 0.4329510) + 0.238081
    return np.clip((a / b) @ _ACES_OUTPUT.T, 0.0, 1.0)


def display_linear(
    pixels: np.ndarray, *, exposure: float = 0.0, tonemap: Tonemap = "linear"
) -> np.ndarray:
    """Radiance scaled by 2^exposure and mapped into [0, 1] by the tone curve."""
    scaled = np.nan_to_num(pixels.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    scaled *= np.float32(2.0**exposure)
    if tonemap == "aces":
        return aces_filmic(scaled)
    return np.clip(scaled, 0.0, 1.0)


def srgb_bytes(display: np.ndarray) -> np.ndarray:
    """The sRGB transfer of display-linear values in [0, 1], as 8-bit values."""
    x = np.clip(display, 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.rint(encoded * 255.0).astype(np.uint8)


def decode_exr(data: bytes) -> np.ndarray:
    """The RGB pixels [height, width, 3] of an EXR file's bytes, as float32."""
    return decode_exr_layers(data)[0]


def decode_exr_layers(data: bytes) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The RGB pixels [height, width, 3] of an EXR file's bytes, and its AOVs by name
    (the channels NAME.R, NAME.G, NAME.B), as float32."""
    import OpenImageIO as oiio  # imported when used: `import yarf` stays light

    with tempfile.TemporaryDirectory(prefix="yarf-") as folder:
        path = Path(folder) / "image.exr"
        path.write_bytes(data)
        image = oiio.ImageInput.open(str(path))
        if image is None:
            raise OSError(f"cannot read an EXR image: {oiio.geterror()}")
        try:
            spec = image.spec()
            values = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
            if values is None:
                raise OSError(f"cannot read an EXR image: {image.geterror()}")
            channels = np.asarray(values, dtype=np.float32).reshape(
                spec.height, spec.width, spec.nchannels
            )
            names = list(spec.channelnames)
        finally:
            image.close()
    rgb = [names.index(c) for c in "RGB"]
    aovs: dict[str, np.ndarray] = {}
    for name in dict.fromkeys(n.rpartition(".")[0] for n in names if "." in n):
        layer = [f"{name}.{c}" for c in "RGB"]
        if all(channel in names for channel in layer):
            aovs[name] = np.ascontiguousarray(channels[..., [names.index(c) for c in layer]])
    return np.ascontiguousarray(channels[..., rgb]), aovs


def check_writable(path: Path) -> None:
    """Raises OSError unless a file can be written at ``path`` (its folder made if
    needed), so that a render is not lost to a bad output path at its end."""
    if path.is_dir():
        raise IsADirectoryError(21, "is a folder", str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.name}.", delete=True):
        pass


def write_image(
    path: Path,
    pixels: np.ndarray,
    settings: ImageSettings | None = None,
    *,
    window: render_pb2.PixelWindow | None = None,
    aovs: Mapping[str, np.ndarray] | None = None,
) -> None:
    """Writes linear float pixels [height, width, 3] (the whole film) as an .exr or
    .png file; with ``window``, only those pixels. An EXR holds the ``aovs`` (each
    [height, width, 3], by name) as channels NAME.R, NAME.G, NAME.B after R, G, B;
    a PNG the image alone."""
    import OpenImageIO as oiio  # imported when used: `import yarf` stays light

    settings = settings or ImageSettings()
    height, width, _ = pixels.shape
    x0, y0 = 0, 0
    if window is not None:
        x0, y0 = window.x0, window.y0
        pixels = pixels[window.y0 : window.y1, window.x0 : window.x1]
    layers = {
        name: image if window is None else image[window.y0 : window.y1, window.x0 : window.x1]
        for name, image in (aovs or {}).items()
    }
    png = path.suffix.lower() == ".png"
    if png:
        data = srgb_bytes(
            display_linear(pixels, exposure=settings.exposure, tonemap=settings.tonemap)
        )
        spec = oiio.ImageSpec(data.shape[1], data.shape[0], 3, oiio.UINT8)
        spec.attribute("oiio:ColorSpace", "sRGB")
    else:
        data = np.ascontiguousarray(
            np.concatenate([pixels, *layers.values()], axis=2), dtype=np.float32
        )
        spec = oiio.ImageSpec(
            data.shape[1], data.shape[0], data.shape[2], oiio.HALF if settings.half else oiio.FLOAT
        )
        spec.channelnames = ("R", "G", "B", *(f"{n}.{c}" for n in layers for c in "RGB"))
        spec.x, spec.y = x0, y0
        spec.full_x, spec.full_y, spec.full_width, spec.full_height = 0, 0, width, height
        spec.attribute("compression", "zip")
        spec.attribute("oiio:ColorSpace", "lin_rec709")
    output = oiio.ImageOutput.create(str(path))
    if output is None:
        raise OSError(f"cannot write {path}: {oiio.geterror()}")
    try:
        if not output.open(str(path), spec):
            raise OSError(f"cannot write {path}: {output.geterror()}")
        if not output.write_image(data):
            raise OSError(f"cannot write {path}: {output.geterror()}")
    finally:
        output.close()
