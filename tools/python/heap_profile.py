#!/usr/bin/env python3
"""The top surface of a repose run's heap and overflow, from its MCAP's last particle frame.

    python tools/python/heap_profile.py RUN.mcap [--bin MM] [--out-to MM]

Prints, for rings of BIN mm around the tray's axis (default 2.5 mm, out to 80 mm), the
highest grain top in the ring relative to the tray's top, and how many grains the ring
holds. The tray's top comes from the run's `tilth.experiment` metadata (`tray_top_z_m`);
grains at or above the funnel outlet (`drop_height_m` above the tray) are left out. Used in
docs/li2022-compare.md, "The tray's stand", to see whether the overflow reached the rim.
Needs the packages of tools/python/requirements.txt.
"""
import argparse
import json

import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from check_mcap import NUMERIC_TYPES


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mcap")
    ap.add_argument("--bin", type=float, default=2.5, help="ring width, mm")
    ap.add_argument("--out-to", type=float, default=80.0, help="outermost radius, mm")
    a = ap.parse_args(argv)
    with open(a.mcap, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {}
        for m in reader.iter_metadata():
            if m.name == "tilth.experiment":
                meta = {k: json.loads(v) if v[:1] in "-0123456789" else v for k, v in m.metadata.items()}
        last = None
        for _, _, message, msg in reader.iter_decoded_messages(topics=["/particles"]):
            last = (message.log_time, msg)
    if last is None:
        raise SystemExit(f"{a.mcap}: no /particles messages")
    if "tray_top_z_m" not in meta:
        raise SystemExit(f"{a.mcap}: no tray_top_z_m in its tilth.experiment metadata (not a repose run?)")
    t, msg = last
    top_z = float(meta["tray_top_z_m"])
    ceiling = top_z + float(meta.get("drop_height_m", 1e9))
    fields = list(msg.fields)
    arr = np.frombuffer(msg.data, dtype=np.dtype({
        "names": [f.name for f in fields],
        "formats": [NUMERIC_TYPES[f.type][0] for f in fields],
        "offsets": [f.offset for f in fields],
        "itemsize": msg.point_stride,
    }))
    x, y, z, rad = (arr[k].astype(float) for k in ("x", "y", "z", "radius"))
    cx, cy = float(meta.get("tray_centre_x_m", 0.0)), float(meta.get("tray_centre_y_m", 0.0))
    r = np.hypot(x - cx, y - cy)
    print(f"{a.mcap}: t = {t / 1e9:.3f} s, {len(z)} grains; tray top at z = {top_z * 1e3:.1f} mm, "
          f"rim at r = {float(meta.get('tray_radius_m', float('nan'))) * 1e3:.1f} mm")
    edges = np.arange(0.0, a.out_to + 1e-9, a.bin) * 1e-3
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (r >= lo) & (r < hi) & (z < ceiling)
        top = f"{1e3 * ((z[m] + rad[m]).max() - top_z):7.1f} mm" if m.any() else "      -   "
        print(f"r {lo * 1e3:5.1f}-{hi * 1e3:5.1f} mm: top {top} from the tray's top, {int(m.sum()):6d} grains")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
