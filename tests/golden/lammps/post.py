#!/usr/bin/env python3
"""Helpers for the LAMMPS golden data (see README.md).

  post.py tsuji-arg E          -> argument to pass to LAMMPS "damping tsuji" so that the
                                  damping prefactor equals alpha = sqrt(5)*|beta(E)|
  post.py summary WORKDIR      -> writes summary.csv (case,quantity,value) to stdout from
                                  the *.final / *.raw files left in WORKDIR by regen.sh
"""
import math
import sys

# material / geometry (must match the .lammps inputs)
E_YOUNG = 13.5e6
NU = 0.2
RADIUS = 1.0e-3
E_STAR = E_YOUNG / (2.0 * (1.0 - NU * NU))          # 1/E* = 2(1-nu^2)/E
G_STAR = E_YOUNG / (4.0 * (2.0 - NU) * (1.0 + NU))  # 1/G* = 2*2(2-nu)(1+nu)/E


def beta(e):
    """|beta| = -ln e / sqrt(ln^2 e + pi^2)"""
    le = math.log(e)
    return -le / math.sqrt(le * le + math.pi * math.pi)


def tsuji_poly(c):
    """LAMMPS 2021/2022 'damping tsuji' conversion (pair_granular.cpp / fix_wall_gran.cpp)."""
    return (1.2728 - 4.2783 * c + 11.087 * c ** 2 - 22.348 * c ** 3
            + 27.467 * c ** 4 - 18.022 * c ** 5 + 4.8218 * c ** 6)


def tsuji_arg(e):
    """c in [0,1] with tsuji_poly(c) = sqrt(5)*|beta(e)| (polynomial is decreasing on [0,1])."""
    target = math.sqrt(5.0) * beta(e)
    if not (tsuji_poly(1.0) < target < tsuji_poly(0.0)):
        raise SystemExit(f"e={e}: alpha={target} outside the range of the Tsuji polynomial")
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if tsuji_poly(mid) > target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def read_final(path):
    d = {}
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if len(parts) == 2:
                d[parts[0]] = parts[1]
    return d


def fmt(v):
    return "%.15g" % v


def summary(work):
    rows = []

    def add(case, q, v):
        rows.append((case, q, v if isinstance(v, str) else fmt(v)))

    for e in ("0.2", "0.45", "0.9"):
        case = f"pp_headon_e{e}"
        d = read_final(f"{work}/{case}.final")
        v1, v2 = float(d["vx1_final"]), float(d["vx2_final"])
        add(case, "e_requested", e)
        add(case, "tsuji_arg", d["tsuji_arg"])
        add(case, "vx1_final", v1)
        add(case, "vx2_final", v2)
        add(case, "restitution", (v2 - v1) / (0.5 - (-0.5)))
    for e in ("0.2", "0.45", "0.9"):
        case = f"pw_headon_e{e}"
        d = read_final(f"{work}/{case}.final")
        vz = float(d["vz_final"])
        add(case, "e_requested", e)
        add(case, "tsuji_arg", d["tsuji_arg"])
        add(case, "vz_final", vz)
        add(case, "restitution", vz / 0.5)

    case = "pw_oblique_mu0.3_e0.45"
    d = read_final(f"{work}/{case}.final")
    add(case, "e_requested", "0.45")
    add(case, "tsuji_arg", d["tsuji_arg"])
    for k in ("vx_final", "vy_final", "vz_final", "omegax_final", "omegay_final", "omegaz_final"):
        add(case, k, float(d[k]))
    add(case, "restitution_normal", float(d["vz_final"]) / 0.5)

    case = "pp_oblique_mu0.3_e0.45"
    d = read_final(f"{work}/{case}.final")
    add(case, "e_requested", "0.45")
    add(case, "tsuji_arg", d["tsuji_arg"])
    for p in ("1", "2"):
        for k in ("vx", "vy", "vz", "omegax", "omegay", "omegaz"):
            add(case, f"{k}{p}_final", float(d[f"{k}{p}_final"]))
    add(case, "restitution_x", (float(d["vx2_final"]) - float(d["vx1_final"])) / 1.0)

    for case in ("pp_jkr_pulloff", "pp_jkr_pulloff_e0.9"):
        d = read_final(f"{work}/{case}.final")
        gamma = float(d["gamma"])
        rstar = RADIUS / 2.0
        data = []
        with open(f"{work}/{case}.raw") as fh:
            next(fh)
            for line in fh:
                ov, fn = line.split()
                data.append((float(ov), float(fn)))
        imin = min(range(len(data)), key=lambda k: data[k][1])
        last = max(k for k, r in enumerate(data) if r[1] != 0.0)
        if last + 1 >= len(data):
            raise SystemExit(f"{case}: contact did not break inside the fine window")
        # LAMMPS break criterion (pair_granular.cpp, JKR): a_c = (9 pi gamma R*^2/(4 E*))^(1/3)
        a_c = (9.0 * math.pi * gamma * rstar ** 2 / (4.0 * E_STAR)) ** (1.0 / 3.0)
        delta_po = a_c * a_c / rstar - 2.0 * math.sqrt(math.pi * gamma * a_c / E_STAR)
        add(case, "gamma", d["gamma"])
        add(case, "damping", f"{d['dmodel']} {d['damp']}")
        add(case, "min_force_n", data[imin][1])
        add(case, "overlap_at_min_force", data[imin][0])
        add(case, "break_overlap_last_contact", data[last][0])
        add(case, "break_overlap_first_free", data[last + 1][0])
        add(case, "min_force_over_pi_gamma_Rstar", data[imin][1] / (math.pi * gamma * rstar))
        add(case, "analytic_pulloff_3pi_gamma_Rstar", 3.0 * math.pi * gamma * rstar)
        add(case, "analytic_break_overlap", delta_po)

    out = sys.stdout
    out.write("case,quantity,value\n")
    for r in rows:
        out.write(",".join(r) + "\n")


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "tsuji-arg":
        print(repr(tsuji_arg(float(sys.argv[2]))))
    elif len(sys.argv) == 3 and sys.argv[1] == "summary":
        summary(sys.argv[2])
    else:
        raise SystemExit(__doc__)


if __name__ == "__main__":
    main()
