"""Samples/s of several yarfd builds on one scene (the Cornell box unless
told), run by run in turn.

For "before and after" figures of a change: build the older commit in a
worktree (``git worktree add ../before COMMIT`` and a CMake build there),
or copy a build's ``bin`` and ``plugins`` folders aside before rebuilding,
then

    .venv/bin/python bench/compare_builds.py before=../before/build/bin/yarfd \
        now=build/bin/yarfd --spp 256 --runs 7

Each build serves its own plugins. The runs alternate between builds, so
that a busy or throttled machine slows them alike; medians and bests are
given as ratios against the first build named. ``--scene FILE`` measures
another scene (any format yarf reads), ``--size N`` renders its film N
pixels wide and high, ``--transport CLASS`` with another transport.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bench_report import cpu_model, write_result

from yarf import LocalServer, load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "cornell-box" / "scene.json"


def server_of(binary: Path) -> LocalServer:
    """A yarfd and the plugins beside it (bin/../plugins, as a build tree has them):
    a copied build keeps its own plugins, not those its binary was built to find."""
    plugins = binary.resolve().parent.parent / "plugins"
    return LocalServer(binary=binary, plugin_paths=[plugins] if plugins.is_dir() else [])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "builds", nargs="+", help="NAME=PATH of a yarfd binary; the first is the baseline"
    )
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--scene", type=Path, default=SCENE)
    parser.add_argument("--size", type=int, help="film width and height in pixels")
    parser.add_argument("--transport", help="the transport class (default: the scene's)")
    args = parser.parse_args()
    builds = dict(build.split("=", 1) for build in args.builds)
    scene = load_scene(args.scene)
    if args.size:
        scene.film.width = scene.film.height = args.size
    if args.transport:
        scene.transport.class_name = args.transport
    samples = scene.film.width * scene.film.height * args.spp
    rates: dict[str, list[float]] = {name: [] for name in builds}
    servers = {name: server_of(Path(path)) for name, path in builds.items()}
    for server in servers.values():
        server.__enter__()
    try:
        clients = {name: server.client() for name, server in servers.items()}
        for client in clients.values():
            client.render(scene, spp=8, seed=1)  # plugins loaded, caches warm
        for run in range(args.runs):
            for name, client in clients.items():
                start = time.perf_counter()
                client.render(scene, spp=args.spp, seed=run)
                rates[name].append(samples / (time.perf_counter() - start) / 1e6)
    finally:
        for server in servers.values():
            server.__exit__(None, None, None)
    baseline = next(iter(builds))
    median = {name: sorted(r)[len(r) // 2] for name, r in rates.items()}
    name = "Cornell box" if args.scene == SCENE else str(args.scene)
    print(f"{name}, {args.spp} spp, {args.runs} runs per build, {cpu_model()}")
    for name, r in rates.items():
        print(
            f"  {name}: median {median[name]:.3f} M samples/s "
            f"({median[name] / median[baseline]:.3f}x), best {max(r):.3f} "
            f"({max(r) / max(rates[baseline]):.3f}x)"
        )
    write_result(
        "compare_builds",
        {"cpu": cpu_model(), "scene": str(args.scene), "spp": args.spp, "rates": rates},
    )


if __name__ == "__main__":
    main()
