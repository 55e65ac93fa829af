#!/usr/bin/env python3
"""How `tilth fit`'s finite-difference step sets the quality of its estimates and standard
errors, by simulating the fit on a model whose truth is known.

    python3 tools/discovery/fit_steps.py [--draws N] [--seed S] [--info K] [--steps 0.05,0.1,0.25]

The model: 16 rows (readings at conditions), two free parameters in [0, 1] and [-0.5, 0.5],
each reading linear in them plus a mild square term (strength K: larger K, better-determined
parameters). Every run's value carries the grains' chaos (sd 2, independent between any two
runs, even of one seed at two settings: the chaotic extreme the discovery proof's per-seed
slopes show); each measured value is the mean of 4 truth runs plus injected noise (sd 1).

Each draw fits the data as `runner/src/study/fit/mod.rs` does: R = 4 seeds, start
(0.35, 0.0), Levenberg-Marquardt from lambda 1e-3 with the trust radius at a quarter of each
range, halved on a rejected step, a setting accepted only if its measured chi^2 is lower,
stopped at the noise (chi^2 <= dof and the predicted gain under chi^2_2's 95 % quantile),
3 iterations at most; the standard errors from (J'J)^-1 and, as the fit reports them, from
(J'J - N)^-1 (`jacobian_noise.rs`), both scaled by max(1, chi^2 / dof).

Printed per step size (a fraction of each range): each parameter's bias and RMSE against the
truth, the exact standard deviation (from the exact Jacobian at the truth), how often the
95 % interval (estimate +- 1.96 standard errors) holds the truth with either standard error
(the corrected one over the fits it determines), and how often it determines none.
docs/discovery-proof.md ("`fit`'s standard errors") gives the result.
"""
import argparse

import numpy as np

ROWS, R, CHAOS, NOISE = 16, 4, 2.0, 1.0
LOW, HIGH = np.array([0.0, -0.5]), np.array([1.0, 0.5])
TRUTH, START = np.array([0.5, 0.1]), np.array([0.35, 0.0])
# chi^2_2's 95 % quantile: -2 ln 0.05.
NOISE_GAIN = -2.0 * np.log(0.05)


def model(info):
    i = np.arange(ROWS)
    slope = np.stack([7 + 0.3 * i, 6 - 0.5 * i], 1) * info
    square = np.stack([-4 + 0.2 * i, 2 - 0.1 * i], 1)
    return lambda th: slope @ th + square @ (th**2), slope, square


def fit(y, mu, h_frac, rng):
    span = HIGH - LOW
    se = np.sqrt(CHAOS**2 / R + NOISE**2)
    dof = ROWS - 2
    theta, best = START.copy(), None
    lam, radius, last = 1e-3, 0.25, 0.25
    for it in range(4):
        centre = mu(theta)[:, None] + rng.normal(0, CHAOS, (ROWS, R))
        z = (y - centre.mean(1)) / se
        chi2 = z @ z
        if best is None or chi2 < best[1]:
            lam = max(lam / 3, 1e-6)
            if it == 3:
                best = (theta.copy(), chi2, z, best[3], best[4])
                break
            h = np.where(theta + h_frac * span <= HIGH, h_frac * span, -h_frac * span)
            slopes = []
            for j in range(2):
                t = theta.copy()
                t[j] += h[j]
                moved = mu(t)[:, None] + rng.normal(0, CHAOS, (ROWS, R))
                slopes.append((moved - centre) / h[j])
            jac = np.stack([g.mean(1) / se for g in slopes], 1)
            noise = np.array(
                [
                    [sum(np.cov(slopes[a][i], slopes[b][i])[0, 1] for i in range(ROWS)) / (R * se**2) for b in range(2)]
                    for a in range(2)
                ]
            )
            best = (theta.copy(), chi2, z, jac, noise)
            jtz = jac.T @ z
            gain = jtz @ np.linalg.solve(jac.T @ jac, jtz)
            if chi2 <= dof and gain < NOISE_GAIN:
                break
        else:
            lam *= 4
            radius = 0.5 * last
            if it == 3:
                break
        th, _, zb, jac, _ = best
        a = jac.T @ jac
        d = np.linalg.solve(a + lam * np.diag(np.diag(a)), jac.T @ zb)
        nxt = np.clip(th + np.clip(d, -radius * span, radius * span), LOW, HIGH)
        last = np.max(np.abs(nxt - th) / span)
        if np.all(np.abs(nxt - th) < 0.01 * span):
            break
        theta = nxt
    th, chi2, _, jac, noise = best
    scale = max(chi2 / dof, 1.0)
    a = jac.T @ jac
    naive = np.sqrt(np.diag(np.linalg.inv(a)) * scale)
    try:
        np.linalg.cholesky(a - noise)
        corrected = np.sqrt(np.diag(np.linalg.inv(a - noise)) * scale)
    except np.linalg.LinAlgError:
        corrected = np.full(2, np.inf)
    return th, naive, corrected


def covered(err, se):
    """How often the 95 % interval holds the truth, over the fits with a standard error."""
    ok = np.isfinite(se)
    return f"{np.mean(err[ok] < 1.96 * se[ok]):.2f}" if ok.any() else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--info", type=float, default=2.5)
    ap.add_argument("--steps", default="0.05,0.1,0.25,0.4")
    args = ap.parse_args()
    mu, slope, square = model(args.info)
    se_data = np.sqrt(NOISE**2 + CHAOS**2 / 4)
    se_fit = np.sqrt(CHAOS**2 / R + NOISE**2)
    exact = (slope + 2 * square * TRUTH) / np.sqrt(se_fit**2 + se_data**2 - NOISE**2)
    exact_sd = np.sqrt(np.diag(np.linalg.inv(exact.T @ exact)))
    print(f"{args.draws} draws, seed {args.seed}, info {args.info}; exact sd {exact_sd.round(4)}")
    print("| step | parameter | bias | RMSE | coverage, (J'J)^-1 | coverage, (J'J - N)^-1, of the fits it determines | not determined |")
    print("|---|---|---|---|---|---|---|")
    for h in [float(x) for x in args.steps.split(",")]:
        rng = np.random.default_rng(args.seed)
        est, naive, corrected = [], [], []
        for _ in range(args.draws):
            y = mu(TRUTH) + rng.normal(0, NOISE, ROWS) + rng.normal(0, CHAOS / 2, ROWS)
            th, n, c = fit(y, mu, h, rng)
            est.append(th)
            naive.append(n)
            corrected.append(c)
        est, naive, corrected = map(np.array, (est, naive, corrected))
        for j in range(2):
            err = np.abs(est[:, j] - TRUTH[j])
            print(
                f"| {h:g} | {j} | {est[:, j].mean() - TRUTH[j]:+.4f} | {np.sqrt((err**2).mean()):.4f} "
                f"| {np.mean(err < 1.96 * naive[:, j]):.2f} | {covered(err, corrected[:, j])} "
                f"| {np.mean(np.isinf(corrected[:, j])):.2f} |"
            )


if __name__ == "__main__":
    main()
