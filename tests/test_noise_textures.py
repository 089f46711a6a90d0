"""pbrt-v4's procedural textures as pbrt defines them: the solid ones (fbm,
wrinkled, windy, marble, the checkerboard of dimension 3) placed by the
transform in force at their Texture directive, and dots and bilerp over
the surface's uv.

A flat diffuse floor under a uniform white sky reflects its albedo: seen
straight down by an orthographic camera, each pixel is the mean albedo
over its square of floor. The albedo is a noise texture; the expected
image is that texture's value averaged over each pixel, computed here by
an implementation of pbrt's noise of this file's own (numpy), from the
texture's placement in the pbrt file.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from yarf import Client
from yarf.scene import import_scene

# Ken Perlin's permutation, pbrt's NoisePerm: the reference values.
# fmt: off
PERMUTATION = np.array([
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103,
    30, 69, 142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26,
    197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174,
    20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231,
    83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143,
    54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196,
    135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124,
    123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101,
    155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185,
    112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81,
    51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176,
    115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243,
    141, 128, 195, 78, 66, 215, 61, 156, 180,
])
# fmt: on


def noise(p: np.ndarray) -> np.ndarray:
    """Perlin's gradient noise at points p [..., 3], as pbrt-v4's Noise."""
    cell = np.floor(p)
    d = p - cell
    i = cell.astype(np.int64) & 255
    fade = d * d * d * (d * (d * 6 - 15) + 10)
    total = np.zeros(p.shape[:-1])
    for corner in range(8):
        offset = np.array([(corner >> axis) & 1 for axis in range(3)])
        h = PERMUTATION[(i[..., 0] + offset[0]) & 255]
        h = PERMUTATION[(h + i[..., 1] + offset[1]) & 255]
        h = PERMUTATION[(h + i[..., 2] + offset[2]) & 255] & 15
        dx, dy, dz = (d - offset).transpose((d.ndim - 1, *range(d.ndim - 1)))
        u = np.where((h < 8) | (h == 12) | (h == 13), dx, dy)
        v = np.where((h < 4) | (h == 12) | (h == 13), dy, dz)
        gradient = np.where(h & 1, -u, u) + np.where(h & 2, -v, v)
        weight = np.prod(np.where(offset == 1, fade, 1 - fade), axis=-1)
        total += weight * gradient
    return total


def octaves(
    p: np.ndarray, omega: float, count: int, term: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, float]:
    """Σ ωⁱ term(1.99ⁱ p) over `count` octaves, and the next octave's weight."""
    total, scale, weight = np.zeros(p.shape[:-1]), 1.0, 1.0
    for _ in range(count):
        total += weight * term(p * scale)
        scale *= 1.99
        weight *= omega
    return total, weight


def fbm(p: np.ndarray, omega: float = 0.5, count: int = 8) -> np.ndarray:
    return octaves(p, omega, count, noise)[0]


def turbulence(p: np.ndarray, omega: float = 0.5, count: int = 8) -> np.ndarray:
    total, weight = octaves(p, omega, count, lambda q: np.abs(noise(q)))
    return total + 0.2 * weight


MARBLE_COLOURS = np.array(
    [
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.5, 0.5, 0.5],
        [0.6, 0.59, 0.58],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.2, 0.2, 0.33],
        [0.58, 0.58, 0.6],
    ]
)


def marble(p: np.ndarray, scale: float, variation: float) -> np.ndarray:
    p = p * scale
    t = 0.5 + 0.5 * np.sin(p[..., 1] + variation * fbm(p))
    segments = len(MARBLE_COLOURS) - 3
    first = np.clip(np.floor(t * segments).astype(int), 0, segments - 1)
    t = (t * segments - first)[..., None]
    c = [MARBLE_COLOURS[first + k] for k in range(4)]
    s = [c[k] + t * (c[k + 1] - c[k]) for k in range(3)]
    s = [s[k] + t * (s[k + 1] - s[k]) for k in range(2)]
    return 1.5 * (s[0] + t * (s[1] - s[0]))


def in_dot(s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Whether (s, t) lies in one of pbrt's dots."""
    cell_s, cell_t = np.floor(s + 0.5), np.floor(t + 0.5)
    half = np.full_like(s, 0.5)

    def at(ds: float, dt: float) -> np.ndarray:
        return noise(np.stack([cell_s + ds, cell_t + dt, half], axis=-1))

    centre_s = cell_s + 0.15 * at(1.5, 2.8)
    centre_t = cell_t + 0.15 * at(4.5, 9.8)
    near = (s - centre_s) ** 2 + (t - centre_t) ** 2 < 0.35**2
    return (at(0.5, 0.5) > 0) & near


def dots_albedo(world: np.ndarray, uscale: float, vscale: float) -> np.ndarray:
    """The dots over the floor's uv, (u, v) = (x, z), 0.8 within, 0.3 without."""
    return grey(np.where(in_dot(uscale * world[..., 0], vscale * world[..., 2]), 0.8, 0.3))


SIZE = 32
SPAN = 4.0  # the orthographic view, scene units across
PBRT_FLOOR = """Film "rgb" "integer xresolution" [{size}] "integer yresolution" [{size}]
    "string filename" "floor.exr"
PixelFilter "box" "float xradius" 0.5 "float yradius" 0.5
Sampler "independent" "integer pixelsamples" 64
Integrator "path" "integer maxdepth" 1
LookAt 0 5 0  0 0 0  0 0 1
Camera "orthographic" "float screenwindow" [-2 2 -2 2]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
Translate 0.3 0.1 0.7
Rotate 90 1 0 0
Scale 0.5 0.5 0.5
{texture}
AttributeEnd
{material}
Shape "trianglemesh" "point3 P" [-50 0 -50  50 0 -50  50 0 50  -50 0 50]
    "point2 uv" [-50 -50  50 -50  50 50  -50 50] "integer indices" [0 1 2  0 2 3]
"""


def texture_space(world: np.ndarray) -> np.ndarray:
    """The texture's space: the inverse of the transform at its directive."""
    translate = np.eye(4)
    translate[:3, 3] = [0.3, 0.1, 0.7]
    rotate = np.eye(4)
    rotate[1:3, 1:3] = [[0, -1], [1, 0]]  # 90° about x
    scale = np.diag([0.5, 0.5, 0.5, 1])
    to_texture = np.linalg.inv(translate @ rotate @ scale)
    return world @ to_texture[:3, :3].T + to_texture[:3, 3]


def floor_points(sub: int) -> np.ndarray:
    """sub × sub points of the floor within each pixel, [SIZE, SIZE, sub², 3]:
    the camera's x is the world's x, the film's y downward the world's −z."""
    offsets = (np.arange(sub) + 0.5) / sub
    pixel = SPAN / SIZE
    x = -SPAN / 2 + (np.arange(SIZE)[:, None] + offsets[None, :]) * pixel
    z = SPAN / 2 - (np.arange(SIZE)[:, None] + offsets[None, :]) * pixel
    xs = np.broadcast_to(x[None, :, None, :], (SIZE, SIZE, sub, sub))
    zs = np.broadcast_to(z[:, None, :, None], (SIZE, SIZE, sub, sub))
    points = np.stack([xs, np.zeros_like(xs), zs], axis=-1)
    return points.reshape(SIZE, SIZE, sub * sub, 3)


def grey(value: np.ndarray) -> np.ndarray:
    return np.repeat(value[..., None], 3, axis=-1)


def mix_albedo(amount: np.ndarray) -> np.ndarray:
    """pbrt's mix of 0.5 and 0.8 by `amount`."""
    return grey(0.5 + 0.3 * amount)


def windy(p: np.ndarray) -> np.ndarray:
    return np.abs(fbm(0.1 * p, 0.5, 3)) * fbm(p, 0.5, 6)


def solid_checkerboard(p: np.ndarray) -> np.ndarray:
    """pbrt's checkerboard of dimension 3: 0.8 in even unit cubes, 0.3 in odd."""
    return grey(np.where(np.floor(p).sum(axis=-1) % 2 == 0, 0.8, 0.3))


def bilerp(world: np.ndarray, corners: tuple[float, float, float, float]) -> np.ndarray:
    """pbrt's bilerp of v00, v10, v01, v11 at (s, t) = (x/4 + ½, z/4 + ½) of uv (x, z)."""
    s, t = world[..., 0] / 4 + 0.5, world[..., 2] / 4 + 0.5
    v00, v10, v01, v11 = corners
    return grey((1 - s) * (1 - t) * v00 + s * (1 - t) * v10 + (1 - s) * t * v01 + s * t * v11)


MIX_MATERIAL = (
    'Texture "albedo" "spectrum" "mix" "rgb tex1" [0.5 0.5 0.5] "rgb tex2" [0.8 0.8 0.8]'
    ' "texture amount" "noise"\nMaterial "diffuse" "texture reflectance" "albedo"'
)
# Each texture: its directive, the material using it, the albedo it gives
# at the floor's points (world space), and the albedo were it misplaced
# (a solid texture's transform ignored; the dots' uv scales swapped, the
# bilerp's corners v10 and v01).
Albedo = Callable[[np.ndarray], np.ndarray]
CASES: dict[str, tuple[str, str, Albedo, Albedo]] = {
    "fbm": (
        'Texture "noise" "float" "fbm" "integer octaves" 5 "float roughness" 0.6',
        MIX_MATERIAL,
        lambda x: mix_albedo(fbm(texture_space(x), 0.6, 5)),
        lambda x: mix_albedo(fbm(x, 0.6, 5)),
    ),
    "wrinkled": (
        'Texture "noise" "float" "wrinkled" "integer octaves" 6',
        'Texture "albedo" "spectrum" "scale" "rgb tex" [0.4 0.4 0.4] "texture scale" "noise"\n'
        'Material "diffuse" "texture reflectance" "albedo"',
        lambda x: grey(0.4 * turbulence(texture_space(x), 0.5, 6)),
        lambda x: grey(0.4 * turbulence(x, 0.5, 6)),
    ),
    "windy": (
        'Texture "noise" "float" "windy"',
        MIX_MATERIAL,
        lambda x: mix_albedo(windy(texture_space(x))),
        lambda x: mix_albedo(windy(x)),
    ),
    "marble": (
        'Texture "albedo" "spectrum" "marble" "float scale" 1.5 "float variation" 0.5',
        'Material "diffuse" "texture reflectance" "albedo"',
        lambda x: marble(texture_space(x), 1.5, 0.5),
        lambda x: marble(x, 1.5, 0.5),
    ),
    "checkerboard 3-D": (
        'Texture "albedo" "spectrum" "checkerboard" "integer dimension" 3\n'
        '    "rgb tex1" [0.8 0.8 0.8] "rgb tex2" [0.3 0.3 0.3]',
        'Material "diffuse" "texture reflectance" "albedo"',
        lambda x: solid_checkerboard(texture_space(x)),
        lambda x: solid_checkerboard(x),
    ),
    "bilerp": (
        "",
        'Texture "albedo" "spectrum" "bilerp" "rgb v00" [0.2 0.2 0.2] "rgb v10" [0.8 0.8 0.8]\n'
        '    "rgb v01" [0.5 0.5 0.5] "rgb v11" [0.3 0.3 0.3]\n'
        '    "float uscale" 0.25 "float vscale" 0.25 "float udelta" 0.5 "float vdelta" 0.5\n'
        'Material "diffuse" "texture reflectance" "albedo"',
        lambda x: bilerp(x, (0.2, 0.8, 0.5, 0.3)),
        lambda x: bilerp(x, (0.2, 0.5, 0.8, 0.3)),
    ),
    "dots": (
        "",
        'Texture "albedo" "spectrum" "dots" "float uscale" 2 "float vscale" 3\n'
        '    "rgb inside" [0.8 0.8 0.8] "rgb outside" [0.3 0.3 0.3]\n'
        'Material "diffuse" "texture reflectance" "albedo"',
        lambda x: dots_albedo(x, 2, 3),
        lambda x: dots_albedo(x, 3, 2),
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_pbrt_noise_texture_is_pbrts_noise_where_the_file_places_it(
    client: Client, tmp_path: Path, name: str
) -> None:
    texture, material, albedo, misplaced = CASES[name]
    path = tmp_path / f"{name}.pbrt"
    path.write_text(PBRT_FLOOR.format(size=SIZE, texture=texture, material=material))
    imported = import_scene(path)
    assert not [w for w in imported.warnings if "not supported" in w], imported.warnings
    result = client.render(imported.scene, spp=64, seed=5)
    image, variance = result.pixels[..., :3], result.variance[..., :3]
    # The sky's light reaches the floor by light and BSDF samples weighed
    # together: each pixel is off by its estimate's noise, no more (the
    # mean square of the z-scores is 1 where the image is right).
    z = (image - albedo(floor_points(16)).mean(axis=2)) / np.sqrt(variance + 1e-12)
    assert (z**2).mean() < 1.3, (name, (z**2).mean())
    assert np.abs(z).max() < 5.5, (name, np.abs(z).max())
    # Misplaced, it would not match: measured so, the mean square z-score
    # is 5.8 (windy) to 480 (the solid checkerboard).
    wrong = (image - misplaced(floor_points(8)).mean(axis=2)) / np.sqrt(variance + 1e-12)
    assert (wrong**2).mean() > 3
