#!/usr/bin/env python3
"""Write a small synthetic tilth run as MCAP, following tilth's MCAP layout.

Stand-in for a real `tilth` run, so that check_mcap.py / mcap_to_rrd.py /
check_rrd.py can be developed and tested without the Rust writer:

    python3 tools/python/make_sample_mcap.py OUT.mcap
    python3 tools/python/make_sample_mcap.py OUT.mcap.partial --truncate 0.6

Layout (the contract with tilth's Rust writer):
  * profile "" (or "protobuf" with --profile protobuf), zstd chunks;
  * every channel: message_encoding "protobuf"; schema encoding "protobuf",
    schema name = Foxglove type name, schema data = FileDescriptorSet (one schema
    per type, shared by its channels); channel metadata "unit" where there is one;
  * log_time = publish_time = simulated time in ns;
  * /particles              foxglove.PointCloud, frame "world", identity pose,
                            timestamp = simulated time,
                            stride 28: x y z radius speed (FLOAT32 @0..16),
                            id material (UINT32 @20, @24); metres, m/s
  * /walls                  foxglove.SceneUpdate, one entity per wall
                            (id = wall name) with a Cylinder/Cube/TriangleList
  * /spheres                (only with --spheres) foxglove.SceneUpdate, a sphere per particle
  * /walls/<name>/force     foxglove.Vector3 (N)
  * /walls/<name>/torque    foxglove.Vector3 (N m)
  * /scalars/<name>         foxglove.Vector3, value in x, y = z = 0
  * metadata "tilth.run" and "tilth.channels".

The output is deterministic (fixed seed, no wall-clock time in the file).
"""

from __future__ import annotations

import argparse
import io
import math
import os
import sys

import numpy as np
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.CylinderPrimitive_pb2 import CylinderPrimitive
from foxglove_schemas_protobuf.PackedElementField_pb2 import PackedElementField
from foxglove_schemas_protobuf.Point3_pb2 import Point3
from foxglove_schemas_protobuf.PointCloud_pb2 import PointCloud
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.TriangleListPrimitive_pb2 import TriangleListPrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter
from mcap_protobuf.schema import build_file_descriptor_set

# The point layout of /particles (name, type, offset); stride 28 bytes.
F = PackedElementField
PARTICLE_FIELDS = [
    ("x", F.FLOAT32, 0),
    ("y", F.FLOAT32, 4),
    ("z", F.FLOAT32, 8),
    ("radius", F.FLOAT32, 12),
    ("speed", F.FLOAT32, 16),
    ("id", F.UINT32, 20),
    ("material", F.UINT32, 24),
]
POINT_STRIDE = 28
PARTICLE_DTYPE = np.dtype(
    {
        "names": [n for n, _, _ in PARTICLE_FIELDS],
        "formats": ["<f4"] * 5 + ["<u4"] * 2,
        "offsets": [o for _, _, o in PARTICLE_FIELDS],
        "itemsize": POINT_STRIDE,
    }
)

DRUM_RADIUS = 0.10  # m
DRUM_LENGTH = 0.05  # m, along y
DRUM_OMEGA = 2.0  # rad/s about +y
WALLS = ("drum", "floor", "chute", "hopper")
SCALARS = {
    "kinetic_energy": ("J", "total translational kinetic energy of the particles"),
    "contacts": ("1", "number of active particle-particle and particle-wall contacts"),
    "particles": ("1", "number of particles in the domain"),
}


class TopicWriter:
    """Like tilth's Rust writer: one schema per message type (shared by channels), a "unit"
    in the channel metadata where there is one, per-channel sequence numbers, and
    log_time = publish_time = simulated time."""

    def __init__(self, out, chunk_size: int, profile: str):
        self.w = McapWriter(out, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        self.w.start(profile=profile, library="tilth sample (tools/python/make_sample_mcap.py)")
        self.schemas = {}
        self.channels = {}

    def add_metadata(self, name, data):
        self.w.add_metadata(name, data)

    def write(self, topic: str, msg, ns: int, unit: str | None = None) -> None:
        if topic not in self.channels:
            cls = type(msg)
            name = cls.DESCRIPTOR.full_name
            if name not in self.schemas:
                fds = build_file_descriptor_set(cls).SerializeToString()
                self.schemas[name] = self.w.register_schema(name=name, encoding="protobuf", data=fds)
            meta = {"unit": unit} if unit else {}
            cid = self.w.register_channel(topic=topic, message_encoding="protobuf", schema_id=self.schemas[name], metadata=meta)
            self.channels[topic] = [cid, 0]
        ch = self.channels[topic]
        self.w.add_message(channel_id=ch[0], log_time=ns, publish_time=ns, sequence=ch[1], data=msg.SerializeToString())
        ch[1] += 1

    def finish(self):
        self.w.finish()


def identity_pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, q=(0.0, 0.0, 0.0, 1.0)) -> Pose:
    return Pose(
        position=Vector3(x=x, y=y, z=z),
        orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
    )


def quat_about_axis(axis, angle: float):
    ax = np.asarray(axis, float)
    ax = ax / np.linalg.norm(ax)
    s = math.sin(angle / 2)
    return (ax[0] * s, ax[1] * s, ax[2] * s, math.cos(angle / 2))


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def walls_update(t: float) -> SceneUpdate:
    """One SceneEntity per wall; the drum turns, the others are fixed."""
    # Foxglove cylinders have their axis along z: turn z onto y, then spin about y.
    z_to_y = quat_about_axis((1, 0, 0), -math.pi / 2)
    spin = quat_about_axis((0, 1, 0), DRUM_OMEGA * t)
    drum = SceneEntity(
        frame_id="world",
        id="drum",
        cylinders=[
            CylinderPrimitive(
                pose=identity_pose(q=quat_mul(spin, z_to_y)),
                size=Vector3(x=2 * DRUM_RADIUS, y=2 * DRUM_RADIUS, z=DRUM_LENGTH),
                bottom_scale=1.0,
                top_scale=1.0,
                color=Color(r=0.6, g=0.6, b=0.7, a=0.3),
            )
        ],
    )
    floor = SceneEntity(
        frame_id="world",
        id="floor",
        cubes=[
            CubePrimitive(
                pose=identity_pose(z=-DRUM_RADIUS - 0.02),
                size=Vector3(x=0.4, y=0.2, z=0.01),
                color=Color(r=0.4, g=0.4, b=0.4, a=1.0),
            )
        ],
    )
    # A sloped chute above the drum: two triangles, indexed.
    pts = [(-0.15, -0.03, 0.16), (-0.05, -0.03, 0.11), (-0.05, 0.03, 0.11), (-0.15, 0.03, 0.16)]
    chute = SceneEntity(
        frame_id="world",
        id="chute",
        triangles=[
            TriangleListPrimitive(
                pose=identity_pose(),
                points=[Point3(x=x, y=y, z=z) for x, y, z in pts],
                indices=[0, 1, 2, 0, 2, 3],
                color=Color(r=0.8, g=0.5, b=0.2, a=1.0),
            )
        ],
    )
    # A conical hopper above the chute, written as tilth writes an axisymmetric wall:
    # size = bounding box of the larger radius, bottom/top_scale = radius / larger radius.
    r_base, r_top, length = 0.01, 0.04, 0.06
    hopper = SceneEntity(
        frame_id="world",
        id="hopper",
        cylinders=[
            CylinderPrimitive(
                pose=identity_pose(x=-0.14, z=0.20 + length / 2),
                size=Vector3(x=2 * r_top, y=2 * r_top, z=length),
                bottom_scale=r_base / r_top,
                top_scale=1.0,
                color=Color(r=0.6, g=0.6, b=0.65, a=0.35),
            )
        ],
    )
    return SceneUpdate(entities=[drum, floor, chute, hopper])


def particle_state(rng: np.random.Generator, n_max: int, frames: int):
    """Initial state: particles placed in the drum, inserted a few per frame."""
    r = rng.uniform(0.1, 0.9, n_max) * (DRUM_RADIUS - 0.005)
    phi = rng.uniform(-math.pi, 0, n_max)  # lower half of the drum
    y = rng.uniform(-DRUM_LENGTH / 2 + 0.003, DRUM_LENGTH / 2 - 0.003, n_max)
    radius = rng.uniform(0.001, 0.002, n_max).astype(np.float32)
    material = (rng.uniform(0, 1, n_max) < 0.3).astype(np.uint32)
    # Insertion: the cloud grows linearly to n_max over the first half of the run.
    per_frame = max(1, math.ceil(n_max / max(1, frames // 2)))
    return r, phi, y, radius, material, per_frame


def write_sample(
    path_or_file, frames: int, n_max: int, dt: float, profile: str, chunk_size: int, seed: int, spheres: bool = False
) -> None:
    rng = np.random.default_rng(seed)
    r, phi0, y, radius, material, per_frame = particle_state(rng, n_max, frames)
    ids = np.arange(n_max, dtype=np.uint32)

    writer = TopicWriter(path_or_file, chunk_size=chunk_size, profile=profile)
    writer.add_metadata(
        "tilth.run",
        {
            "run_id": f"sample-{seed:04d}",
            "seed": str(seed),
            "sweep": "sample",
            "scene": "rotating_drum",
            "tilth_version": "0.1.0",
            "git_commit": "0000000000000000000000000000000000000000",
            "factor.friction": "0.5",
            "factor.omega": str(DRUM_OMEGA),
            "generator": "tools/python/make_sample_mcap.py",
        },
    )
    channels = {
        "/particles": "m, m/s; foxglove.PointCloud in frame world: x y z radius [m], speed [m/s], id, material",
        "/walls": "m; foxglove.SceneUpdate, one entity per wall (entity id = wall name)",
    }
    if spheres:
        channels["/spheres"] = "m, m/s; foxglove.SceneUpdate, every particle as a sphere of its diameter, coloured by speed"
    for w in WALLS:
        channels[f"/walls/{w}/force"] = f"N; total contact force on wall {w} (foxglove.Vector3)"
        channels[f"/walls/{w}/torque"] = f"N m; total contact torque on wall {w} about the origin (foxglove.Vector3)"
    for name, (unit, meaning) in SCALARS.items():
        channels[f"/scalars/{name}"] = f"{unit}; {meaning} (value in x of foxglove.Vector3)"
    writer.add_metadata("tilth.channels", channels)

    fields = [PackedElementField(name=n, type=ty, offset=o) for n, ty, o in PARTICLE_FIELDS]
    g = 9.81
    mass = 2500.0 * 4.0 / 3.0 * math.pi * radius.astype(np.float64) ** 3

    for k in range(frames):
        t = k * dt
        ns = int(round(t * 1e9))
        n = min(n_max, (k + 1) * per_frame)

        # Particles ride the drum wall up and slump back: a toy kinematic model.
        phi = phi0[:n] + DRUM_OMEGA * t + 0.3 * np.sin(3.0 * t + ids[:n])
        cloud = np.zeros(n, dtype=PARTICLE_DTYPE)
        cloud["x"] = r[:n] * np.cos(phi)
        cloud["y"] = y[:n]
        cloud["z"] = r[:n] * np.sin(phi)
        vel = r[:n] * (DRUM_OMEGA + 0.9 * np.cos(3.0 * t + ids[:n]))
        speed = np.abs(vel).astype(np.float32)
        cloud["radius"] = radius[:n]
        cloud["speed"] = speed
        cloud["id"] = ids[:n]
        cloud["material"] = material[:n]

        if spheres:  # tilth's optional /spheres: every particle as a SpherePrimitive
            sph = SceneEntity(frame_id="world", id="particles")
            sph.timestamp.FromNanoseconds(ns)
            for p in cloud:
                d = 2.0 * float(p["radius"])
                sph.spheres.append(
                    SpherePrimitive(
                        pose=identity_pose(float(p["x"]), float(p["y"]), float(p["z"])),
                        size=Vector3(x=d, y=d, z=d),
                        color=Color(r=min(1.0, float(p["speed"]) / 0.25), g=0.3, b=0.5, a=1.0),
                    )
                )
            writer.write("/spheres", SceneUpdate(entities=[sph]), ns)

        pc = PointCloud(
            frame_id="world",
            pose=identity_pose(),
            point_stride=POINT_STRIDE,
            fields=fields,
            data=cloud.tobytes(),
        )
        pc.timestamp.FromNanoseconds(ns)  # as tilth does: Rerun's importer makes a "timestamp" timeline of it
        writer.write("/particles", pc, ns)

        walls = walls_update(t)
        for e in walls.entities:
            e.timestamp.FromNanoseconds(ns)
        writer.write("/walls", walls, ns)

        weight = float(mass[:n].sum() * g)
        forces = {
            "drum": (0.0, 0.0, weight * (0.95 + 0.05 * math.sin(5 * t))),
            "floor": (0.0, 0.0, 0.0),
            "chute": (0.01 * math.sin(t), 0.0, 0.02 * (1 + math.cos(t))),
            "hopper": (0.0, 0.0, 0.005 * max(0.0, 1.0 - t)),
        }
        torques = {
            "drum": (0.0, -weight * 0.3 * DRUM_RADIUS, 0.0),
            "floor": (0.0, 0.0, 0.0),
            "chute": (0.0, 0.001 * math.sin(t), 0.0),
            "hopper": (0.0, 0.0, 0.0),
        }
        for w in WALLS:
            fx, fy, fz = forces[w]
            writer.write(f"/walls/{w}/force", Vector3(x=fx, y=fy, z=fz), ns, unit="N")
            tx, ty, tz = torques[w]
            writer.write(f"/walls/{w}/torque", Vector3(x=tx, y=ty, z=tz), ns, unit="N m")

        ke = float(0.5 * (mass[:n] * speed.astype(np.float64) ** 2).sum())
        scalars = {"kinetic_energy": ke, "contacts": float(int(2.5 * n)), "particles": float(n)}
        for name, value in scalars.items():
            writer.write(f"/scalars/{name}", Vector3(x=value, y=0.0, z=0.0), ns, unit=SCALARS[name][0])

    writer.finish()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output path (e.g. run.mcap, or run.mcap.partial with --truncate)")
    ap.add_argument("--frames", type=int, default=200, help="number of output frames (default 200)")
    ap.add_argument("--particles", type=int, default=500, help="final number of particles (default 500)")
    ap.add_argument("--dt", type=float, default=0.005, help="simulated seconds between frames (default 0.005)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--profile", default="", choices=["", "protobuf"], help='MCAP header profile (default "")')
    ap.add_argument("--chunk-size", type=int, default=64 * 1024, help="target uncompressed chunk size in bytes")
    ap.add_argument("--spheres", action="store_true", help="also write /spheres (SceneUpdate, a sphere per particle)")
    ap.add_argument(
        "--truncate",
        type=float,
        metavar="FRACTION",
        help="keep only this fraction (0..1) of the bytes, like a run killed mid-way (no summary, no footer)",
    )
    args = ap.parse_args(argv)

    buf = io.BytesIO()
    write_sample(buf, args.frames, args.particles, args.dt, args.profile, args.chunk_size, args.seed, args.spheres)
    data = buf.getvalue()
    if args.truncate is not None:
        if not 0.0 < args.truncate < 1.0:
            ap.error("--truncate must be strictly between 0 and 1")
        data = data[: int(len(data) * args.truncate)]
    tmp = args.out + ".tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, args.out)
    print(f"wrote {args.out}: {len(data)} bytes, {args.frames} frames" + (" (truncated)" if args.truncate else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
