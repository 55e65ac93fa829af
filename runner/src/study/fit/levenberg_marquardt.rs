//! Levenberg-Marquardt on simulations: each iteration runs one setting; when it improves
//! on the best so far, the finite-difference Jacobian there; then steps from the best
//! setting. The module docs of `fit` say why each choice.

use super::jacobian_noise::jacobian_noise;
use super::params::show;
use super::rmse;
use super::simulations::{Evaluated, Problem, Sims, at, residuals};
use super::stop::{Stop, at_noise, noise_gain, predicted_gain};
use crate::study::lab_runs::{Simulate, prefetch};
use anyhow::{Result, anyhow, bail};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::collections::BTreeMap;

/// One iteration's record.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    pub iteration: usize,
    pub theta: Vec<f64>,
    pub chi2: f64,
    pub rmse: BTreeMap<String, f64>,
    /// Whether this setting improved on the best before it.
    pub accepted: bool,
    /// For an accepted setting whose Jacobian was run: the chi^2 the Gauss-Newton step from
    /// it is predicted to remove, z'J (J'J)^-1 J'z (`stop.rs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_gain: Option<f64>,
}

/// How far each parameter is moved for the finite-difference Jacobian, as a fraction of its
/// range: as far as a step may go (the trust radius starts at a quarter of each range), so
/// the secant describes the readings over the region a step can reach.
///
/// Not less: the grains' chaos decorrelates the runs of one seed after any change, so each
/// slope carries noise of variance 2 s^2 / (R h^2), s the runs' scatter. At 5 % of the range
/// that noise was larger than the slopes themselves on the discovery proof's draws, so J'J
/// was mostly noise: steps came out short, the estimates stayed near their start, and the
/// standard errors were 2-6x too small (docs/discovery-proof.md, "`fit`'s standard errors"). A
/// simulation of this fit on a model of two parameters
/// whose truth is known (`tools/discovery/fit_steps.py`, 400 draws each): with 5 % steps
/// the estimates fall short of the truth by up to 1.6 of their exact standard deviations
/// and the 95 % interval holds it in 5-77 % of the draws; with 25 %, the bias is under 0.25
/// of them and the interval holds it in 85-95 % of the draws with (J'J)^-1, 95-97 % with
/// the Jacobian's noise taken off.
const JACOBIAN_STEP: f64 = 0.25;

/// The best setting so far.
pub(super) struct Best {
    pub(super) theta: Vec<f64>,
    pub(super) chi2: f64,
    /// The rows' simulated means and their standard errors.
    pub(super) centre: Vec<f64>,
    pub(super) se: Vec<f64>,
    /// The degrees of freedom of each se^2 (the fit's misfit test allows for them).
    pub(super) dof: Vec<f64>,
    /// The Jacobian (standardised by `se`) and the noise it carries into J'J
    /// (`jacobian_noise.rs`).
    pub(super) jac: DMatrix<f64>,
    pub(super) noise: DMatrix<f64>,
}

impl Best {
    fn at(
        theta: &[f64],
        chi2: f64,
        (centre, se, dof): (Vec<f64>, Vec<f64>, Vec<f64>),
        (jac, noise): (DMatrix<f64>, DMatrix<f64>),
    ) -> Best {
        Best {
            theta: theta.to_vec(),
            chi2,
            centre,
            se,
            dof,
            jac,
            noise,
        }
    }
}

/// What the fit ends with.
pub(super) struct Fitted {
    /// The best setting (at least iteration 0's).
    pub(super) best: Best,
    pub(super) history: Vec<Step>,
    pub(super) stopped: Stop,
}

/// What Levenberg-Marquardt carries from one iteration to the next.
struct State {
    /// The setting the next iteration runs.
    theta: Vec<f64>,
    best: Option<Best>,
    /// The damping: divided by 3 after an accepted setting, multiplied by 4 after a rejected
    /// one.
    lambda: f64,
    /// The trust radius: a step moves each parameter by at most this fraction of its range.
    radius: f64,
    /// The last step, as a fraction of each range (its largest component).
    last_step: f64,
    history: Vec<Step>,
}

/// A step from the best setting.
struct Proposal {
    /// The setting it leads to, within the bounds.
    next: Vec<f64>,
    /// Whether every parameter moves by under 1 % of its range (converged).
    small: bool,
    /// Its largest component as a fraction of that parameter's range.
    last_step: f64,
}

/// Fits the free parameters: iterations 0..=`--iterations`, each running one setting (and,
/// when it is the best so far and a step follows, the P settings of the Jacobian), until
/// the fit is at the noise, converges, or runs out of iterations. `dof` = rows - P (at
/// least 1).
pub(super) fn levenberg_marquardt(p: &Problem, dof: usize) -> Result<Fitted> {
    let mut state = State {
        theta: p.params.iter().map(|p| p.start).collect(),
        best: None,
        lambda: 1e-3,
        radius: 0.25,
        last_step: 0.25f64,
        history: vec![],
    };
    let mut stopped = Stop::Iterations;
    for it in 0..=p.args.iterations {
        if let Some(why) = state.iteration(p, it, dof)? {
            stopped = why;
            break;
        }
    }
    Ok(Fitted {
        best: state.best.expect("iteration 0 ran"),
        history: state.history,
        stopped,
    })
}

impl State {
    /// Iteration `it`: runs `theta`; if it improves on the best, it becomes the best and its
    /// Jacobian is run; if not, the damping is raised and the trust radius halved. Then the
    /// step from the best setting gives the next `theta`. Some(why) when the fit stops here.
    fn iteration(&mut self, p: &Problem, it: usize, dof: usize) -> Result<Option<Stop>> {
        let (args, n) = (p.args, p.params.len());
        if !args.lab.quiet {
            eprintln!(
                "fit: iteration {it} of {}: {}",
                args.iterations,
                show(p.params, &self.theta)
            );
        }
        let Evaluated {
            centre,
            se,
            z,
            dof: row_dof,
            chi2,
            seeds: centre_seeds,
        } = p.evaluate(it, &self.theta)?;
        let accepted = self.best.as_ref().is_none_or(|b| chi2 < b.chi2);
        self.history.push(Step {
            iteration: it,
            theta: self.theta.clone(),
            chi2,
            rmse: rmse(p.rows, &centre),
            accepted,
            predicted_gain: None,
        });
        if accepted {
            self.lambda = (self.lambda / 3.0f64).max(1e-6);
            if it == args.iterations {
                // No step follows: the standard errors use the last Jacobian, one step
                // back (not worth P more settings of runs).
                let (jac, noise) = self
                    .best
                    .take()
                    .map(|b| (b.jac, b.noise))
                    .unwrap_or_else(|| (DMatrix::zeros(p.rows.len(), n), DMatrix::zeros(n, n)));
                let rows = (centre, se, row_dof);
                self.best = Some(Best::at(&self.theta, chi2, rows, (jac, noise)));
                return Ok(Some(Stop::Iterations));
            }
            let (jac, noise) = jacobian(p, it, &self.theta, &centre, &se, &centre_seeds)?;
            let gain = predicted_gain(&jac, &z);
            self.history
                .last_mut()
                .expect("pushed above")
                .predicted_gain = gain;
            let rows = (centre, se, row_dof);
            self.best = Some(Best::at(&self.theta, chi2, rows, (jac, noise)));
            if at_noise(chi2, dof, gain, n) && !args.to_minimum {
                if !args.lab.quiet {
                    eprintln!(
                        "fit: at the noise (chi^2 {chi2:.2} <= {dof} degrees of freedom; the next step's predicted gain {} < {:.2}, chi^2_{n}'s 95 % quantile); --to-minimum steps on",
                        gain.map_or("-".into(), |g| format!("{g:.2}")),
                        noise_gain(n)
                    );
                }
                return Ok(Some(Stop::AtNoise));
            }
        } else {
            self.lambda *= 4.0;
            // Back to the best setting, with a step half as long as the one that failed
            // (raising lambda alone hardly shortens a step that was small to begin with).
            self.radius = 0.5 * self.last_step;
            if it == args.iterations {
                return Ok(Some(Stop::Iterations));
            }
        }
        let best = self.best.as_ref().unwrap();
        let Proposal {
            next,
            small,
            last_step,
        } = propose(p, it, best, self.lambda, self.radius)?;
        self.last_step = last_step;
        if small {
            if !args.lab.quiet {
                eprintln!("fit: converged (every step under 1 % of its range)");
            }
            return Ok(Some(Stop::Converged));
        }
        self.theta = next;
        Ok(None)
    }
}

/// The Jacobian at the accepted setting `theta` of iteration `it`, standardised by its
/// standard errors, J_ij = (mean_i(theta + h_j e_j) - centre_i) / h_j / se_i, and the noise
/// it carries into J'J (`jacobian_noise.rs`). Parameter j moves by h_j = `JACOBIAN_STEP` of
/// its range (backwards at its upper bound); the P moved settings are simulated in turn. A
/// moved setting whose runs fail (a funnel that jams with more adhesion) is run the other
/// way instead, then half as far either way, while in range: a backward or shorter
/// difference is as good a slope, if noisier.
fn jacobian(
    p: &Problem,
    it: usize,
    theta: &[f64],
    centre: &[f64],
    se: &[f64],
    centre_seeds: &[Vec<f64>],
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let (rows, n) = (p.rows, p.params.len());
    let mut steps: Vec<f64> = p
        .params
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let h0 = JACOBIAN_STEP * (p.high - p.low);
            if theta[j] + h0 <= p.high { h0 } else { -h0 }
        })
        .collect();
    let moved = |j: usize, h: f64, name: &str| {
        let mut t = theta.to_vec();
        t[j] += h;
        p.setting(it, name, &t)
    };
    let moved_settings = (0..n)
        .map(|j| moved(j, steps[j], &format!("param-{j}")))
        .collect::<Result<Vec<_>>>()?;
    // With --slurm the P moved settings go into one job array.
    let hows: Vec<Simulate> = moved_settings
        .iter()
        .map(|(path, out)| at(path, out, p.args, p.set))
        .collect();
    prefetch(rows, &hows)?;
    let mut jac = DMatrix::zeros(rows.len(), n);
    let mut moved_seeds = Vec::with_capacity(n);
    for (j, param) in p.params.iter().enumerate() {
        let (path, out) = &moved_settings[j];
        let mut sims = p.run_at(path, out)?;
        let failed_row = |s: &Sims| s.mean.iter().position(|m| m.is_none());
        // Failed runs: the other way, then half as far either way, while in range.
        let h = steps[j];
        let (low, high) = (p.params[j].low, p.params[j].high);
        for (k, retry) in [-h, 0.5 * h, -0.5 * h].into_iter().enumerate() {
            if failed_row(&sims).is_none() {
                break;
            }
            if (low..=high).contains(&(theta[j] + retry)) {
                steps[j] = retry;
                let (path, out) = moved(j, retry, &format!("param-{j}-retry-{k}"))?;
                sims = p.run_at(&path, &out)?;
            }
        }
        if let Some(i) = failed_row(&sims) {
            bail!(
                "iteration {it}: the runs with {} moved failed at row {}",
                param.label,
                rows[i].row
            );
        }
        for i in 0..rows.len() {
            jac[(i, j)] = (sims.mean[i].expect("checked above") - centre[i]) / steps[j] / se[i];
        }
        moved_seeds.push(sims.seeds);
    }
    let noise = jacobian_noise(centre_seeds, &moved_seeds, &steps, se);
    Ok((jac, noise))
}

/// The Levenberg-Marquardt step from the best setting (Marquardt 1963): d solves
///
///   (J'J + lambda diag(J'J)) d = J'z,
///
/// z the best setting's standardised residuals (measured - simulated, so that theta + d
/// moves the simulations towards the measurements) and each diagonal term at least 1e-12, so that a parameter that moves no reading leaves
/// the system solvable. Each component is then limited to `radius` of its parameter's
/// range, and the setting it leads to kept within the bounds.
fn propose(p: &Problem, it: usize, best: &Best, lambda: f64, radius: f64) -> Result<Proposal> {
    let n = p.params.len();
    let (b_theta, jac) = (&best.theta, &best.jac);
    let b_z = residuals(p.rows, &best.centre, &best.se);
    let jtj = jac.transpose() * jac;
    let jtz = jac.transpose() * DVector::from_vec(b_z);
    let mut a = jtj.clone();
    for k in 0..n {
        a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
    }
    let d = a
        .lu()
        .solve(&jtz)
        .ok_or_else(|| anyhow!("iteration {it}: the fit's normal equations are singular"))?;
    let mut next = b_theta.clone();
    let mut small = true;
    let mut last_step = 0.0f64;
    for (k, p) in p.params.iter().enumerate() {
        let span = p.high - p.low;
        let step = d[k].clamp(-radius * span, radius * span);
        next[k] = (b_theta[k] + step).clamp(p.low, p.high);
        small &= (next[k] - b_theta[k]).abs() < 0.01 * span;
        last_step = last_step.max((next[k] - b_theta[k]).abs() / span);
    }
    Ok(Proposal {
        next,
        small,
        last_step,
    })
}
