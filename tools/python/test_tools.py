#!/usr/bin/env python3
"""Tests for the MCAP/Rerun tools (stdlib unittest; no pytest needed).

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v

Each test works on a small sample written by make_sample_mcap.py, or on a copy of it
rewritten with one defect, and runs the scripts as a CI job would (subprocesses).
The Rerun tests need the rerun-sdk from requirements.txt (the `rerun` CLI ships in it).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from mcap.reader import make_reader  # noqa: E402
from mcap.writer import CompressionType, Writer  # noqa: E402

PY = sys.executable
# messages per frame in the sample: /particles, /walls, 4 walls x (force, torque), 3 scalars
PER_FRAME = 1 + 1 + 4 * 2 + 3


def run(*args, check=None):
    proc = subprocess.run([PY, *args], capture_output=True, text=True, cwd=HERE)
    if check is not None and proc.returncode != check:
        raise AssertionError(
            f"{' '.join(args)} exited {proc.returncode}, expected {check}\nstdout:\n{proc.stdout}\nstderr:\n{proc.stderr}"
        )
    return proc


def rewrite(src, dst, message_fn=None, metadata_fn=None, profile=None):
    """Copy an MCAP file record by record, letting message_fn/metadata_fn change or drop records.

    message_fn(topic, schema_name, schema_data, data, log_time, publish_time) returns
    (schema_name, schema_data, data, log_time, publish_time) or None to drop the message."""
    with open(src, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        messages = list(reader.iter_messages(log_time_order=False))
    w = Writer(dst, compression=CompressionType.ZSTD, chunk_size=64 * 1024)
    w.start(profile=header.profile if profile is None else profile, library=header.library)
    for name, kv in metadata:
        if metadata_fn:
            kv = metadata_fn(name, kv)
        if kv is not None:
            w.add_metadata(name, kv)
    schemas, channels = {}, {}
    for schema, channel, msg in messages:
        rec = (schema.name, schema.data, msg.data, msg.log_time, msg.publish_time)
        if message_fn:
            rec = message_fn(channel.topic, *rec)
        if rec is None:
            continue
        sname, sdata, data, lt, pt = rec
        skey = (sname, sdata)
        if skey not in schemas:
            schemas[skey] = w.register_schema(name=sname, encoding="protobuf", data=sdata)
        ckey = (channel.topic, schemas[skey])
        if ckey not in channels:
            channels[ckey] = w.register_channel(topic=channel.topic, message_encoding="protobuf", schema_id=schemas[skey])
        w.add_message(channel_id=channels[ckey], log_time=lt, data=data, publish_time=pt)
    w.finish()


class Base(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="tilth-tools-")
        cls.sample = os.path.join(cls.tmp, "run.mcap")
        run("make_sample_mcap.py", cls.sample, "--frames", "60", "--particles", "200", check=0)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.tmp, name)

    def check_fails(self, path, *needles, extra=()):
        proc = run("check_mcap.py", path, *extra, check=1)
        for needle in needles:
            self.assertIn(needle, proc.stderr)
        return proc


class CheckMcapTest(Base):
    def test_sample_passes_and_reports(self):
        proc = run("check_mcap.py", self.sample, "--json", check=0)
        rep = json.loads(proc.stdout)["files"][0]
        self.assertTrue(rep["complete"])
        self.assertEqual(rep["messages_read"], 60 * PER_FRAME)
        self.assertEqual(rep["messages_decoded"], rep["messages_read"])
        self.assertEqual(rep["topics"]["/particles"]["messages"], 60)
        self.assertEqual(rep["first_cloud"]["particles"], 7)
        self.assertEqual(rep["last_cloud"]["particles"], 200)
        self.assertEqual(rep["walls"], ["drum", "floor", "chute", "hopper"])
        self.assertEqual(rep["topics"]["/walls/drum/force"]["unit"], "N")
        self.assertEqual(rep["topics"]["/scalars/kinetic_energy"]["unit"], "J")
        self.assertEqual(rep["metadata"]["tilth.run"]["seed"], "7")
        self.assertIn("/scalars/kinetic_energy", rep["metadata"]["tilth.channels"])
        self.assertEqual(rep["warnings"], [])

    def test_profile_protobuf_passes(self):
        dst = self.path("profile.mcap")
        rewrite(self.sample, dst, profile="protobuf")
        run("check_mcap.py", dst, "--strict", check=0)

    def test_truncated_is_incomplete_unless_allowed(self):
        dst = self.path("run.mcap.partial")
        with open(self.sample, "rb") as f:
            data = f.read()
        with open(dst, "wb") as f:
            f.write(data[: len(data) * 6 // 10])
        self.check_fails(dst, "incomplete")
        proc = run("check_mcap.py", dst, "--allow-partial", "--json", check=0)
        rep = json.loads(proc.stdout)["files"][0]
        self.assertFalse(rep["complete"])
        self.assertGreater(rep["messages_read"], 0)
        self.assertLess(rep["messages_read"], 60 * PER_FRAME)
        self.assertEqual(rep["messages_read"], rep["messages_decoded"])
        self.assertIsNotNone(rep["truncation"])

    def test_killed_inside_unfinished_chunk(self):
        # What tilth's Rust writer (mcap crate) leaves when killed: the last chunk's record
        # length is still u64::MAX and its data is cut short.
        with open(self.sample, "rb") as f:
            summary = make_reader(f).get_summary()
            f.seek(0)
            data = bytearray(f.read())
        chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
        last = chunks[len(chunks) // 2]
        start = last.chunk_start_offset
        data[start + 1 : start + 9] = b"\xff" * 8
        dst = self.path("killed.mcap.partial")
        with open(dst, "wb") as f:
            f.write(bytes(data[: start + 200]))
        self.check_fails(dst, "incomplete")
        proc = run("check_mcap.py", dst, "--allow-partial", "--json", check=0)
        rep = json.loads(proc.stdout)["files"][0]
        self.assertIn("the last chunk was still being written", rep["truncation"])
        # exactly the messages of the chunks before the unfinished one
        from mcap.data_stream import ReadDataStream
        from mcap.records import Chunk, Message
        from mcap.stream_reader import breakup_chunk

        expected = 0
        with open(self.sample, "rb") as f:
            for ci in chunks:
                if ci.chunk_start_offset >= start:
                    break
                f.seek(ci.chunk_start_offset + 1 + 8)
                chunk = Chunk.read(ReadDataStream(f))
                expected += sum(isinstance(r, Message) for r in breakup_chunk(chunk))
        self.assertGreater(expected, 0)
        self.assertEqual(rep["messages_read"], expected)

    def test_truncated_inside_header_fails_even_if_allowed(self):
        dst = self.path("tiny.mcap.partial")
        with open(self.sample, "rb") as f:
            data = f.read(40)
        with open(dst, "wb") as f:
            f.write(data)
        self.check_fails(dst, "incomplete", extra=("--allow-partial",))

    def test_not_mcap(self):
        dst = self.path("junk.mcap")
        with open(dst, "wb") as f:
            f.write(b"hello world, this is not an mcap file at all" * 4)
        self.check_fails(dst, "not an MCAP file")

    def test_non_foxglove_schema(self):
        dst = self.path("custom.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/scalars/contacts":
                sname = "tilth.Scalar"
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "not a Foxglove schema")

    def test_unknown_foxglove_type(self):
        dst = self.path("unknown_type.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/scalars/contacts":
                sname = "foxglove.Scalar"
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "not one of foxglove_schemas_protobuf's types")

    def test_garbage_payload(self):
        dst = self.path("garbage.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/walls" and lt > 0:
                data = b"\xff\xff\xff\xff\xff"
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "does not decode as foxglove.SceneUpdate")

    def test_payload_of_another_type(self):
        # a Vector3 payload on a channel that claims PointCloud: parses, but only as unknown fields
        from foxglove_schemas_protobuf.Vector3_pb2 import Vector3

        dst = self.path("mislabelled.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/particles" and lt > 0:
                data = Vector3(x=1.0, y=2.0, z=3.0).SerializeToString()
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "fields that type does not define")

    def _edit_cloud(self, name, edit):
        from foxglove_schemas_protobuf.PointCloud_pb2 import PointCloud

        dst = self.path(name)

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/particles":
                msg = PointCloud.FromString(data)
                edit(msg)
                data = msg.SerializeToString()
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        return dst

    def test_cloud_without_pose(self):
        self.check_fails(self._edit_cloud("nopose.mcap", lambda m: m.ClearField("pose")), "pose is not set")

    def test_cloud_data_not_multiple_of_stride(self):
        def edit(m):
            m.data = m.data + b"\x00" * 5

        self.check_fails(self._edit_cloud("stride.mcap", edit), "not a multiple of point_stride")

    def test_cloud_field_past_stride(self):
        def edit(m):
            m.fields[-1].offset = 26

        self.check_fails(self._edit_cloud("field.mcap", edit), "runs past point_stride")

    def test_cloud_layout_differs(self):
        def edit(m):
            m.fields[3].name = "r"

        self.check_fails(self._edit_cloud("layout.mcap", edit), "tilth's layout")

    def test_scalar_with_y(self):
        from foxglove_schemas_protobuf.Vector3_pb2 import Vector3

        dst = self.path("scalar_y.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/scalars/kinetic_energy":
                v = Vector3.FromString(data)
                v.y = 1.0
                data = v.SerializeToString()
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "y = z = 0")

    def test_publish_time_differs(self):
        dst = self.path("publish.mcap")
        rewrite(self.sample, dst, lambda t, s, d, data, lt, pt: (s, d, data, lt, pt + 1))
        self.check_fails(dst, "publish_time")

    def test_time_going_backwards(self):
        dst = self.path("backwards.mcap")
        seen = {"n": 0}

        def fn(topic, sname, sdata, data, lt, pt):
            if topic == "/scalars/contacts":
                seen["n"] += 1
                if seen["n"] == 30:
                    lt = pt = lt - 20_000_000
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "log_time goes backwards")

    def test_missing_metadata(self):
        dst = self.path("nometa.mcap")
        rewrite(self.sample, dst, metadata_fn=lambda name, kv: None if name == "tilth.run" else kv)
        self.check_fails(dst, '"tilth.run" is missing')

    def test_closed_partial_needs_allow_partial(self):
        # a run stopped early whose file was closed: complete MCAP structure, .partial name
        dst = self.path("closed.mcap.partial")
        shutil.copy(self.sample, dst)
        self.check_fails(dst, "incomplete run")
        proc = run("check_mcap.py", dst, "--allow-partial", "--json", check=0)
        rep = json.loads(proc.stdout)["files"][0]
        self.assertTrue(rep["complete"])
        self.assertEqual(rep["messages_read"], 60 * PER_FRAME)

    def test_spheres_topic_accepted(self):
        dst = self.path("spheres.mcap")
        run("make_sample_mcap.py", dst, "--frames", "10", "--particles", "30", "--spheres", check=0)
        proc = run("check_mcap.py", dst, "--json", "--strict", check=0)
        rep = json.loads(proc.stdout)["files"][0]
        self.assertEqual(rep["topics"]["/spheres"]["schema"], "foxglove.SceneUpdate")

    def test_schema_mismatch_fails(self):
        # the stored FileDescriptorSet must agree with foxglove_schemas_protobuf's
        from google.protobuf import descriptor_pb2

        dst = self.path("schema_mismatch.mcap")

        def fn(topic, sname, sdata, data, lt, pt):
            if sname == "foxglove.Vector3":
                fds = descriptor_pb2.FileDescriptorSet.FromString(sdata)
                for fd in fds.file:
                    for m in fd.message_type:
                        if m.name == "Vector3":
                            m.field[0].name = "u"
                sdata = fds.SerializeToString()
            return sname, sdata, data, lt, pt

        rewrite(self.sample, dst, fn)
        self.check_fails(dst, "foxglove.Vector3 field #1 is u")

    def test_several_files_one_bad(self):
        dst = self.path("junk2.mcap")
        with open(dst, "wb") as f:
            f.write(b"\x89MCAP0\r\n" + b"\x00" * 10)
        proc = run("check_mcap.py", self.sample, dst, check=1)
        self.assertIn("1 passed, 1 failed", proc.stdout)


class GeometryTest(unittest.TestCase):
    def test_cone_mesh(self):
        import numpy as np
        from foxglove_schemas_protobuf.CylinderPrimitive_pb2 import CylinderPrimitive

        import mcap_to_rrd as m

        c = CylinderPrimitive(bottom_scale=0.25, top_scale=1.0)
        c.size.x = c.size.y = 0.08
        c.size.z = 0.06
        c.pose.position.z = 1.0
        c.pose.orientation.w = 1.0
        self.assertTrue(m._is_cone(c))
        verts, tris, cols = m.cone_mesh(c, segments=16)
        r = np.hypot(verts[:, 0], verts[:, 1])
        self.assertAlmostEqual(r[:16].max(), 0.01, places=6)  # bottom ring: 0.04 * 0.25
        self.assertAlmostEqual(r[16:32].max(), 0.04, places=6)  # top ring
        self.assertAlmostEqual(verts[:, 2].min(), 0.97, places=6)
        self.assertAlmostEqual(verts[:, 2].max(), 1.03, places=6)
        self.assertEqual(tris.max(), len(verts) - 1)
        self.assertEqual(len(cols), len(verts))

    def test_quat_rotate(self):
        import math

        import numpy as np

        import mcap_to_rrd as m

        q = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # +90 deg about z
        out = m.quat_rotate(q, np.array([[1.0, 0.0, 0.0]]))
        np.testing.assert_allclose(out, [[0.0, 1.0, 0.0]], atol=1e-12)


class RerunTest(Base):
    def test_mcap_to_rrd_and_check_rrd(self):
        rrd = self.path("out.rrd")
        run("mcap_to_rrd.py", self.sample, rrd, check=0)
        proc = run(
            "check_rrd.py",
            rrd,
            "--json",
            "--entity", "/particles",
            "--entity", "/walls/drum",
            "--component", "/walls/hopper=Mesh3D:vertex_positions",
            "--entity", "/walls/drum/force",
            "--entity", "/scalars/kinetic_energy",
            "--component", "/particles=Points3D:radii",
            "--component", "/particles=Points3D:colors",
            "--component", "/scalars/kinetic_energy=Scalars:scalars",
            "--min-rows", "60",
            check=0,
        )
        rep = json.loads(proc.stdout)
        self.assertEqual(rep["verify"], "ok")
        self.assertEqual(rep["recording_id"], "sample-0007")
        self.assertEqual(rep["entities"]["/particles"]["rows"], 60)
        self.assertEqual(rep["entities"]["/particles"]["timelines"], ["sim_time"])
        self.assertIn("seed", rep["entities"]["/__properties/tilth.run"]["components"])

    def test_check_rrd_missing_entity_fails(self):
        rrd = self.path("out2.rrd")
        run("mcap_to_rrd.py", self.sample, rrd, check=0)
        proc = run("check_rrd.py", rrd, "--entity", "/nope", check=1)
        self.assertIn("entity /nope is missing", proc.stderr)

    def test_partial_conversion(self):
        part = self.path("conv.mcap.partial")
        with open(self.sample, "rb") as f:
            data = f.read()
        with open(part, "wb") as f:
            f.write(data[: len(data) // 2])
        rrd = self.path("part.rrd")
        proc = run("mcap_to_rrd.py", part, rrd, check=1)
        self.assertIn("incomplete", proc.stderr)
        run("mcap_to_rrd.py", part, rrd, "--allow-partial", check=0)
        run("check_rrd.py", rrd, "--entity", "/particles", check=0)

    def test_rerun_cli_mcap_convert(self):
        from check_rrd import rerun_cli

        exe = rerun_cli()
        self.assertIsNotNone(exe, "the rerun CLI from rerun-sdk is not installed")
        rrd = self.path("cli.rrd")
        proc = subprocess.run([exe, "mcap", "convert", self.sample, "-o", rrd], capture_output=True, text=True)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        proc = run(
            "check_rrd.py",
            rrd,
            "--json",
            "--entity", "/particles",
            "--entity", "/walls",
            "--entity", "/walls/drum/force",
            "--entity", "/scalars/kinetic_energy",
            "--component", "/particles=Points3D:positions",
            "--component", "/walls/drum/force=foxglove.Vector3:message",
            check=0,
        )
        rep = json.loads(proc.stdout)
        # What Rerun's importer drops (documented in README.md): no radii from a PointCloud.
        self.assertNotIn("Points3D:radii", rep["entities"]["/particles"]["components"])


if __name__ == "__main__":
    unittest.main()
