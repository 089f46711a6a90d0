"""Structure-aware fuzzing of Submit: real scenes mutated field by field over the proto descriptors.

Each mutant is a SubmitRequest made from a seed scene by a few random edits
of its fields (extreme, non-finite or wrong numbers; long, empty or odd
text; unknown enum values; messages cleared, duplicated or removed),
sometimes followed by flips of bytes in its wire form. Every mutant goes to
``yarfd --check-requests`` (Submit's own checks), which must answer it,
accepted or refused, and stay alive. Every k-th accepted mutant, made small,
is rendered by a real yarfd, which must end the job (succeeded or failed
with an error) and stay alive: what the checks let through must not crash
the server.

  .venv/bin/python fuzz/submit_fuzz.py --mutants 3000 --renders 20     (make fuzz)
  .venv/bin/python fuzz/submit_fuzz.py --mutants 10000000 --renders 100000 --seed 7   (hours)

A failure prints the mutant (as text) and writes it to ``--artifacts``.
"""

from __future__ import annotations

import argparse
import math
import random
import sys
import time
from pathlib import Path

import numpy as np
from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from yarf import LocalServer, component, load_scene, properties, rgb, transform, vec3
from yarf.farm.validation import AddressNotAllowed, InvalidRequest, SubmitChecker
from yarf.scene import float_array
from yarf.v1 import render_pb2, scene_pb2

ROOT = Path(__file__).resolve().parents[1]
# Rendered mutants end within this, or the server is taken to hang.
RENDER_TIMEOUT = 60.0

NUMBERS = [
    math.nan, math.inf, -math.inf, 1e39, -1e39, 1e300, 1e12, 1e12 * 1.0000001, 1e-30, -1e-30,
    0.0, -0.0, -1.0, 1.0, 0.5, 179.99, 180.0, 1e6, -1e6, 5e-324,
]  # fmt: skip
INTEGERS = [
    0,
    1,
    2,
    3,
    255,
    256,
    1 << 16,
    1 << 20,
    (1 << 20) + 1,
    16384,
    16385,
    (1 << 31) - 1,
    1 << 31,
]
TEXTS = ["", "x", "grey", "light", "a" * 1024, "a" * 1025, "é" * 600, "../../etc/passwd",
         "mean_sample", "path", "photon_map", "\u0000", "127.0.0.1:1"]  # fmt: skip


def seeds() -> list[render_pb2.SubmitRequest]:
    """Real requests to start from: the Cornell box and a scene using every kind of part."""
    cornell = load_scene(ROOT / "scenes" / "cornell-box" / "scene.json")
    cornell.film.width = cornell.film.height = 16
    rich = scene_pb2.Scene()
    rich.camera.model = scene_pb2.Camera.THIN_LENS
    rich.camera.origin.CopyFrom(vec3(0, 0, 4))
    rich.camera.target.CopyFrom(vec3(0, 0, 0))
    rich.camera.up.CopyFrom(vec3(0, 1, 0))
    rich.camera.fov = 40
    rich.camera.lens_radius = 0.05
    rich.camera.focus_distance = 4
    rich.film.width = rich.film.height = 12
    rich.film.filter.kind = scene_pb2.ReconstructionFilter.GAUSSIAN
    rich.materials.add(
        name="grey", class_name="lambertian", properties=properties(reflectance=rgb(0.5))
    )
    rich.materials.add(name="glass", class_name="dielectric", properties=properties(int_ior=1.5))
    light = rich.shapes.add(name="light", material="grey")
    light.rectangle.SetInParent()
    light.to_world.CopyFrom(transform(np.diag([1.5, 1.5, 1.0, 1.0])))
    light.emitter.CopyFrom(component("diffuse_area", radiance=rgb(1.0)))
    mesh = rich.shapes.add(name="mesh", material="grey").mesh
    mesh.positions.extend([-1, -1, 0, 1, -1, 0, 0, 1, 0])
    mesh.indices.extend([0, 1, 2])
    ply = rich.shapes.add(name="ply", material="glass").mesh
    ply.format = "ply"
    ply.data = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n" + (
        b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 1\n1 0 1\n0 1 1\n3 0 1 2\n"
    )
    group = rich.groups.add(name="balls")
    ball = group.shapes.add(name="ball", material="glass")
    ball.sphere.radius = 0.3
    placed = rich.instances.add(group="balls")
    placed.to_world.CopyFrom(transform(np.diag([1.0, 2.0, 1.0, 1.0])))
    spot = rich.lights.add(
        name="spot", emitter=component("spot", intensity=rgb(5.0), cutoff_angle=30.0)
    )
    spot.to_world.CopyFrom(transform(np.eye(4)))
    # Media: a homogeneous fog around the camera, a grid inside a null box.
    rich.materials.add(name="boundary", class_name="null")
    rich.camera_medium = "fog"
    rich.media.add(
        name="fog", medium=component("homogeneous", sigma_a=rgb(0.1), sigma_s=rgb(0.3), g=0.4)
    )
    voxels = [0.5, 1.0, 0.0, 2.0, 1.5, 0.2, 0.7, 1.1]
    rich.media.add(
        name="smoke",
        medium=component(
            "grid", density=float_array(voxels), nx=2, ny=2, nz=2, to_world=transform(np.eye(4))
        ),
    )
    box = rich.shapes.add(name="box", material="boundary", interior="smoke", exterior="fog").mesh
    box.positions.extend([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1])
    box.indices.extend([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3])
    requests = []
    for scene in (cornell, rich):
        for transport in ("path", "bdpt", "photon_map", "volpath", "light"):
            request = render_pb2.SubmitRequest(scene=scene, name="fuzz")
            request.options.spp = 1
            request.options.transport.class_name = transport
            requests.append(request)
    return requests


def fields_of(message: Message) -> list[tuple[Message, FieldDescriptor]]:
    """Every (message, field) of the tree under ``message``, set or not."""
    out = []
    for field in message.DESCRIPTOR.fields:
        out.append((message, field))
        if field.message_type is None or field.message_type.GetOptions().map_entry:
            continue
        if field.is_repeated:
            for item in getattr(message, field.name):
                out += fields_of(item)
        elif message.HasField(field.name):
            out += fields_of(getattr(message, field.name))
    return out


def scalar(field: FieldDescriptor, rng: random.Random) -> object:
    kind = field.cpp_type
    if kind in (FieldDescriptor.CPPTYPE_DOUBLE, FieldDescriptor.CPPTYPE_FLOAT):
        return rng.choice(NUMBERS) if rng.random() < 0.8 else rng.uniform(-10, 10)
    if kind == FieldDescriptor.CPPTYPE_BOOL:
        return rng.random() < 0.5
    if kind == FieldDescriptor.CPPTYPE_ENUM:
        return rng.choice([value.number for value in field.enum_type.values] + [7, 99])
    if kind == FieldDescriptor.CPPTYPE_STRING:
        if field.type == FieldDescriptor.TYPE_BYTES:
            return rng.randbytes(rng.choice([0, 3, 64]))
        return rng.choice(TEXTS)
    signed = kind in (FieldDescriptor.CPPTYPE_INT32, FieldDescriptor.CPPTYPE_INT64)
    value = rng.choice(INTEGERS)
    if kind in (FieldDescriptor.CPPTYPE_INT32, FieldDescriptor.CPPTYPE_UINT32):
        value = min(value, (1 << 31) - 1 if signed else (1 << 32) - 1)
    return -value if signed and rng.random() < 0.3 else value


def mutate_once(request: render_pb2.SubmitRequest, rng: random.Random) -> None:
    owner, field = rng.choice(fields_of(request))
    container = getattr(owner, field.name)
    if field.message_type is not None and field.message_type.GetOptions().map_entry:
        # Properties.values: a key added, dropped or given a wild value.
        if container and rng.random() < 0.3:
            del container[rng.choice(list(container))]
        else:
            key = rng.choice([*list(container), "scale", "photons", "max_depth", "radiance"])
            value = container[key]
            choice = rng.randrange(4)
            if choice == 0:
                value.float_value = rng.choice(NUMBERS)
            elif choice == 1:
                value.int_value = rng.choice([-1, 0, 10**10, (1 << 63) - 1, 1 << 40])
            elif choice == 2:
                value.rgb_value.r, value.rgb_value.g, value.rgb_value.b = (
                    rng.choice(NUMBERS) for _ in range(3)
                )
            else:
                value.string_value = rng.choice(TEXTS)
        return
    if field.is_repeated:
        if field.message_type is not None:
            if container and rng.random() < 0.5:
                del container[rng.randrange(len(container))]
            elif container:
                container.add().CopyFrom(rng.choice(container))
            else:
                container.add()
        elif container and rng.random() < 0.7:
            container[rng.randrange(len(container))] = scalar(field, rng)
        elif container and rng.random() < 0.5:
            del container[rng.randrange(len(container)) :]
        else:
            container.append(scalar(field, rng))
        return
    if field.message_type is not None:
        if owner.HasField(field.name) and rng.random() < 0.4:
            owner.ClearField(field.name)
        else:
            container.SetInParent()
        return
    try:
        setattr(owner, field.name, scalar(field, rng))
    except (TypeError, ValueError):
        pass  # a value the Python runtime refuses to put on the wire


def mutant(seed_requests: list[render_pb2.SubmitRequest], rng: random.Random) -> bytes:
    request = render_pb2.SubmitRequest()
    request.CopyFrom(rng.choice(seed_requests))
    for _ in range(rng.choice([1, 1, 2, 3, 6])):
        mutate_once(request, rng)
    wire = bytearray(request.SerializeToString())
    if wire and rng.random() < 0.1:
        for _ in range(rng.randint(1, 4)):
            wire[rng.randrange(len(wire))] = rng.randrange(256)
    return bytes(wire)


def small(request: render_pb2.SubmitRequest) -> render_pb2.SubmitRequest:
    """The accepted mutant at a size that renders in moments."""
    small_request = render_pb2.SubmitRequest()
    small_request.CopyFrom(request)
    film = small_request.scene.film
    film.width, film.height = min(film.width, 16), min(film.height, 16)
    options = small_request.options
    options.spp = min(options.spp, 2)
    options.first_sample = 0
    options.ClearField("crop")
    for spec in (options.transport, small_request.scene.transport):
        for key in ("photons", "caustic_photons", "photons_per_pass"):
            if key in spec.properties.values:
                spec.properties.values[key].int_value = 1000
    return small_request


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--mutants", type=int, default=3000, help="mutants checked (default 3000)")
    parser.add_argument(
        "--renders", type=int, default=20, help="accepted mutants rendered (default 20)"
    )
    parser.add_argument(
        "--seed", type=int, default=int(time.time()), help="random seed (default: the time)"
    )
    parser.add_argument(
        "--artifacts", type=Path, default=ROOT / "build" / "fuzz", help="where failures go"
    )
    args = parser.parse_args()
    rng = random.Random(args.seed)
    seed_requests = seeds()
    checker = SubmitChecker()
    accepted: list[render_pb2.SubmitRequest] = []
    refused = 0
    started = time.monotonic()
    for _ in range(args.mutants):
        wire = mutant(seed_requests, rng)
        try:
            request = render_pb2.SubmitRequest.FromString(wire)
        except Exception:
            request = render_pb2.SubmitRequest()  # the checker sees the wire bytes as they are
        try:
            accepted.append(checker.check_wire(wire).accepted)
        except (InvalidRequest, AddressNotAllowed):
            refused += 1
        except (OSError, EOFError) as error:
            return fail(args.artifacts, request, wire, f"yarfd --check-requests died: {error}")
    checker.close()
    checked_at = time.monotonic()
    rendered = ended_failed = 0
    every = max(1, len(accepted) // max(1, args.renders))
    with LocalServer() as server, server.client() as client:
        for request in accepted[::every][: args.renders]:
            wire = small(request).SerializeToString()
            try:
                job = client.render_service.Submit(
                    render_pb2.SubmitRequest.FromString(wire), timeout=30
                ).job_id
            except Exception:
                continue  # refused here (e.g. a mesh reader's error): fine
            status = client.wait(job, timeout=RENDER_TIMEOUT)
            rendered += 1
            if status.state == render_pb2.FAILED:
                ended_failed += 1
            if not server.is_running():
                return fail(
                    args.artifacts, request, wire, f"yarfd died rendering it:\n{server.log[-3000:]}"
                )
            if status.state not in (render_pb2.SUCCEEDED, render_pb2.FAILED):
                client.cancel(job)
                return fail(
                    args.artifacts, request, wire, f"the job did not end in {RENDER_TIMEOUT} s"
                )
    checking, rendering = checked_at - started, time.monotonic() - checked_at
    print(
        f"submit_fuzz: seed {args.seed}: {args.mutants} mutants checked in {checking:.1f} s "
        f"({len(accepted)} accepted, {refused} refused); {rendered} rendered in "
        f"{rendering:.1f} s ({ended_failed} failed with an error); yarfd stayed up"
    )
    return 0


def fail(artifacts: Path, request: render_pb2.SubmitRequest, wire: bytes, why: str) -> int:
    artifacts.mkdir(parents=True, exist_ok=True)
    path = artifacts / f"submit-crash-{int(time.time())}.bin"
    path.write_bytes(wire)
    print(
        f"submit_fuzz: {why}\nthe mutant ({path}):\n{text_format.MessageToString(request)[:4000]}"
    )
    return 1


if __name__ == "__main__":
    sys.exit(main())
