"""The prepare passes of photon mapping, SPPM and radiosity run on the job's threads.

Photon shooting (photon_map's maps, each SPPM pass's map) and radiosity's
form factors are split among the job's threads, and their results are
joined in a fixed order: the image is the same bit for bit with one
thread or several, and a job that is almost all preparing keeps more than
one thread busy.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO
from thread_ticks import threads_that_worked

from yarf import Client, LocalServer, component, load_scene
from yarf.v1 import scene_pb2

GLOSSY_BOX = REPO / "scenes" / "cornell-box" / "glossy.json"
DIFFUSE_BOX = REPO / "scenes" / "cornell-box" / "scene.json"

# Transport, scene and spp of a job whose time goes to preparing.
PREPARED = {
    "photon_map": (
        component("photon_map", photons=400_000, caustic_photons=400_000),
        GLOSSY_BOX,
        1,
    ),
    "sppm": (component("sppm", photons_per_pass=200_000), GLOSSY_BOX, 4),
    "radiosity": (component("radiosity"), DIFFUSE_BOX, 1),
}


def tiny(path: object, width: int) -> scene_pb2.Scene:
    scene = load_scene(path)
    scene.film.width = scene.film.height = width
    return scene


@pytest.mark.parametrize("method", PREPARED)
def test_the_image_does_not_depend_on_the_threads(client: Client, method: str) -> None:
    transport, path, spp = PREPARED[method]
    scene = tiny(path, 16)
    one, two = (
        client.raw(client.wait(client.submit(scene, spp, 3, transport=transport, threads=n)).job_id)
        for n in (1, 2)
    )
    assert np.isfinite(one.pixels).all() and one.pixels.max() > 0
    np.testing.assert_array_equal(one.pixels, two.pixels)


@pytest.mark.parametrize("method", PREPARED)
def test_preparing_keeps_the_jobs_threads_busy(
    server: LocalServer, client: Client, method: str
) -> None:
    transport, path, spp = PREPARED[method]
    job_id = client.submit(tiny(path, 4), spp, 3, transport=transport, threads=2)
    assert threads_that_worked(server.pid, client, job_id) >= 2
