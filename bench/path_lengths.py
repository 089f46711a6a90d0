"""Where the Cornell box's time goes, by path length: yarf against Mitsuba 3.

Both render the Cornell box (bench/cornell_box.py's two files) with the
path tracer's max_depth at 1 (camera rays and the light they see), 2 (one
bounce: a shading point, a light sample and its shadow ray, a BSDF
sample), 3 and 6 (the Cornell box bench's). The time a sample takes at
each depth, and what each step of depths adds to it, tell a cost per
sample (camera, sampler, film) apart from a cost per bounce, for yarf and
for Mitsuba's llvm_ad_rgb measured in the same run; ratios are yarf's
samples/s over Mitsuba's (above 1: yarf is faster).

Results also go to out/bench/path_lengths.json.
"""

from __future__ import annotations

import json
from itertools import pairwise

from bench_report import cpu_model
from cornell_box import ROOT, SCENE, THROUGHPUT_SPP, mitsuba_render
from lights import yarf_render

from yarf.scene import load_scene
from yarf.server import LocalServer

DEPTHS = (1, 2, 3, 6)
# yarf's renders per depth; the fastest counts, as Mitsuba's one timed
# render after its warm-up.
RUNS = 3


def main() -> None:
    rows: dict[int, dict[str, float]] = {}
    with LocalServer() as server, server.client() as client:
        for depth in DEPTHS:
            scene = load_scene(SCENE)
            scene.transport.properties.values["max_depth"].int_value = depth
            yarf_render(client, scene, 2, 99)  # warm-up
            rates = [yarf_render(client, scene, THROUGHPUT_SPP, run)[2] for run in range(RUNS)]
            yarf = max(rate["samples_per_second"] for rate in rates)
            _, mitsuba = mitsuba_render("llvm_ad_rgb", THROUGHPUT_SPP, 1, max_depth=depth)
            rows[depth] = {"yarf": yarf, "mitsuba_llvm_ad_rgb": mitsuba["samples_per_second"]}

    print(f"cpu: {cpu_model()}")
    print(f"Cornell box, {THROUGHPUT_SPP} spp; ns are wall-clock per sample on all threads")
    print(f"{'max_depth':>9}{'yarf M/s':>10}{'ns':>7}{'mitsuba M/s':>13}{'ns':>7}{'ratio':>8}")
    for depth, row in rows.items():
        y, m = row["yarf"], row["mitsuba_llvm_ad_rgb"]
        row["ratio"] = y / m
        print(
            f"{depth:>9}{y / 1e6:>10.3f}{1e9 / y:>7.0f}{m / 1e6:>13.3f}{1e9 / m:>7.0f}{y / m:>8.3f}"
        )
    steps: dict[str, dict[str, float]] = {}
    for shorter, longer in pairwise(DEPTHS):
        added = {
            key: 1e9 / rows[longer][key] - 1e9 / rows[shorter][key]
            for key in ("yarf", "mitsuba_llvm_ad_rgb")
        }
        added["ratio"] = added["mitsuba_llvm_ad_rgb"] / added["yarf"]
        steps[f"{shorter}-{longer}"] = added
        print(
            f"depth {shorter} -> {longer} adds: yarf {added['yarf']:.0f} ns, "
            f"mitsuba {added['mitsuba_llvm_ad_rgb']:.0f} ns per sample (ratio {added['ratio']:.3f})"
        )
    out = ROOT / "out" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    report = {"cpu_model": cpu_model(), "spp": THROUGHPUT_SPP, "depths": rows, "steps": steps}
    (out / "path_lengths.json").write_text(json.dumps(report, indent=2))
    print(f"written {out / 'path_lengths.json'}")


if __name__ == "__main__":
    main()
