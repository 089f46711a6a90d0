"""Renders Mitsuba 3's Cornell box once and reports the time it took.

Run as a separate process per variant (Mitsuba's LLVM variant reads
DRJIT_LIBLLVM_PATH at import). Prints one JSON object; saves the image as
.npy when --out is given. A first render at low spp warms up the JIT, so
the timed render measures rendering only.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", type=Path)
    parser.add_argument("--variant", default="scalar_rgb")
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path)
    parser.add_argument(
        "--max-depth",
        type=int,
        help="the scene's max_depth parameter (the Cornell box declares it)",
    )
    args = parser.parse_args()

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    parameters = {} if args.max_depth is None else {"max_depth": args.max_depth}
    scene = mi.load_file(str(args.scene), **parameters)
    np.asarray(mi.render(scene, spp=4, seed=args.seed + 1_000_003))  # warm-up
    start = time.perf_counter()
    image = mi.render(scene, spp=args.spp, seed=args.seed)
    dr.eval(image)
    pixels = np.asarray(image, dtype=np.float32)[..., :3]
    seconds = time.perf_counter() - start
    if args.out:
        np.save(args.out, pixels)
    height, width = pixels.shape[:2]
    print(
        json.dumps(
            {
                "variant": args.variant,
                "spp": args.spp,
                "seconds": seconds,
                "samples_per_second": width * height * args.spp / seconds,
            }
        )
    )


if __name__ == "__main__":
    main()
