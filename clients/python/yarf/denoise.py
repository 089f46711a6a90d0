"""Denoising a rendered image on this machine's CPU with Intel Open Image Denoise.

The server renders the image and, beside it, the albedo and shading
normal of the first surface each pixel sees (the AOVs ``albedo`` and
``sh_normal``); OIDN's "RT" filter takes the three (the image as HDR) and
returns a denoised image. The server's image stays as rendered: the
denoised one exists only in the client. OIDN comes from the PyPI package
``pyoidn`` (``pip install 'yarf[denoise]'``).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import ModuleType

import numpy as np

from yarf.v1 import render_pb2

# The AOVs the denoiser takes beside the image, as RenderOptions.aovs names them.
DENOISE_AOVS: tuple[str, ...] = ("albedo", "sh_normal")


class DenoiseError(RuntimeError):
    """The denoiser is not installed, or the image lacks the AOVs it takes."""


def denoiser() -> ModuleType:
    """The ``pyoidn`` module; DenoiseError, saying how to install it, when it is missing."""
    try:
        import pyoidn
    except ImportError as error:
        raise DenoiseError(
            f"denoising needs Intel Open Image Denoise, which cannot be imported ({error}): "
            "pip install 'yarf[denoise]' (the pyoidn package)"
        ) from None
    return pyoidn


def missing_aovs(aovs: Mapping[str, np.ndarray]) -> list[str]:
    """The AOVs of DENOISE_AOVS that ``aovs`` lacks."""
    return [name for name in DENOISE_AOVS if name not in aovs]


def denoise(
    pixels: np.ndarray,
    aovs: Mapping[str, np.ndarray],
    *,
    window: render_pb2.PixelWindow | None = None,
) -> np.ndarray:
    """The denoised copy of linear radiance ``pixels`` [H, W, 3], guided by the
    ``albedo`` and ``sh_normal`` of ``aovs`` (each [H, W, 3]). With ``window``,
    only those pixels are denoised (the others are copied): a crop window's image.

    Raises DenoiseError when pyoidn is missing or an AOV is absent.
    """
    pyoidn = denoiser()
    missing = missing_aovs(aovs)
    if missing:
        raise DenoiseError(f"the image has no {' and '.join(missing)} AOV to denoise with")
    rows, columns = slice(None), slice(None)
    if window is not None:
        rows, columns = slice(window.y0, window.y1), slice(window.x0, window.x1)

    def part(image: np.ndarray, low: float, high: float) -> np.ndarray:
        values = np.nan_to_num(image[rows, columns].astype(np.float32), nan=0.0, posinf=high)
        return np.ascontiguousarray(np.clip(values, low, high))

    # OIDN wants HDR colour ≥ 0, albedo in [0, 1] and normals in [-1, 1]; the
    # albedo is an estimate of one model sample per camera sample, so a pixel
    # may exceed 1 a little.
    color = part(pixels, 0.0, np.finfo(np.float32).max)
    albedo = part(aovs["albedo"], 0.0, 1.0)
    normal = part(aovs["sh_normal"], -1.0, 1.0)
    denoised = pyoidn.denoise(color, albedo, normal, hdr=True, filter_type="RT")
    result = np.array(pixels, dtype=np.float32, copy=True)
    result[rows, columns] = denoised
    return result
