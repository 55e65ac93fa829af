#!/usr/bin/env python3
"""Measurements of the funnel repose test made by LAMMPS, for the discovery loop (README.md).

    tests/golden/lammps-funnel/regen.py [--replicates 4] [--jobs 2]
    tests/golden/lammps-funnel/regen.py --scale study --cases base --levels 6   # the study's 2 mm

For each case (`base`: the model of models/li2022.toml as LAMMPS writes it; `twisting`: the
same with LAMMPS's `twisting marshall`, an effect the model lacks) and each moisture level it
runs funnel.lammps REPLICATES times from different random packings, reduces every run to the
lab's four readings with the definitions of runner/src/lab/repose/mod.rs, discharge.rs and
runner/src/lab/observe.rs, and writes <case>.csv (the measurement file `tilth diagnose`
reads) and <case>-runs.csv (every run's readings). Needs `lmp` (Debian package lammps,
20220106) and Python 3.11 (tomllib); LMP=/path/to/lmp overrides.
"""
import argparse
import concurrent.futures as cf
import csv
import math
import os
import random
import statistics
import subprocess
import tempfile
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODEL = HERE.parents[2] / "models" / "li2022.toml"
LEVELS = [3.0, 6.0, 9.0, 12.0]
CASES = {"base": "twisting none", "twisting": "twisting marshall"}

# The funnel test's rig (runner/src/lab/repose/funnel.rs with the experiment's defaults), m.
TRAY_R, TRAY_H, DROP = 0.0618 / 2, 0.020, 0.060
R_OUT, R_IN, FUNNEL_H = 0.020, 0.0675, 0.140
HALF = max(R_IN, 0.15) + 0.05
GRAVITY = 9.81


class Scale:
    """A preset of the lab's funnel test: grain diameter D (m), soil poured MASS_G (g), how it
    comes in (all at once, the coarse preset's fill; or at RATE grains/s, the study's factory,
    by LAMMPS's `fix pour`), and the tray's stand (m; the tray and its stand are one closed
    cylinder on the floor)."""

    def __init__(self, name, d, mass_g, rate, stand):
        self.name, self.D, self.MASS_G, self.RATE = name, d, mass_g, rate
        self.Z_TRAY = stand + TRAY_H
        self.Z_OUT = self.Z_TRAY + DROP
        self.Z_TOP = self.Z_OUT + FUNNEL_H
        # The fill: the funnel's upper 40 %, one diameter inside its wall and top.
        self.Z_FILL = self.Z_OUT + 0.6 * FUNNEL_H
        self.R_FILL = R_OUT + (R_IN - R_OUT) * 0.6 - d
        self.FILL_H = self.Z_TOP - self.Z_FILL - d


# The lab's presets (runner/src/lab/repose/mod.rs): coarse on the floor, the study's on a stand.
SCALES = {"coarse": Scale("coarse", 0.004, 40.0, None, 0.0), "study": Scale("study", 0.002, 200.0, 20000.0, 0.1)}
HEAP_SPEED = 0.05  # observe::HEAP_SPEED
DT_FRACTION = 0.35  # sweeps/experiments/repose.toml
MAX_TIME = 8.0
ROLLING_DAMPING = 0.3  # epsd's default eta_r (`tilth laws`)
# Instrument resolution added to each reading's standard error, the noise floor the
# synthetic proof injects (tools/discovery/setup.sh, NOISE): deg, g, fraction, g.
FLOOR = {"heap_cone_angle_deg": 0.5, "tray_mass_g": 0.5, "funnel_flow_rate_g_s": 0.02, "funnel_residue_g": 0.05}
UNITS = {"heap_cone_angle_deg": "deg", "tray_mass_g": "g", "funnel_flow_rate_g_s": "g/s", "funnel_residue_g": "g"}


def at(value, moisture):
    """A model parameter at `moisture`: a number or {interpolate, x, y} (linear)."""
    if not isinstance(value, dict):
        return float(value)
    xs, ys = value["x"], value["y"]
    if moisture <= xs[0]:
        return ys[0]
    for (x0, y0), (x1, y1) in zip(zip(xs, ys), zip(xs[1:], ys[1:])):
        if moisture <= x1:
            return y0 + (y1 - y0) * (moisture - x0) / (x1 - x0)
    return ys[-1]


def tsuji_arg(e):
    """c with LAMMPS's Tsuji polynomial P(c) = sqrt(5)|beta(e)|: tilth's restitution damping
    (../lammps/README.md, "Normal damping")."""
    le = math.log(e)
    target = math.sqrt(5.0) * -le / math.sqrt(le * le + math.pi ** 2)
    poly = lambda c: 1.2728 - 4.2783 * c + 11.087 * c**2 - 22.348 * c**3 + 27.467 * c**4 - 18.022 * c**5 + 4.8218 * c**6
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if poly(mid) > target else (lo, mid)
    return 0.5 * (lo + hi)


def moduli(a, b):
    """E* and G* of a contact between materials a and b (Pa)."""
    e_star = 1.0 / sum((1 - m["poisson_ratio"] ** 2) / m["youngs_modulus"] for m in (a, b))
    g_star = 1.0 / sum(2 * (2 - m["poisson_ratio"]) * (1 + m["poisson_ratio"]) / m["youngs_modulus"] for m in (a, b))
    return e_star, g_star


def rolling_sds(mu_r, e_star, r_star, gamma, mass, radius):
    """LAMMPS `rolling sds k g mu` for tilth's `epsd` (Ai et al. 2011 type C): the same cap
    mu_r R* F_n; the spring k_r = 2.25 S_n mu_r^2 R*^2 (N m/rad) is k R*^2 in SDS, with S_n
    = 2 E* a at a typical contact (JKR at zero load when adhesive, else Hertz under one grain's
    weight), since SDS's stiffness is constant; the dashpot eta_r 2 sqrt(I_r k_r) likewise."""
    if gamma > 0:
        a = (9 * math.pi * gamma * r_star**2 / e_star) ** (1 / 3)
    else:
        a = (3 * mass * 9.81 * r_star / (4 * e_star)) ** (1 / 3)
    k = 2.25 * 2 * e_star * a * mu_r**2
    inertia = 1.4 * mass * radius**2  # I + m d^2 of one sphere about its contact point
    i_r = inertia / 2 if r_star < radius else inertia
    g = ROLLING_DAMPING * 2 * math.sqrt(i_r * k * r_star**2) / r_star**2
    return k, g, mu_r


def parameters(model, moisture, twist, d):
    soil, steel = model["materials"]["soil"], model["materials"]["steel"]
    ss, sw = model["pairs"]["soil-soil"], model["pairs"]["soil-steel"]
    if at(sw["surface_energy"], moisture) != 0.0:
        raise SystemExit("soil-steel surface_energy must be 0: the walls here are hertz/material")
    radius = d / 2
    mass = soil["density"] * math.pi / 6 * d**3
    gamma = at(ss["surface_energy"], moisture)
    e_ss, g_ss = moduli(soil, soil)
    e_sw, g_sw = moduli(soil, steel)
    kr, gr, mur = rolling_sds(at(ss["rolling_friction"], moisture), e_ss, radius / 2, gamma, mass, radius)
    krw, grw, murw = rolling_sds(at(sw["rolling_friction"], moisture), e_sw, radius, 0.0, mass, radius)
    nuw = 0.2
    return {
        "E": soil["youngs_modulus"], "nu": soil["poisson_ratio"], "gamma": gamma,
        "damp": tsuji_arg(at(ss["restitution"], moisture)), "xgt": math.sqrt(4 * g_ss / e_ss),
        "mu": at(ss["friction"], moisture), "kr": kr, "gr": gr, "mur": mur,
        "Ew": 2 * (1 - nuw) * e_sw, "nuw": nuw, "ktw": 8 * g_sw,
        "dampw": tsuji_arg(at(sw["restitution"], moisture)), "xgtw": math.sqrt(4 * g_sw / e_sw),
        "muw": at(sw["friction"], moisture), "krw": krw, "grw": grw, "murw": murw,
        "twist": twist,
    }, mass


def packing(path, seed, mass, scale):
    """The pour's grains at random, apart, in the funnel's fill cylinder, moving down at 0.2
    m/s as the lab's factory makes them; none when `fix pour` makes them (scale.RATE)."""
    D = scale.D
    count = 0 if scale.RATE else round(scale.MASS_G * 1e-3 / mass)
    rng = random.Random(seed)
    placed = []
    while len(placed) < count:
        r = scale.R_FILL * math.sqrt(rng.random())
        phi = 2 * math.pi * rng.random()
        p = (r * math.cos(phi), r * math.sin(phi), scale.Z_FILL + D / 2 + (scale.FILL_H - D) * rng.random())
        if all((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2 >= D * D for q in placed):
            placed.append(p)
    density = mass / (math.pi / 6 * D**3)
    with open(path, "w") as f:
        f.write(f"tilth funnel pour, seed {seed}\n\n{count} atoms\n1 atom types\n\n")
        f.write(f"{-HALF} {HALF} xlo xhi\n{-HALF} {HALF} ylo yhi\n-0.005 {scale.Z_TOP + 0.05} zlo zhi\n\nAtoms # sphere\n\n")
        for k, p in enumerate(placed, 1):
            f.write(f"{k} 1 {D} {density!r} {p[0]!r} {p[1]!r} {p[2]!r}\n")
        f.write("\nVelocities\n\n")
        for k in range(1, count + 1):
            f.write(f"{k} 0 0 -0.2 0 0 0\n")


def crossing(samples, level):
    """discharge.rs: when the passed fraction first reached `level`, interpolated."""
    for k, (t, f) in enumerate(samples):
        if f >= level:
            if k == 0:
                return t
            t0, f0 = samples[k - 1]
            return t0 + (t - t0) * (level - f0) / (f - f0)
    return None


def reduce(out, scale):
    """The four readings of one run; the flow rate is None when the funnel held back more
    than a fifth of the soil (no t80)."""
    rows = []
    with open(f"{out}.final.dump") as f:
        lines = f.read().splitlines()
    start = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS")) + 1
    for line in lines[start:]:
        _, x, y, z, vx, vy, vz, r, m = map(float, line.split())
        rows.append((x, y, z, math.sqrt(vx * vx + vy * vy + vz * vz), r, m))
    top, tray = 0.0, 0.0
    for x, y, z, v, r, m in rows:
        if math.hypot(x, y) <= TRAY_R and scale.Z_TRAY < z < scale.Z_OUT and v < HEAP_SPEED:
            top = max(top, z + r - scale.Z_TRAY)
            tray += m
    samples = []
    with open(f"{out}.flow") as f:
        for line in f:
            if not line.startswith("#"):
                t, below = map(float, line.split())
                samples.append((t, below * 1e3 / scale.MASS_G))
    t20, t80 = crossing(samples, 0.2), crossing(samples, 0.8)
    return {
        "heap_cone_angle_deg": math.degrees(math.atan(top / TRAY_R)),
        "tray_mass_g": tray * 1e3,
        "funnel_flow_rate_g_s": 0.6 * scale.MASS_G / (t80 - t20) if t80 is not None else None,
        "funnel_residue_g": sum(m for _, _, z, _, _, m in rows if z > scale.Z_OUT) * 1e3,
    }


def pour_vars(scale, mass, density, seed, dt):
    """fix pour's arguments for the lab's factory: `count` grains at scale.RATE a second. fix
    pour inserts a burst every time a grain takes to fall through the fill (from rest at -0.2
    m/s under gravity, fix_pour.cpp), of vol * V_fill / V_grain grains; vol is chosen so the
    bursts average the factory's rate. Also returns when the last burst comes in (s)."""
    d, count = scale.D, round(scale.MASS_G * 1e-3 / mass)
    fall = (0.2 - math.sqrt(0.04 + 2 * GRAVITY * scale.FILL_H)) / -GRAVITY
    nfreq = int(fall / dt + 0.5)
    per_burst = round(scale.RATE * nfreq * dt)
    volume, grain = math.pi * scale.R_FILL**2 * scale.FILL_H, math.pi / 6 * d**3
    bursts = math.ceil(count / per_burst)
    return {"pour": count, "seed": 1000 + seed, "rfill": scale.R_FILL, "zfill0": scale.Z_FILL,
            "zfill1": scale.Z_FILL + scale.FILL_H + d, "d": d, "rho": density,
            "vol": (per_burst + 0.5) * grain / volume}, (bursts - 1) * nfreq * dt


def run_one(job):
    case, moisture, seed, model, lmp, work, scale = job
    params, mass = parameters(model, moisture, CASES[case], scale.D)
    tag = f"{case}-{moisture:g}-{seed}"
    data, out = f"{work}/{tag}.data", f"{work}/{tag}"
    packing(data, seed, mass, scale)
    # The lab's step: DT_FRACTION of the Rayleigh time pi R sqrt(rho/G) / (0.1631 nu + 0.8766).
    soil = model["materials"]["soil"]
    shear = soil["youngs_modulus"] / (2 * (1 + soil["poisson_ratio"]))
    dt = DT_FRACTION * math.pi * scale.D / 2 * math.sqrt(soil["density"] / shear) / (0.1631 * soil["poisson_ratio"] + 0.8766)
    poured = 0.0
    if scale.RATE:
        extra, poured = pour_vars(scale, mass, soil["density"], seed, dt)
        params.update(extra)
    args = [lmp, "-in", str(HERE / "funnel.lammps"), "-log", "none", "-screen", f"{out}.screen",
            "-var", "data", data, "-var", "out", out, "-var", "dt", repr(dt),
            "-var", "sample", str(round(1e-3 / dt)), "-var", "check", str(round(0.02 / dt)),
            "-var", "steps", str(round(MAX_TIME / dt)), "-var", "skin", repr(0.6 * scale.D),
            "-var", "ztray", repr(scale.Z_TRAY), "-var", "zout", repr(scale.Z_OUT), "-var", "ztop", repr(scale.Z_TOP),
            "-var", "tmin", repr(poured + 0.3)]
    for key, value in params.items():
        args += ["-var", key, value if isinstance(value, str) else repr(value)]
    done = subprocess.run(args, cwd=work, capture_output=True, text=True)
    if done.returncode != 0:
        tail = Path(f"{out}.screen").read_text().splitlines()[-15:] if Path(f"{out}.screen").exists() else []
        raise SystemExit(f"LAMMPS failed on {tag}:\n" + "\n".join(tail) + done.stderr)
    readings = reduce(out, scale)
    with open(f"{out}.screen") as f:
        last = [l for l in f.read().splitlines() if l.strip() and l.split()[0].isdigit()][-1].split()
    readings["simulated_s"] = float(last[1])
    return case, moisture, seed, readings


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--scale", choices=list(SCALES), default="coarse",
                    help="coarse: 40 g of 4 mm, all at once; study: 200 g of 2 mm at 20,000/s (files study-*.csv)")
    ap.add_argument("--levels", default=",".join(f"{m:g}" for m in LEVELS), help="moisture levels, %%")
    ap.add_argument("--keep", help="keep LAMMPS's files in this directory")
    args = ap.parse_args()
    scale, levels = SCALES[args.scale], [float(m) for m in args.levels.split(",")]
    prefix = "" if scale.name == "coarse" else f"{scale.name}-"
    model = tomllib.loads(MODEL.read_text())
    lmp = os.environ.get("LMP", "lmp")
    version = subprocess.run([lmp, "-h"], capture_output=True, text=True).stdout.splitlines()
    version = next((l.strip() for l in version if "Large-scale" in l), "LAMMPS")
    cases = args.cases.split(",")
    with tempfile.TemporaryDirectory() as temp:
        work = args.keep or temp
        os.makedirs(work, exist_ok=True)
        jobs = [(c, m, s, model, lmp, work, scale) for c in cases for m in levels for s in range(1, args.replicates + 1)]
        with cf.ProcessPoolExecutor(args.jobs) as pool:
            results = list(pool.map(run_one, jobs))
    for case in cases:
        mine = [r for r in results if r[0] == case]
        with open(HERE / f"{prefix}{case}-runs.csv", "w", newline="") as f:
            w = csv.writer(f)
            keys = list(UNITS) + ["simulated_s"]
            w.writerow(["moisture_pct", "seed"] + keys)
            for _, m, s, rd in mine:
                w.writerow([f"{m:g}", s] + ["" if rd[k] is None else f"{rd[k]:.6g}" for k in keys])
        with open(HERE / f"{prefix}{case}.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["test", "moisture_pct", "firmness_mpa", "normal_pressure_pa", "observable", "value", "unit", "uncertainty", "replicates", "source"])
            for m in levels:
                for key, unit in UNITS.items():
                    xs = [rd[key] for _, mm, _, rd in mine if mm == m and rd[key] is not None]
                    if len(xs) < 2:
                        continue  # the flow rate of a funnel that held the soil back
                    floor = FLOOR[key] * (statistics.fmean(xs) if key == "funnel_flow_rate_g_s" else 1.0)
                    se = math.sqrt(statistics.variance(xs) / len(xs) + floor**2)
                    w.writerow(["repose", f"{m:g}", "", "", key, f"{statistics.fmean(xs):.6g}", unit, f"{se:.4g}", len(xs),
                                f"LAMMPS ({version}), tests/golden/lammps-funnel/funnel.lammps, case {case}, {scale.name}"])
        print(f"wrote {prefix}{case}.csv and {prefix}{case}-runs.csv")


if __name__ == "__main__":
    main()
