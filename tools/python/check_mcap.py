#!/usr/bin/env python3
"""Prove that tilth's MCAP run files are real: read and decode every message.

    python3 tools/python/check_mcap.py run.mcap [more.mcap ...] [--json]
    python3 tools/python/check_mcap.py run.mcap.partial --allow-partial

For each file this
  * reads every message with the official reader (mcap.reader.make_reader),
    validating chunk CRCs and the counts in the summary section;
  * decodes EVERY message with the class from foxglove_schemas_protobuf named
    by the channel's schema (e.g. "foxglove.PointCloud" ->
    foxglove_schemas_protobuf.PointCloud_pb2.PointCloud); a schema that is not a
    Foxglove one, a payload that does not parse or that carries fields the
    Foxglove type does not have is a failure; the FileDescriptorSet stored in the
    file must define the named type with the same fields as the Foxglove one;
  * checks the tilth layout: protobuf encodings, profile "" or "protobuf",
    log_time == publish_time and non-decreasing per topic, the /particles
    PointCloud (pose set, stride 28 and the 7 fields x y z radius speed id
    material, data length a multiple of the stride, finite values, radius > 0),
    /walls SceneUpdate entities, Vector3 wall forces/torques, /scalars/* with
    y = z = 0;
  * reads the metadata records ("tilth.run" and "tilth.channels" are required in
    a complete file).

It prints, per file, messages per topic, how many were decoded, the particle
counts of the first and last cloud, and the metadata; with --json, one JSON
document for all files. Exit status 1 (with "FAIL <file>: <reason>" on stderr)
if any file fails.

A run killed mid-way leaves a truncated file without a summary or footer
(run.mcap.partial). Without --allow-partial such a file fails with an error
saying it is "incomplete". With --allow-partial it is read as a stream from the
start, and the report says how many messages could be read and decoded before
the truncation; a partial file fails only if something before the truncation is
wrong (or if not a single message could be read). A run that stopped early but
closed its file keeps the .partial name with a complete MCAP structure: that too
is "incomplete" without --allow-partial, and is read in full with it.

Other topics than tilth's are allowed if their schema is a Foxglove one (e.g. the
optional /spheres SceneUpdate); they get the generic checks of their type.
"""

from __future__ import annotations

import argparse
import importlib
import io
import json
import math
import os
import re
import struct
import sys
from collections import OrderedDict
from typing import Any, Dict, List, Optional

import numpy as np
from google.protobuf import descriptor_pb2
from google.protobuf.message import DecodeError, Message as PbMessage
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Metadata

MAGIC = b"\x89MCAP0\r\n"
FOOTER_RECORD_SIZE = 1 + 8 + 8 + 8 + 4  # opcode, length, summary_start, summary_offset_start, crc

# --- tilth layout -------------------------------------------------------------------------------
PARTICLES_TOPIC = "/particles"
WALLS_TOPIC = "/walls"
WALL_VECTOR_RE = re.compile(r"^/walls/([^/]+)/(force|torque)$")
SCALAR_RE = re.compile(r"^/scalars/([^/]+)$")
# name -> (PackedElementField.NumericType name, offset)
PARTICLE_LAYOUT = OrderedDict(
    [
        ("x", ("FLOAT32", 0)),
        ("y", ("FLOAT32", 4)),
        ("z", ("FLOAT32", 8)),
        ("radius", ("FLOAT32", 12)),
        ("speed", ("FLOAT32", 16)),
        ("id", ("UINT32", 20)),
        ("material", ("UINT32", 24)),
    ]
)
PARTICLE_STRIDE = 28
RUN_KEYS_EXPECTED = ("run_id", "seed", "sweep", "scene", "tilth_version", "git_commit")

# PackedElementField.NumericType -> (numpy dtype, size in bytes)
NUMERIC_TYPES = {
    1: ("<u1", 1),  # UINT8
    2: ("<i1", 1),  # INT8
    3: ("<u2", 2),  # UINT16
    4: ("<i2", 2),  # INT16
    5: ("<u4", 4),  # UINT32
    6: ("<i4", 4),  # INT32
    7: ("<f4", 4),  # FLOAT32
    8: ("<f8", 8),  # FLOAT64
}


class CheckFailure(Exception):
    """A file is not a valid tilth MCAP file."""


class _NonSeekable(io.RawIOBase):
    """Hide seek() so that make_reader() returns its streaming (NonSeekingReader) reader."""

    def __init__(self, f):
        self._f = f

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return False

    def readinto(self, b) -> int:
        data = self._f.read(len(b))
        b[: len(data)] = data
        return len(data)


# --- Foxglove classes and schema comparison --------------------------------------------------------
_CLASS_CACHE: Dict[str, type] = {}


def foxglove_class(schema_name: str) -> type:
    """The foxglove_schemas_protobuf class for a schema name such as "foxglove.PointCloud"."""
    if schema_name in _CLASS_CACHE:
        return _CLASS_CACHE[schema_name]
    if not schema_name.startswith("foxglove.") or schema_name.count(".") != 1:
        raise CheckFailure(f"schema {schema_name!r} is not a Foxglove schema (expected 'foxglove.<Type>')")
    type_name = schema_name.split(".", 1)[1]
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9]*", type_name):
        raise CheckFailure(f"schema {schema_name!r} is not a Foxglove schema name")
    try:
        module = importlib.import_module(f"foxglove_schemas_protobuf.{type_name}_pb2")
        cls = getattr(module, type_name)
    except (ImportError, AttributeError):
        raise CheckFailure(
            f"schema {schema_name!r} is not one of foxglove_schemas_protobuf's types"
        ) from None
    if cls.DESCRIPTOR.full_name != schema_name:
        raise CheckFailure(f"schema {schema_name!r} resolves to {cls.DESCRIPTOR.full_name}")
    _CLASS_CACHE[schema_name] = cls
    return cls


def _fds_messages(fds: descriptor_pb2.FileDescriptorSet) -> Dict[str, descriptor_pb2.DescriptorProto]:
    out: Dict[str, descriptor_pb2.DescriptorProto] = {}

    def add(prefix: str, msg: descriptor_pb2.DescriptorProto) -> None:
        full = f"{prefix}.{msg.name}" if prefix else msg.name
        out[full] = msg
        for nested in msg.nested_type:
            add(full, nested)

    for fd in fds.file:
        for msg in fd.message_type:
            add(fd.package, msg)
    return out


def compare_schema(schema_name: str, schema_data: bytes, cls: type) -> List[str]:
    """Compare the FileDescriptorSet stored in the file with the Foxglove package's descriptor.

    Returns a list of warnings; raises CheckFailure on a real incompatibility (the named
    type is missing, or a field number has a different name or wire type)."""
    warnings: List[str] = []
    try:
        fds = descriptor_pb2.FileDescriptorSet.FromString(schema_data)
    except DecodeError as e:
        raise CheckFailure(f"schema {schema_name!r}: data is not a FileDescriptorSet ({e})") from None
    stored = _fds_messages(fds)
    if schema_name not in stored:
        raise CheckFailure(
            f"schema {schema_name!r}: its FileDescriptorSet does not define {schema_name} "
            f"(defines: {', '.join(sorted(stored)) or 'nothing'})"
        )

    # Walk the type graph from the named message, comparing field numbers, names and types.
    seen = set()
    todo = [(schema_name, cls.DESCRIPTOR)]
    while todo:
        full_name, pkg_desc = todo.pop()
        if full_name in seen:
            continue
        seen.add(full_name)
        if full_name not in stored:
            if full_name.startswith("google.protobuf."):
                continue  # well-known types may be referenced without being embedded by some writers
            raise CheckFailure(f"schema {schema_name!r}: FileDescriptorSet lacks the type {full_name}")
        stored_fields = {f.number: f for f in stored[full_name].field}
        pkg_fields = {f.number: f for f in pkg_desc.fields}
        for number, pf in pkg_fields.items():
            sf = stored_fields.get(number)
            if sf is None:
                warnings.append(f"{schema_name}: stored schema of {full_name} lacks field {pf.name} (#{number})")
                continue
            if sf.name != pf.name or sf.type != pf.type:
                raise CheckFailure(
                    f"schema {schema_name!r}: {full_name} field #{number} is {sf.name} (type {sf.type}) in the "
                    f"file but {pf.name} (type {pf.type}) in foxglove_schemas_protobuf"
                )
            if pf.message_type is not None:
                todo.append((pf.message_type.full_name, pf.message_type))
        for number, sf in stored_fields.items():
            if number not in pkg_fields:
                warnings.append(
                    f"{schema_name}: stored schema of {full_name} has field {sf.name} (#{number}) that "
                    f"foxglove_schemas_protobuf does not know (newer Foxglove schema?)"
                )
    return warnings


def unknown_field_paths(msg: PbMessage, path: str = "") -> List[str]:
    """Paths of sub-messages that carry fields their type does not define."""
    from google.protobuf import unknown_fields

    out = []
    if len(unknown_fields.UnknownFieldSet(msg)):
        out.append(path or "<root>")
    for fd, value in msg.ListFields():
        if fd.message_type is None:
            continue
        if fd.is_repeated:
            if fd.message_type.GetOptions().map_entry:
                continue
            for i, item in enumerate(value):
                out.extend(unknown_field_paths(item, f"{path}.{fd.name}[{i}]"))
        else:
            out.extend(unknown_field_paths(value, f"{path}.{fd.name}"))
    return out


# --- Per-message checks -------------------------------------------------------------------------------
def _finite(*vals: float) -> bool:
    return all(math.isfinite(v) for v in vals)


def _check_pose(pose, what: str) -> None:
    p, q = pose.position, pose.orientation
    if not _finite(p.x, p.y, p.z, q.x, q.y, q.z, q.w):
        raise CheckFailure(f"{what}: pose has non-finite values")
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if abs(norm - 1.0) > 1e-3:
        raise CheckFailure(f"{what}: pose orientation is not a unit quaternion (|q| = {norm:.6g})")


def check_point_cloud(msg, where: str, tilth_layout: bool) -> int:
    """Checks a foxglove.PointCloud; returns its number of points."""
    if not msg.HasField("pose"):
        raise CheckFailure(f"{where}: PointCloud pose is not set")
    if not msg.pose.HasField("orientation"):
        raise CheckFailure(f"{where}: PointCloud pose.orientation is not set")
    _check_pose(msg.pose, where)
    stride = msg.point_stride
    if stride <= 0:
        raise CheckFailure(f"{where}: PointCloud point_stride is {stride}")
    if len(msg.data) % stride != 0:
        raise CheckFailure(
            f"{where}: PointCloud data length {len(msg.data)} is not a multiple of point_stride {stride}"
        )
    n = len(msg.data) // stride
    names, formats, offsets = [], [], []
    spans = []
    for f in msg.fields:
        if f.name in names:
            raise CheckFailure(f"{where}: PointCloud field {f.name!r} appears twice")
        if f.type not in NUMERIC_TYPES:
            raise CheckFailure(f"{where}: PointCloud field {f.name!r} has unknown numeric type {f.type}")
        dtype, size = NUMERIC_TYPES[f.type]
        if f.offset + size > stride:
            raise CheckFailure(
                f"{where}: PointCloud field {f.name!r} (offset {f.offset}, {size} bytes) runs past point_stride {stride}"
            )
        for other, lo, hi in spans:
            if f.offset < hi and lo < f.offset + size:
                raise CheckFailure(f"{where}: PointCloud fields {other!r} and {f.name!r} overlap")
        spans.append((f.name, f.offset, f.offset + size))
        names.append(f.name)
        formats.append(dtype)
        offsets.append(f.offset)
    coords = [c for c in ("x", "y", "z") if c in names]
    if len(coords) < 2:
        raise CheckFailure(f"{where}: PointCloud needs at least 2 of the fields x, y, z (has {names})")

    if tilth_layout:
        from foxglove_schemas_protobuf.PackedElementField_pb2 import PackedElementField

        if msg.frame_id != "world":
            raise CheckFailure(f"{where}: frame_id is {msg.frame_id!r}, tilth writes 'world'")
        if stride != PARTICLE_STRIDE:
            raise CheckFailure(f"{where}: point_stride is {stride}, tilth's layout has {PARTICLE_STRIDE}")
        got = OrderedDict((f.name, (PackedElementField.NumericType.Name(f.type), f.offset)) for f in msg.fields)
        if got != PARTICLE_LAYOUT:
            raise CheckFailure(
                f"{where}: fields are {dict(got)}, tilth's layout is {dict(PARTICLE_LAYOUT)}"
            )

    if n:
        arr = np.frombuffer(
            msg.data, dtype=np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": stride})
        )
        for name in names:
            col = arr[name]
            if col.dtype.kind == "f" and not np.isfinite(col).all():
                raise CheckFailure(f"{where}: PointCloud field {name!r} has non-finite values")
        if tilth_layout:
            if not (arr["radius"] > 0).all():
                raise CheckFailure(f"{where}: particle radius <= 0")
            if not (arr["speed"] >= 0).all():
                raise CheckFailure(f"{where}: particle speed < 0")
            if len(np.unique(arr["id"])) != n:
                raise CheckFailure(f"{where}: particle ids are not unique")
    return n


def check_scene_update(msg, where: str, walls: bool) -> List[str]:
    """Checks a foxglove.SceneUpdate; with walls=True (the /walls topic) also tilth's wall rules."""
    ids = []
    for e in msg.entities:
        if not e.id and walls:
            raise CheckFailure(f"{where}: SceneEntity without an id (tilth uses the wall name)")
        if e.id in ids:
            raise CheckFailure(f"{where}: SceneEntity id {e.id!r} appears twice")
        ids.append(e.id)
        n_prims = len(e.cylinders) + len(e.cubes) + len(e.triangles)
        if walls and n_prims == 0:
            raise CheckFailure(f"{where}: wall {e.id!r} has no Cylinder/Cube/TriangleList primitive")
        for sp in e.spheres:
            _check_pose(sp.pose, f"{where}: entity {e.id!r} sphere")
            if not _finite(sp.size.x, sp.size.y, sp.size.z) or min(sp.size.x, sp.size.y, sp.size.z) <= 0:
                raise CheckFailure(f"{where}: entity {e.id!r} has a sphere with an invalid size")
        for c in list(e.cylinders) + list(e.cubes):
            _check_pose(c.pose, f"{where}: entity {e.id!r}")
            if not _finite(c.size.x, c.size.y, c.size.z) or min(c.size.x, c.size.y, c.size.z) < 0:
                raise CheckFailure(f"{where}: entity {e.id!r} has a cube/cylinder with an invalid size")
        for t in e.triangles:
            n_idx = len(t.indices) if len(t.indices) else len(t.points)
            if n_idx % 3:
                raise CheckFailure(f"{where}: entity {e.id!r} TriangleList has {n_idx} vertices, not a multiple of 3")
            if len(t.indices) and max(t.indices) >= len(t.points):
                raise CheckFailure(f"{where}: entity {e.id!r} TriangleList index out of range")
            if t.colors and len(t.colors) != len(t.points):
                raise CheckFailure(f"{where}: entity {e.id!r} TriangleList colors/points length mismatch")
    return ids


# --- File-level check ---------------------------------------------------------------------------------
def file_is_complete(path: str) -> Optional[str]:
    """None if the file ends with a footer and the closing magic, else why not."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(len(MAGIC))
        if head != MAGIC:
            raise CheckFailure("not an MCAP file (bad leading magic)")
        if size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
            return f"only {size} bytes: no footer"
        f.seek(-len(MAGIC), os.SEEK_END)
        if f.read(len(MAGIC)) != MAGIC:
            return "does not end with the MCAP magic: no footer/summary section (truncated?)"
        f.seek(-(len(MAGIC) + FOOTER_RECORD_SIZE), os.SEEK_END)
        rec = f.read(FOOTER_RECORD_SIZE)
        if rec[0] != 0x02 or struct.unpack_from("<Q", rec, 1)[0] != 20:
            return "no footer record before the closing magic"
    return None


class Report:
    def __init__(self, path: str):
        self.path = path
        self.ok = True
        self.error: Optional[str] = None
        self.complete: Optional[bool] = None
        self.truncation: Optional[str] = None
        self.profile: Optional[str] = None
        self.library: Optional[str] = None
        self.topics: Dict[str, Dict[str, Any]] = OrderedDict()
        self.messages_read = 0
        self.messages_decoded = 0
        self.first_cloud: Optional[Dict[str, int]] = None
        self.last_cloud: Optional[Dict[str, int]] = None
        self.walls: List[str] = []
        self.time_range_ns: Optional[List[int]] = None
        self.metadata: Dict[str, Dict[str, str]] = OrderedDict()
        self.warnings: List[str] = []

    def as_dict(self) -> Dict[str, Any]:
        return {
            "file": self.path,
            "ok": self.ok,
            "error": self.error,
            "complete": self.complete,
            "truncation": self.truncation,
            "profile": self.profile,
            "library": self.library,
            "messages_read": self.messages_read,
            "messages_decoded": self.messages_decoded,
            "topics": self.topics,
            "time_range_ns": self.time_range_ns,
            "first_cloud": self.first_cloud,
            "last_cloud": self.last_cloud,
            "walls": self.walls,
            "metadata": self.metadata,
            "warnings": self.warnings,
        }


class FileChecker:
    def __init__(self, report: Report):
        self.r = report
        self.last_time: Dict[str, int] = {}
        self.checked_schemas: Dict[int, type] = {}
        self.wall_vectors: set = set()

    def on_schema(self, schema, channel) -> type:
        if schema is None:
            raise CheckFailure(f"channel {channel.topic!r} has no schema")
        cached = self.checked_schemas.get(schema.id)
        if cached is not None:
            return cached
        if schema.encoding != "protobuf":
            raise CheckFailure(f"channel {channel.topic!r}: schema encoding is {schema.encoding!r}, expected 'protobuf'")
        cls = foxglove_class(schema.name)
        self.r.warnings.extend(compare_schema(schema.name, schema.data, cls))
        self.checked_schemas[schema.id] = cls
        return cls

    def on_message(self, schema, channel, message) -> None:
        topic = channel.topic
        self.r.messages_read += 1
        t = self.r.topics.get(topic)
        if t is None:
            if channel.message_encoding != "protobuf":
                raise CheckFailure(
                    f"channel {topic!r}: message_encoding is {channel.message_encoding!r}, expected 'protobuf'"
                )
            cls = self.on_schema(schema, channel)
            expected = expected_schema(topic)
            if expected and cls.DESCRIPTOR.full_name != expected:
                raise CheckFailure(f"channel {topic!r} has schema {cls.DESCRIPTOR.full_name}, tilth writes {expected}")
            t = self.r.topics[topic] = OrderedDict(
                [
                    ("schema", schema.name),
                    ("unit", dict(channel.metadata).get("unit")),
                    ("messages", 0),
                    ("decoded", 0),
                    ("first_ns", None),
                    ("last_ns", None),
                ]
            )
        cls = self.on_schema(schema, channel)
        where = f"{topic} @ log_time {message.log_time}"
        t["messages"] += 1

        if message.log_time != message.publish_time:
            raise CheckFailure(f"{where}: publish_time {message.publish_time} != log_time (both must be simulated time)")
        prev = self.last_time.get(topic)
        if prev is not None and message.log_time < prev:
            raise CheckFailure(f"{where}: log_time goes backwards (previous {prev})")
        self.last_time[topic] = message.log_time
        if t["first_ns"] is None:
            t["first_ns"] = message.log_time
        t["last_ns"] = message.log_time

        try:
            msg = cls.FromString(message.data)
        except DecodeError as e:
            raise CheckFailure(f"{where}: payload does not decode as {schema.name}: {e}") from None
        unknown = unknown_field_paths(msg)
        if unknown:
            raise CheckFailure(
                f"{where}: payload decoded as {schema.name} has fields that type does not define "
                f"(at {', '.join(unknown[:3])}): wrong schema or newer Foxglove schema"
            )
        self.check_semantics(topic, msg, where, message.log_time)
        t["decoded"] += 1
        self.r.messages_decoded += 1
        lo_hi = self.r.time_range_ns
        self.r.time_range_ns = [
            message.log_time if lo_hi is None else min(lo_hi[0], message.log_time),
            message.log_time if lo_hi is None else max(lo_hi[1], message.log_time),
        ]

    def check_semantics(self, topic: str, msg, where: str, ns: int) -> None:
        name = msg.DESCRIPTOR.full_name
        if name == "foxglove.PointCloud":
            n = check_point_cloud(msg, where, tilth_layout=(topic == PARTICLES_TOPIC))
            if topic == PARTICLES_TOPIC:
                if self.r.first_cloud is None:
                    self.r.first_cloud = {"log_time_ns": ns, "particles": n}
                self.r.last_cloud = {"log_time_ns": ns, "particles": n}
        elif name == "foxglove.SceneUpdate":
            ids = check_scene_update(msg, where, walls=(topic == WALLS_TOPIC))
            if topic == WALLS_TOPIC:
                for i in ids:
                    if i not in self.r.walls:
                        self.r.walls.append(i)
        elif name == "foxglove.Vector3":
            if not _finite(msg.x, msg.y, msg.z):
                raise CheckFailure(f"{where}: non-finite Vector3 ({msg.x}, {msg.y}, {msg.z})")
            m = WALL_VECTOR_RE.match(topic)
            if m:
                self.wall_vectors.add(m.group(1))
            if SCALAR_RE.match(topic) and (msg.y != 0.0 or msg.z != 0.0):
                raise CheckFailure(f"{where}: scalar channel must have y = z = 0, got ({msg.x}, {msg.y}, {msg.z})")

    def finish(self, complete: bool) -> None:
        r = self.r
        if PARTICLES_TOPIC not in r.topics:
            if complete:
                raise CheckFailure(f"no {PARTICLES_TOPIC} messages")
            r.warnings.append(f"no {PARTICLES_TOPIC} message before the truncation")
        if r.walls:
            for w in sorted(self.wall_vectors - set(r.walls)):
                r.warnings.append(f"/walls/{w}/force|torque has no entity {w!r} on {WALLS_TOPIC}")
        for name in ("tilth.run", "tilth.channels"):
            if name not in r.metadata:
                if complete:
                    raise CheckFailure(f'metadata record "{name}" is missing')
                r.warnings.append(f'metadata record "{name}" not found before the truncation')
        run = r.metadata.get("tilth.run", {})
        missing = [k for k in RUN_KEYS_EXPECTED if k not in run]
        if run and missing:
            r.warnings.append(f'"tilth.run" lacks the keys {missing}')
        chans = r.metadata.get("tilth.channels")
        if chans is not None:
            # keys may be patterns such as "/walls/<name>/force"
            patterns = [re.compile("^" + re.sub(r"<[^>/]+>", "[^/]+", re.escape(k)) + "$") for k in chans]
            undocumented = [t for t in r.topics if t not in chans and not any(p.match(t) for p in patterns)]
            if undocumented:
                r.warnings.append(f'"tilth.channels" does not describe {undocumented}')


def expected_schema(topic: str) -> Optional[str]:
    if topic == PARTICLES_TOPIC:
        return "foxglove.PointCloud"
    if topic == WALLS_TOPIC:
        return "foxglove.SceneUpdate"
    if WALL_VECTOR_RE.match(topic) or SCALAR_RE.match(topic):
        return "foxglove.Vector3"
    return None


def _add_metadata(report: Report, records) -> None:
    for m in records:
        if not isinstance(m, Metadata):
            continue
        if m.name in report.metadata:
            report.warnings.append(f'metadata record "{m.name}" appears more than once; keeping the last')
        report.metadata[m.name] = dict(m.metadata)


def _check_header(report: Report, reader) -> None:
    header = reader.get_header()
    report.profile = header.profile
    report.library = header.library
    if header.profile not in ("", "protobuf"):
        raise CheckFailure(f'header profile is {header.profile!r}, expected "" or "protobuf"')


def check_complete(path: str, report: Report) -> None:
    checker = FileChecker(report)
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        _check_header(report, reader)
        try:
            summary = reader.get_summary()
        except (McapError, struct.error, ValueError, EOFError) as e:
            raise CheckFailure(f"incomplete or corrupt summary section: {e}") from None
        if summary is None:
            raise CheckFailure("no summary section (the footer says summary_start = 0)")
        # File order (not log-time order), so that the per-topic time-order check tests the writer.
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            checker.on_message(schema, channel, message)
        _add_metadata(report, reader.iter_metadata())
        stats = summary.statistics
        if stats is not None:
            if stats.message_count != report.messages_read:
                raise CheckFailure(
                    f"summary statistics say {stats.message_count} messages, read {report.messages_read}"
                )
            for ch_id, count in stats.channel_message_counts.items():
                topic = summary.channels[ch_id].topic
                got = report.topics.get(topic, {}).get("messages", 0)
                if got != count:
                    raise CheckFailure(f"summary statistics say {count} messages on {topic}, read {got}")
            if stats.metadata_count != sum(1 for _ in summary.metadata_indexes):
                report.warnings.append("metadata_count in statistics differs from the metadata index")
        else:
            report.warnings.append("summary section has no statistics record")
        for ch in summary.channels.values():
            if ch.topic not in report.topics:
                report.warnings.append(f"channel {ch.topic!r} has no messages")
    checker.finish(complete=True)


def check_partial(path: str, report: Report) -> None:
    """Stream from the start and stop at the truncation."""
    checker = FileChecker(report)
    with open(path, "rb") as f:
        reader = make_reader(_NonSeekable(f), validate_crcs=True)
        try:
            for schema, channel, message in reader.iter_messages(log_time_order=False):
                checker.on_message(schema, channel, message)
        except CheckFailure:
            raise
        except Exception as e:  # noqa: BLE001 - any reader error here is the truncation point
            detail = str(e).strip() or "the file ends inside a record"
            if "length 18446744073709551615" in detail:
                # Rust's mcap crate writes a chunk's length (u64::MAX until then) when it closes it
                detail = "the last chunk was still being written (its length was never filled in)"
            report.truncation = f"{type(e).__name__}: {detail}; file size {os.path.getsize(path)} bytes"
        else:
            report.truncation = None
    # Metadata: a second streaming pass (a NonSeekingReader serves one query only).
    with open(path, "rb") as f:
        records = []
        try:
            for rec in make_reader(_NonSeekable(f)).iter_metadata():
                records.append(rec)
        except Exception:  # noqa: BLE001 - stop at the truncation
            pass
        _add_metadata(report, records)
    with open(path, "rb") as f:
        try:
            _check_header(report, make_reader(f))
        except CheckFailure:
            raise
        except Exception as e:  # noqa: BLE001
            raise CheckFailure(f"incomplete file: even the header record is truncated ({type(e).__name__})") from None
    if report.messages_read == 0:
        raise CheckFailure(f"incomplete file: not a single message could be read ({report.truncation})")
    checker.finish(complete=False)


def check_file(path: str, allow_partial: bool) -> Report:
    report = Report(path)
    try:
        if not os.path.isfile(path):
            raise CheckFailure("no such file")
        why = file_is_complete(path)
        report.complete = why is None
        named_partial = path.endswith(".partial")
        if why is None and named_partial and not allow_partial:
            raise CheckFailure(
                "incomplete run: the file is named .partial (tilth stopped before the end of the run and "
                "kept the .partial name), although its MCAP structure is complete. Use --allow-partial to accept it"
            )
        if why is None:
            check_complete(path, report)
        elif not allow_partial:
            raise CheckFailure(
                f"incomplete MCAP file ({why}); a run killed mid-way leaves such a file "
                f"(run.mcap.partial). Use --allow-partial to count the messages before the truncation"
            )
        else:
            check_partial(path, report)
        if named_partial and report.complete:
            report.warnings.append(
                "named .partial: a run that stopped early but closed its file (summary present); all of it was read"
            )
    except CheckFailure as e:
        report.ok = False
        report.error = str(e)
    except (McapError, DecodeError, struct.error, ValueError, EOFError, OSError) as e:
        report.ok = False
        report.error = f"{type(e).__name__}: {e}"
    return report


# --- Output -------------------------------------------------------------------------------------------
def _fmt_ns(ns: Optional[int]) -> str:
    return "-" if ns is None else f"{ns / 1e9:.6f} s"


def print_text(rep: Report, out) -> None:
    status = "OK" if rep.ok else "FAIL"
    kind = "complete" if rep.complete else ("partial" if rep.complete is False else "?")
    print(f"== {rep.path}: {status} ({kind})", file=out)
    if rep.error:
        print(f"   error: {rep.error}", file=out)
    if rep.profile is not None:
        print(f"   profile {rep.profile!r}, library {rep.library!r}", file=out)
    if rep.complete is False and rep.ok:
        print(
            f"   truncated: read and decoded {rep.messages_decoded} messages before the truncation"
            + (f" ({rep.truncation})" if rep.truncation else " (stream ended cleanly)"),
            file=out,
        )
    print(f"   messages read {rep.messages_read}, decoded {rep.messages_decoded}", file=out)
    if rep.time_range_ns:
        print(f"   simulated time {_fmt_ns(rep.time_range_ns[0])} .. {_fmt_ns(rep.time_range_ns[1])}", file=out)
    if rep.topics:
        w = max(len(t) for t in rep.topics)
        for topic, t in rep.topics.items():
            unit = f"  [{t['unit']}]" if t.get("unit") else ""
            print(f"   {topic:<{w}}  {t['messages']:>7} msgs  {t['decoded']:>7} decoded  {t['schema']}{unit}", file=out)
    if rep.first_cloud:
        print(
            f"   particles: first cloud {rep.first_cloud['particles']} @ {_fmt_ns(rep.first_cloud['log_time_ns'])}, "
            f"last cloud {rep.last_cloud['particles']} @ {_fmt_ns(rep.last_cloud['log_time_ns'])}",
            file=out,
        )
    if rep.walls:
        print(f"   walls: {', '.join(rep.walls)}", file=out)
    for name, kv in rep.metadata.items():
        print(f"   metadata {name}:", file=out)
        for k, v in kv.items():
            print(f"     {k} = {v}", file=out)
    for wmsg in rep.warnings:
        print(f"   warning: {wmsg}", file=out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+", metavar="FILE")
    ap.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    ap.add_argument(
        "--allow-partial",
        action="store_true",
        help="accept truncated files (no summary/footer) and report how many messages precede the truncation",
    )
    ap.add_argument("--strict", action="store_true", help="treat warnings as failures")
    args = ap.parse_args(argv)

    reports = [check_file(p, args.allow_partial) for p in args.files]
    if args.strict:
        for rep in reports:
            if rep.ok and rep.warnings:
                rep.ok = False
                rep.error = "warnings with --strict: " + "; ".join(rep.warnings)
    if args.json:
        json.dump({"ok": all(r.ok for r in reports), "files": [r.as_dict() for r in reports]}, sys.stdout, indent=2)
        print()
    else:
        for rep in reports:
            print_text(rep, sys.stdout)
    failed = [r for r in reports if not r.ok]
    for rep in failed:
        print(f"FAIL {rep.path}: {rep.error}", file=sys.stderr)
    if not args.json:
        print(f"{len(reports) - len(failed)} passed, {len(failed)} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
