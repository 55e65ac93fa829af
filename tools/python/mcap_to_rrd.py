#!/usr/bin/env python3
"""Convert a tilth MCAP run to a Rerun recording (.rrd) with the rerun-sdk.

    python3 tools/python/mcap_to_rrd.py run.mcap run.rrd
    python3 tools/python/mcap_to_rrd.py run.mcap.partial run.rrd --allow-partial

Unlike `rerun mcap convert` (which keeps only the positions of a foxglove.PointCloud
and stores foxglove.Vector3 / foxglove.SceneUpdate as undecoded protobuf structs),
this writes, on the duration timeline "sim_time" (= MCAP log_time, simulated
time):

  /particles              Points3D: positions, per-point radii from the `radius`
                          field, colours from `speed` (viridis, 0 .. --speed-max,
                          default the run's maximum), class_ids = material; plus
                          the components particle_id and speed (AnyValues)
  /walls/<name>           Boxes3D / Cylinders3D / Mesh3D from the /walls SceneUpdate
                          (cones and elliptic cylinders as Mesh3D; re-logged only
                          when the wall's shape or pose changes)
  /walls/<name>/force     Scalars time series, three series x y z  (N)
  /walls/<name>/torque    Scalars time series, three series x y z  (N m)
  /scalars/<name>         Scalars time series, one series (the x of the Vector3)

The MCAP metadata records ("tilth.run", "tilth.channels", ...) become recording
properties, and the recording id and name are tilth.run's run_id (prefixed by
sweep_name when present, e.g. "demo-3"). Any other topic
is reported and skipped.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import Counter, OrderedDict, defaultdict

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_mcap import (  # noqa: E402  (shared helpers: one source of truth for the layout)
    NUMERIC_TYPES,
    SCALAR_RE,
    WALL_VECTOR_RE,
    _NonSeekable,
    file_is_complete,
    foxglove_class,
)
from mcap.reader import make_reader  # noqa: E402

TIMELINE = "sim_time"

# viridis at 9 evenly spaced stops (0..1), RGB 0..255
_VIRIDIS = np.array(
    [
        [68, 1, 84],
        [71, 44, 122],
        [59, 81, 139],
        [44, 113, 142],
        [33, 144, 141],
        [39, 173, 129],
        [92, 200, 99],
        [170, 220, 50],
        [253, 231, 37],
    ],
    dtype=np.float64,
)


def colormap(values: np.ndarray, vmax: float) -> np.ndarray:
    """Map values in [0, vmax] to RGB uint8 colours (viridis)."""
    t = np.clip(np.nan_to_num(values / vmax if vmax > 0 else values * 0.0), 0.0, 1.0)
    x = t * (len(_VIRIDIS) - 1)
    i = np.minimum(x.astype(np.int64), len(_VIRIDIS) - 2)
    f = (x - i)[:, None]
    rgb = _VIRIDIS[i] * (1 - f) + _VIRIDIS[i + 1] * f
    return np.round(rgb).astype(np.uint8)


def cloud_array(msg) -> np.ndarray:
    """The points of a foxglove.PointCloud as a numpy structured array."""
    names, formats, offsets = [], [], []
    for f in msg.fields:
        if f.type in NUMERIC_TYPES:
            names.append(f.name)
            formats.append(NUMERIC_TYPES[f.type][0])
            offsets.append(f.offset)
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": msg.point_stride})
    return np.frombuffer(msg.data, dtype=dtype, count=len(msg.data) // msg.point_stride)


def quat_rotate(q, v: np.ndarray) -> np.ndarray:
    """Rotate row vectors v (N,3) by the unit quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    u = np.array([x, y, z])
    uv = np.cross(u, v)
    uuv = np.cross(u, uv)
    return v + 2.0 * (w * uv + uuv)


def pose_tuple(pose):
    p, q = pose.position, pose.orientation
    quat = (q.x, q.y, q.z, q.w)
    if not any(quat):  # unset orientation: identity
        quat = (0.0, 0.0, 0.0, 1.0)
    return (p.x, p.y, p.z), quat


def rgba(c, default=(180, 180, 180, 255)):
    if c is None or (c.r == 0 and c.g == 0 and c.b == 0 and c.a == 0):
        return default
    return tuple(int(round(255 * max(0.0, min(1.0, v)))) for v in (c.r, c.g, c.b, c.a))


def _is_cone(c) -> bool:
    """True unless the Foxglove cylinder is a plain circular cylinder (which Cylinders3D draws)."""
    bottom = c.bottom_scale or 1.0  # 0 would be a cone tip; proto3 cannot tell it from unset
    top = c.top_scale or 1.0
    return abs(bottom - top) > 1e-9 or abs(c.size.x - c.size.y) > 1e-12 * max(1.0, abs(c.size.x))


def cone_mesh(c, segments: int = 64):
    """A truncated (possibly elliptic) cone as a closed triangle mesh: foxglove.CylinderPrimitive's
    bounding box `size`, bottom face (min z) scaled by bottom_scale, top face by top_scale.
    Returns (vertices, triangles, per-vertex RGBA)."""
    pos, q = pose_tuple(c.pose)
    a = 2 * np.pi * np.arange(segments) / segments
    rx, ry, h = c.size.x / 2, c.size.y / 2, c.size.z / 2
    ring = np.stack([rx * np.cos(a), ry * np.sin(a)], axis=1)
    bottom = np.column_stack([ring * c.bottom_scale, np.full(segments, -h)])
    top = np.column_stack([ring * c.top_scale, np.full(segments, h)])
    verts = np.vstack([bottom, top, [[0, 0, -h], [0, 0, h]]])
    i = np.arange(segments)
    j = (i + 1) % segments
    nb, nt = 2 * segments, 2 * segments + 1
    tris = np.vstack(
        [
            np.column_stack([i, j, segments + j]),  # side
            np.column_stack([i, segments + j, segments + i]),
            np.column_stack([np.full(segments, nb), j, i]),  # bottom cap
            np.column_stack([np.full(segments, nt), segments + i, segments + j]),  # top cap
        ]
    ).astype(np.uint32)
    verts = quat_rotate(q, verts) + np.array(pos)
    colour = rgba(c.color if c.HasField("color") else None)
    return verts, tris, np.tile(np.array(colour, dtype=np.uint8), (len(verts), 1))


def wall_archetypes(entity, rr):
    """Rerun archetypes for one foxglove.SceneEntity (cubes, cylinders, triangle lists)."""
    out = []
    if entity.cubes:
        centers, halves, quats, colors = [], [], [], []
        for c in entity.cubes:
            pos, q = pose_tuple(c.pose)
            centers.append(pos)
            halves.append((c.size.x / 2, c.size.y / 2, c.size.z / 2))
            quats.append(q)
            colors.append(rgba(c.color if c.HasField("color") else None))
        out.append(rr.Boxes3D(centers=centers, half_sizes=halves, quaternions=quats, colors=colors))
    meshes = [cone_mesh(c) for c in entity.cylinders if _is_cone(c)]
    plain = [c for c in entity.cylinders if not _is_cone(c)]
    if plain:
        centers, lengths, radii, quats, colors = [], [], [], [], []
        for c in plain:
            pos, q = pose_tuple(c.pose)
            centers.append(pos)
            lengths.append(c.size.z)
            radii.append(c.size.x / 2 * (c.bottom_scale or 1.0))
            quats.append(q)
            colors.append(rgba(c.color if c.HasField("color") else None))
        out.append(
            rr.Cylinders3D(centers=centers, lengths=lengths, radii=radii, quaternions=quats, colors=colors)
        )
    for tri in entity.triangles:
        pts = np.array([[p.x, p.y, p.z] for p in tri.points], dtype=np.float64).reshape(-1, 3)
        pos, q = pose_tuple(tri.pose)
        pts = quat_rotate(q, pts) + np.array(pos)
        idx = np.array(tri.indices, dtype=np.uint32) if len(tri.indices) else np.arange(len(pts), dtype=np.uint32)
        idx = idx[: len(idx) // 3 * 3].reshape(-1, 3)
        if tri.colors:
            cols = np.array([rgba(c) for c in tri.colors], dtype=np.uint8)
        else:
            cols = np.tile(np.array(rgba(tri.color if tri.HasField("color") else None), np.uint8), (len(pts), 1))
        meshes.append((pts, idx, cols))
    if meshes:
        # One Mesh3D per entity (a second one on the same entity path would replace the first).
        verts, tris, cols, base = [], [], [], 0
        for v, t, c in meshes:
            verts.append(v)
            tris.append(t + base)
            cols.append(c)
            base += len(v)
        out.append(
            rr.Mesh3D(
                vertex_positions=np.vstack(verts).astype(np.float32),
                triangle_indices=np.vstack(tris).astype(np.uint32),
                vertex_colors=np.vstack(cols),
            )
        )
    return out


def iter_messages(path: str, allow_partial: bool, topics=None, notes=None):
    """(schema, channel, message) in log-time order; for a truncated file, up to the truncation."""
    why = file_is_complete(path)
    if why is None:
        with open(path, "rb") as f:
            yield from make_reader(f).iter_messages(topics=topics, log_time_order=True)
        return
    if not allow_partial:
        raise SystemExit(f"error: {path}: incomplete MCAP file ({why})")
    with open(path, "rb") as f:
        try:
            for item in make_reader(_NonSeekable(f)).iter_messages(topics=topics, log_time_order=False):
                yield item
        except Exception as e:  # noqa: BLE001 - the truncation
            if notes is not None:
                notes.append(f"stopped at the truncation ({type(e).__name__}: {str(e) or 'the file ends inside a record'})")


def read_metadata(path: str, allow_partial: bool):
    out = OrderedDict()
    complete = file_is_complete(path) is None
    with open(path, "rb") as f:
        reader = make_reader(f if complete else _NonSeekable(f))
        try:
            for m in reader.iter_metadata():
                out[m.name] = dict(m.metadata)
        except Exception:  # noqa: BLE001 - truncated: keep what was read
            if complete or not allow_partial:
                raise
    return out


def decode(schema, message):
    return foxglove_class(schema.name).FromString(message.data)


def convert(inp: str, out: str, allow_partial: bool, speed_max: float | None, app_id: str, quiet: bool) -> dict:
    import rerun as rr
    import rerun.blueprint as rrb

    why = file_is_complete(inp)
    if why is not None and not allow_partial:
        raise SystemExit(
            f"error: {inp}: incomplete MCAP file ({why}); use --allow-partial to convert what precedes the truncation"
        )
    metadata = read_metadata(inp, allow_partial)
    run = metadata.get("tilth.run", {})

    # Pass 1: the speed range for the colour map.
    if speed_max is None:
        speed_max = 0.0
        for schema, channel, message in iter_messages(inp, allow_partial, topics=["/particles"]):
            cloud = cloud_array(decode(schema, message))
            if "speed" in cloud.dtype.names and len(cloud):
                speed_max = max(speed_max, float(np.nanmax(cloud["speed"])))
        if speed_max <= 0:
            speed_max = 1.0

    # Recording id: tilth.run's run_id, prefixed by the sweep's name when there is one
    # (run ids restart at 1 in every sweep).
    rec_id = run.get("run_id") or None
    if rec_id and run.get("sweep_name"):
        rec_id = f"{run['sweep_name']}-{rec_id}"
    rec = rr.RecordingStream(app_id, recording_id=rec_id)
    # Only simulated time: no wall-clock "log_time" / "log_tick" timelines (keeps the output reproducible).
    rec.set_log_time_enabled(False)
    rec.set_log_tick_enabled(False)
    blueprint = rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="particles", origin="/", contents=["+ /particles", "+ /walls/**"]),
            rrb.Vertical(
                rrb.TimeSeriesView(name="scalars", origin="/scalars"),
                rrb.TimeSeriesView(name="wall forces", origin="/walls", contents=["+ /walls/*/force"]),
                rrb.TimeSeriesView(name="wall torques", origin="/walls", contents=["+ /walls/*/torque"]),
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=False,
    )
    rec.save(out, default_blueprint=blueprint)
    if rec_id:
        rec.send_recording_name(rec_id)
    for name, kv in metadata.items():
        if kv:
            rec.send_property(name, rr.AnyValues(**{k: str(v) for k, v in kv.items()}))
    rec.log("/", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)

    series = defaultdict(lambda: ([], []))  # entity -> (times ns, values)
    last_wall = {}
    stats = OrderedDict(messages=0, clouds=0, points_last=0, wall_updates=0, series_points=0, skipped=Counter())
    notes = []
    for schema, channel, message in iter_messages(inp, allow_partial, notes=notes):
        stats["messages"] += 1
        topic = channel.topic
        ns = message.log_time
        if topic == "/particles":
            cloud = cloud_array(decode(schema, message))
            rec.set_time(TIMELINE, duration=np.timedelta64(ns, "ns"))
            pos = np.stack([cloud[c].astype(np.float32) if c in cloud.dtype.names else np.zeros(len(cloud), np.float32) for c in "xyz"], axis=1)
            comps = dict(positions=pos)
            if "radius" in cloud.dtype.names:
                comps["radii"] = cloud["radius"].astype(np.float32)
            if "speed" in cloud.dtype.names:
                comps["colors"] = colormap(cloud["speed"].astype(np.float64), speed_max)
            if "material" in cloud.dtype.names:
                comps["class_ids"] = cloud["material"].astype(np.uint16)
            extra = {}
            if len(cloud) == 0:
                pass  # an empty cloud (e.g. before insertion): AnyValues rejects empty batches
            elif "id" in cloud.dtype.names:
                extra["particle_id"] = cloud["id"].astype(np.uint32)
            if "speed" in cloud.dtype.names and len(cloud):
                extra["speed"] = cloud["speed"].astype(np.float32)
            rec.log("/particles", rr.Points3D(**comps), rr.AnyValues(**extra) if extra else [])
            stats["clouds"] += 1
            stats["points_last"] = len(cloud)
        elif topic == "/walls":
            msg = decode(schema, message)
            rec.set_time(TIMELINE, duration=np.timedelta64(ns, "ns"))
            for d in msg.deletions:
                ids = list(last_wall) if d.type == d.ALL else [d.id]
                for i in ids:
                    rec.log(f"/walls/{i}", rr.Clear(recursive=False))
                    last_wall.pop(i, None)
            for e in msg.entities:
                shape = type(e)()
                shape.CopyFrom(e)
                shape.ClearField("timestamp")  # re-log a wall only when its shape or pose changes
                key = shape.SerializeToString(deterministic=True)
                if last_wall.get(e.id) == key:
                    continue
                last_wall[e.id] = key
                rec.log(f"/walls/{e.id}", *wall_archetypes(e, rr))
                stats["wall_updates"] += 1
        elif WALL_VECTOR_RE.match(topic) or SCALAR_RE.match(topic):
            v = decode(schema, message)
            times, values = series[topic]
            times.append(ns)
            values.append((v.x, v.y, v.z) if WALL_VECTOR_RE.match(topic) else (v.x,))
        else:
            stats["skipped"][topic] += 1  # e.g. /spheres: the same particles as /particles

    for entity, (times, values) in series.items():
        vals = np.asarray(values, dtype=np.float64)
        if vals.shape[1] == 3:
            unit = "N m" if entity.endswith("/torque") else "N"
            rec.log(entity, rr.SeriesLines(names=[f"x [{unit}]", f"y [{unit}]", f"z [{unit}]"]), static=True)
        else:
            rec.log(entity, rr.SeriesLines(names=[entity.rsplit("/", 1)[1]]), static=True)
            vals = vals[:, 0]
        rec.send_columns(
            entity,
            indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(times, dtype="timedelta64[ns]"))],
            columns=rr.Scalars.columns(scalars=vals),
        )
        stats["series_points"] += len(times)

    rec.flush()
    rec.disconnect()
    stats["speed_max"] = speed_max
    stats["series"] = sorted(series)
    stats["skipped"] = dict(stats["skipped"])
    stats["notes"] = notes
    if not quiet:
        print(
            f"wrote {out}: {stats['messages']} messages, {stats['clouds']} clouds "
            f"({stats['points_last']} points in the last), {stats['wall_updates']} wall updates, "
            f"{len(series)} time series ({stats['series_points']} points), colours 0..{speed_max:.4g} m/s"
        )
        for t, n in stats["skipped"].items():
            why = "same particles as /particles" if t == "/spheres" else "not a topic this converter knows"
            print(f"  skipped {n} messages on {t} ({why})")
        for n in notes:
            print(f"  {n}")
    return stats


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input", metavar="IN.mcap")
    ap.add_argument("output", metavar="OUT.rrd")
    ap.add_argument("--allow-partial", action="store_true", help="convert a truncated file up to the truncation")
    ap.add_argument("--speed-max", type=float, help="speed [m/s] mapped to the top of the colour map (default: run max)")
    ap.add_argument("--application-id", default="tilth", help='Rerun application id (default "tilth")')
    ap.add_argument("-q", "--quiet", action="store_true")
    args = ap.parse_args(argv)
    if not os.path.isfile(args.input):
        print(f"error: no such file {args.input}", file=sys.stderr)
        return 1
    convert(args.input, args.output, args.allow_partial, args.speed_max, args.application_id, args.quiet)
    return 0


if __name__ == "__main__":
    sys.exit(main())
