#!/usr/bin/env python3
"""Independent re-integration of the golden cases in plain Python (standard library).

* head-on cases (pp_headon_*, pw_headon_*): the project's force law written directly,
      F_n = 4/3 E* sqrt(R*) d^1.5 + 2 sqrt(5/6) |beta| sqrt(S_n m*) d_dot,  S_n = 2 E* sqrt(R* d)
* oblique cases (pw_oblique_*, pp_oblique_*): a line-by-line transcription of the
  LAMMPS 2021/2022 "tangential mindlin" algorithm (pair_granular.cpp / fix_wall_gran.cpp)
  with k_t = 8 G* a and eta_t = x_gamma_t * eta_n = 2 sqrt(5/6) |beta| sqrt(S_t m*).
Time integration = LAMMPS fix nve/sphere (velocity Verlet, forces evaluated with the
half-step velocities, I = 0.4 m R^2).
Compares with the CSV files in this directory and the *.final files in WORKDIR.
Usage: check_reference.py WORKDIR
"""
import csv
import math
import sys

from post import E_STAR, G_STAR, RADIUS, beta, read_final

RHO = 1380.0
DT = 1.0e-8
NSTEP = 40000
MASS = RHO * 4.0 / 3.0 * math.pi * RADIUS ** 3
INERTIA = 0.4 * MASS * RADIUS ** 2
XGT = math.sqrt(4.0 * G_STAR / E_STAR)  # x_gamma_t
KT = 8.0 * G_STAR                       # k_t = KT * a
MU = 0.3


def normal_force(d, ddot, rstar, mstar, b):
    if d <= 0.0:
        return 0.0
    s_n = 2.0 * E_STAR * math.sqrt(rstar * d)
    return 4.0 / 3.0 * E_STAR * math.sqrt(rstar) * d ** 1.5 \
        + 2.0 * math.sqrt(5.0 / 6.0) * b * math.sqrt(s_n * mstar) * ddot


def run_pp_headon(e):
    b = beta(e)
    x, v, f = -0.00105, 0.5, 0.0      # particle 1; particle 2 is the mirror image
    out = [(0.0, x, v, f)]
    for n in range(1, NSTEP + 1):
        v += 0.5 * DT * f / MASS
        x += DT * v
        f = -normal_force(2.0 * RADIUS + 2.0 * x, 2.0 * v, RADIUS / 2.0, MASS / 2.0, b)
        v += 0.5 * DT * f / MASS
        if n % 100 == 0:
            out.append((n * DT, x, v, f))
    return out, {"vx1_final": v}


def run_pw_headon(e):
    b = beta(e)
    z, v, f = 0.00105, -0.5, 0.0
    out = [(0.0, z, v, f)]
    for n in range(1, NSTEP + 1):
        v += 0.5 * DT * f / MASS
        z += DT * v
        f = normal_force(RADIUS - z, -v, RADIUS, MASS, b)
        v += 0.5 * DT * f / MASS
        if n % 100 == 0:
            out.append((n * DT, z, v, f))
    return out, {"vz_final": v}


# --- small 3-vector helpers -------------------------------------------------
def add(a, b): return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
def sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def scl(s, a): return [s * a[0], s * a[1], s * a[2]]
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def norm(a): return math.sqrt(dot(a, a))


def mindlin(hist, n, vtr, k, dampt, fscrit):
    """LAMMPS tangential mindlin: returns (new history, tangential force)."""
    rsht = dot(hist, n)
    if abs(rsht) * k > 1e-10 * fscrit:            # rotate history into the tangent plane
        shrmag = norm(hist)
        hist = sub(hist, scl(rsht, n))
        prjmag = norm(hist)
        hist = scl(shrmag / prjmag if prjmag > 0 else 0.0, hist)
    hist = add(hist, scl(DT, vtr))
    fs = sub(scl(-k, hist), scl(dampt, vtr))
    fsm = norm(fs)
    if fsm > fscrit:                                # Coulomb cap on spring + damping
        if norm(hist) != 0.0:
            hist = scl(-1.0 / k, add(scl(fscrit / fsm, fs), scl(dampt, vtr)))
            fs = scl(fscrit / fsm, fs)
        else:
            fs = [0.0, 0.0, 0.0]
    return hist, fs


def run_pw_oblique(e):
    alpha = math.sqrt(5.0) * beta(e)
    x, v, w = [0.0, 0.0, 0.00105], [0.3, 0.0, -0.5], [0.0, 0.0, 0.0]
    f, t, hist = [0.0] * 3, [0.0] * 3, [0.0] * 3
    row = lambda n: (n * DT, x[2], v[0], v[2], f[0], f[2], w[1])
    out = [row(0)]
    for step in range(1, NSTEP + 1):
        v = add(v, scl(0.5 * DT / MASS, f)); w = add(w, scl(0.5 * DT / INERTIA, t))
        x = add(x, scl(DT, v))
        f, t = [0.0] * 3, [0.0] * 3
        r = x[2]                                     # distance to the wall z = 0
        if r * r > RADIUS * RADIUS:
            hist = [0.0] * 3
        else:
            n = [0.0, 0.0, 1.0]
            d = RADIUS - r
            a = math.sqrt(RADIUS * d)                # R* = R for a flat wall, m* = m
            knfac = 4.0 / 3.0 * E_STAR * a
            eta_n = alpha * math.sqrt(MASS * knfac)
            vnnr = dot(v, n)
            fn = knfac * d - eta_n * vnnr
            vt = sub(v, scl(vnnr, n))
            vtr = add(vt, cross(n, scl(RADIUS, w)))
            hist, fs = mindlin(hist, n, vtr, KT * a, XGT * eta_n, MU * abs(fn))
            f = add(scl(fn, n), fs)
            t = scl(-RADIUS, cross(n, fs))           # LAMMPS wall: lever arm = R
        v = add(v, scl(0.5 * DT / MASS, f)); w = add(w, scl(0.5 * DT / INERTIA, t))
        if step % 100 == 0:
            out.append(row(step))
    return out, {"vx_final": v[0], "vz_final": v[2], "omegay_final": w[1]}


def run_pp_oblique(e):
    alpha = math.sqrt(5.0) * beta(e)
    x1, x2 = [-0.00105, 0.0, 0.0], [0.00105, 0.0, 0.0]
    v1, v2 = [0.5, 0.2, 0.0], [-0.5, -0.2, 0.0]
    w1, w2 = [0.0] * 3, [0.0] * 3
    f1, f2, t1, t2, hist = [0.0] * 3, [0.0] * 3, [0.0] * 3, [0.0] * 3, [0.0] * 3
    row = lambda n: (n * DT, x1[0], x1[1], v1[0], v1[1], f1[0], f1[1], w1[2],
                     x2[0], x2[1], v2[0], v2[1], w2[2])
    out = [row(0)]
    meff = MASS / 2.0
    for step in range(1, NSTEP + 1):
        v1 = add(v1, scl(0.5 * DT / MASS, f1)); v2 = add(v2, scl(0.5 * DT / MASS, f2))
        w1 = add(w1, scl(0.5 * DT / INERTIA, t1)); w2 = add(w2, scl(0.5 * DT / INERTIA, t2))
        x1 = add(x1, scl(DT, v1)); x2 = add(x2, scl(DT, v2))
        f1, f2, t1, t2 = [0.0] * 3, [0.0] * 3, [0.0] * 3, [0.0] * 3
        dl = sub(x1, x2)
        if dot(dl, dl) >= (2.0 * RADIUS) ** 2:
            hist = [0.0] * 3
        else:
            r = norm(dl)
            n = scl(1.0 / r, dl)                     # from particle 2 to particle 1
            d = 2.0 * RADIUS - r
            a = math.sqrt(RADIUS / 2.0 * d)          # R* = R/2
            knfac = 4.0 / 3.0 * E_STAR * a
            eta_n = alpha * math.sqrt(meff * knfac)
            vr = sub(v1, v2)
            vnnr = dot(vr, n)
            fn = knfac * d - eta_n * vnnr
            vt = sub(vr, scl(vnnr, n))
            wr = add(scl(RADIUS, w1), scl(RADIUS, w2))   # LAMMPS uses the full radii here
            vtr = add(vt, cross(n, wr))
            hist, fs = mindlin(hist, n, vtr, KT * a, XGT * eta_n, MU * abs(fn))
            f = add(scl(fn, n), fs)
            f1, f2 = f, scl(-1.0, f)
            tor = scl(-(RADIUS - 0.5 * d), cross(n, fs))  # lever arm R - delta/2
            t1, t2 = tor, tor
        v1 = add(v1, scl(0.5 * DT / MASS, f1)); v2 = add(v2, scl(0.5 * DT / MASS, f2))
        w1 = add(w1, scl(0.5 * DT / INERTIA, t1)); w2 = add(w2, scl(0.5 * DT / INERTIA, t2))
        if step % 100 == 0:
            out.append(row(step))
    fin = {"vx1_final": v1[0], "vy1_final": v1[1], "omegaz1_final": w1[2],
           "vx2_final": v2[0], "vy2_final": v2[1], "omegaz2_final": w2[2]}
    return out, fin


def compare(case, ref, fin, work):
    with open(f"{case}.csv") as fh:
        lines = list(csv.reader(fh))
    header, rows = lines[0], [[float(c) for c in r] for r in lines[1:]]
    ok = len(rows) == len(ref)
    worst = []
    for j, name in enumerate(header[1:], start=1):
        scale = max(abs(r[j]) for r in rows) or 1.0
        err = max(abs(a[j] - b[j]) for a, b in zip(ref, rows)) / scale
        worst.append(f"{name}:{err:.1e}")
        ok &= err < 1e-8
    d = read_final(f"{work}/{case}.final")
    for k, val in fin.items():
        scale = 0.5 if k.startswith("v") else 100.0
        ok &= abs(val - float(d[k])) / scale < 1e-9
    print(f"{case}: max rel. deviation of CSV columns {' '.join(worst)}; finals "
          + " ".join(f"{k}={val:.12g}(lmp {float(d[k]):.12g})" for k, val in fin.items())
          + (" -> OK" if ok else " -> MISMATCH"))
    return ok


def main():
    work = sys.argv[1]
    ok = True
    for e in ("0.2", "0.45", "0.9"):
        ok &= compare(f"pp_headon_e{e}", *run_pp_headon(float(e)), work)
        ok &= compare(f"pw_headon_e{e}", *run_pw_headon(float(e)), work)
    ok &= compare("pw_oblique_mu0.3_e0.45", *run_pw_oblique(0.45), work)
    ok &= compare("pp_oblique_mu0.3_e0.45", *run_pp_oblique(0.45), work)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
