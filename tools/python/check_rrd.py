#!/usr/bin/env python3
"""Open a Rerun .rrd file and fail unless the given entity paths are in it.

    python3 tools/python/check_rrd.py run.rrd --entity /particles
    python3 tools/python/check_rrd.py run.rrd --entity /particles --component /particles=Points3D:radii \
        --entity /scalars/kinetic_energy --min-rows 10 [--json]

Reads the file with the rerun-sdk's own reader (rerun.chunk.RrdReader: every chunk of
the first recording store, or of --recording-id), prints every entity path it found with
its row count, timelines and component columns, and exits 1 if

  * the file cannot be read, or holds no recording;
  * an --entity is missing, or has fewer than --min-rows rows with data;
  * a --component ENTITY=COMPONENT (e.g. /particles=Points3D:positions) is missing.

Unless --no-verify, it first runs `rerun rrd verify FILE` (the CLI shipped in the
rerun-sdk wheel), which checks that this Rerun version can load every chunk.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from collections import OrderedDict

INTERNAL_COLUMNS = {"rerun.controls.RowId"}


def rerun_cli() -> str | None:
    """The `rerun` executable of this Python environment (or on PATH)."""
    try:
        import rerun_cli  # the package the rerun-sdk wheel installs the binary in

        exe = os.path.join(os.path.dirname(rerun_cli.__file__), "rerun")
        if os.path.exists(exe):
            return exe
    except ImportError:
        pass
    cand = os.path.join(os.path.dirname(sys.executable), "rerun")
    if os.path.exists(cand):
        return cand
    return shutil.which("rerun")


def scan(path: str, recording_id: str | None):
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    recordings = reader.recordings()
    if not recordings:
        raise RuntimeError("the file holds no recording store")
    store = None
    if recording_id is not None:
        matches = [s for s in recordings if s.recording_id == recording_id]
        if not matches:
            raise RuntimeError(
                f"no recording {recording_id!r}; found {[s.recording_id for s in recordings]}"
            )
        store = matches[0]
    else:
        store = recordings[0]

    entities: "OrderedDict[str, dict]" = OrderedDict()
    for chunk in reader.stream(store=store):
        e = entities.setdefault(
            chunk.entity_path, {"rows": 0, "static_rows": 0, "timelines": set(), "components": set()}
        )
        if chunk.is_static:
            e["static_rows"] += chunk.num_rows
        else:
            e["rows"] += chunk.num_rows
        e["timelines"].update(chunk.timeline_names)
        names = set(chunk.to_record_batch().schema.names)
        e["components"].update(names - INTERNAL_COLUMNS - set(chunk.timeline_names))
    info = {
        "application_id": store.application_id,
        "recording_id": store.recording_id,
        "recordings": len(recordings),
        "blueprints": len(reader.blueprints()),
    }
    return info, OrderedDict(sorted(entities.items()))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", metavar="FILE.rrd")
    ap.add_argument("--entity", action="append", default=[], help="entity path that must be present (repeatable)")
    ap.add_argument(
        "--component",
        action="append",
        default=[],
        metavar="ENTITY=COMPONENT",
        help="component column that must be present on an entity, e.g. /particles=Points3D:radii (repeatable)",
    )
    ap.add_argument("--min-rows", type=int, default=1, help="rows (temporal + static) each --entity needs (default 1)")
    ap.add_argument("--recording-id", help="check this recording store instead of the first one")
    ap.add_argument("--no-verify", action="store_true", help="skip `rerun rrd verify`")
    ap.add_argument("--json", action="store_true", help="print JSON instead of text")
    args = ap.parse_args(argv)

    problems = []
    if not os.path.isfile(args.file):
        print(f"FAIL {args.file}: no such file", file=sys.stderr)
        return 1

    verify = None
    if not args.no_verify:
        exe = rerun_cli()
        if exe is None:
            verify = "skipped: no rerun CLI found"
        else:
            proc = subprocess.run([exe, "rrd", "verify", args.file], capture_output=True, text=True)
            verify = "ok" if proc.returncode == 0 else f"failed (exit {proc.returncode})"
            if proc.returncode != 0:
                tail = (proc.stderr or proc.stdout).strip().splitlines()[-5:]
                problems.append("`rerun rrd verify` failed: " + " | ".join(tail))

    try:
        info, entities = scan(args.file, args.recording_id)
    except Exception as e:  # noqa: BLE001 - any read error fails the check
        print(f"FAIL {args.file}: cannot read the recording: {type(e).__name__}: {e}", file=sys.stderr)
        return 1

    for ent in args.entity:
        e = entities.get(ent)
        if e is None:
            problems.append(f"entity {ent} is missing")
        elif e["rows"] + e["static_rows"] < args.min_rows:
            problems.append(f"entity {ent} has {e['rows'] + e['static_rows']} rows, need >= {args.min_rows}")
    for spec in args.component:
        if "=" not in spec:
            problems.append(f"--component {spec!r} is not ENTITY=COMPONENT")
            continue
        ent, comp = spec.split("=", 1)
        e = entities.get(ent)
        if e is None:
            problems.append(f"entity {ent} is missing (wanted component {comp})")
        elif comp not in e["components"]:
            problems.append(f"entity {ent} has no component {comp} (has {sorted(e['components'])})")

    if args.json:
        out = {
            "file": args.file,
            "ok": not problems,
            "problems": problems,
            "verify": verify,
            **info,
            "entities": {
                k: {
                    "rows": v["rows"],
                    "static_rows": v["static_rows"],
                    "timelines": sorted(v["timelines"]),
                    "components": sorted(v["components"]),
                }
                for k, v in entities.items()
            },
        }
        json.dump(out, sys.stdout, indent=2)
        print()
    else:
        print(
            f"== {args.file}: application {info['application_id']!r}, recording {info['recording_id']!r} "
            f"({info['recordings']} recording(s), {info['blueprints']} blueprint(s)); rrd verify: {verify}"
        )
        w = max((len(k) for k in entities), default=0)
        for k, v in entities.items():
            rows = f"{v['rows']} rows" + (f" + {v['static_rows']} static" if v["static_rows"] else "")
            tl = ",".join(sorted(v["timelines"])) or "-"
            print(f"   {k:<{w}}  {rows:<18} timelines [{tl}]  {', '.join(sorted(v['components']))}")
    for p in problems:
        print(f"FAIL {args.file}: {p}", file=sys.stderr)
    if not args.json:
        total = len(args.entity) + len(args.component) + (1 if verify not in (None, "skipped: no rerun CLI found") else 0)
        print(f"{max(0, total - len(problems))} passed, {len(problems)} failed")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
