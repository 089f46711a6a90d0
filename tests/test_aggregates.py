"""Custom aggregates: a scene (or a group) that names an Aggregate class has
its triangle meshes traced by that class instead of Embree's BVH.

The SEADS uniform grid must render the very image Embree's BVH renders (the
C++ tests compare their closest hits ray by ray), and a misnamed or
ill-typed aggregate is refused with the place in the scene that names it.
"""

from __future__ import annotations

import grpc
import pytest
from imagestats import assert_renders_agree

from yarf import Client
from yarf.scene import component
from yarf.v1 import render_pb2, scene_pb2


def small(scene: scene_pb2.Scene) -> scene_pb2.Scene:
    copy = scene_pb2.Scene()
    copy.CopyFrom(scene)
    copy.film.width = copy.film.height = 48
    return copy


def test_the_cornell_box_renders_alike_through_the_grid_and_the_bvh(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    reference = client.render(small(cornell_box), spp=128, seed=1, timeout=600)
    gridded = small(cornell_box)
    gridded.aggregate.CopyFrom(component("seads", density=1.0))
    render = client.render(gridded, spp=128, seed=2, timeout=600)
    assert_renders_agree(render, reference, "seads vs Embree's BVH")


def test_a_misspelt_aggregate_is_refused_at_submit(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    scene = small(cornell_box)
    scene.aggregate.CopyFrom(component("saeds"))
    with pytest.raises(grpc.RpcError) as error:
        client.submit(scene, 1)
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT  # type: ignore[attr-defined]
    message = str(error.value.details())  # type: ignore[attr-defined]
    assert "scene.aggregate.class_name: unknown component class 'saeds'" in message, message
    assert "did you mean 'seads'?" in message


def test_a_density_out_of_range_is_refused_at_submit(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    scene = small(cornell_box)
    scene.aggregate.CopyFrom(component("seads", density=0.0))
    with pytest.raises(grpc.RpcError) as error:
        client.submit(scene, 1)
    message = str(error.value.details())  # type: ignore[attr-defined]
    assert "scene.aggregate.properties.density" in message, message


def test_a_class_that_is_no_aggregate_fails_naming_the_slot(
    client: Client, cornell_box: scene_pb2.Scene
) -> None:
    scene = small(cornell_box)
    scene.aggregate.CopyFrom(component("lambertian"))
    status = client.wait(client.submit(scene, 1), timeout=120)
    assert status.state == render_pb2.FAILED, render_pb2.JobState.Name(status.state)
    assert "scene aggregate (lambertian)" in status.error, status.error
    assert "does not implement yarf.v1.Aggregate" in status.error, status.error
