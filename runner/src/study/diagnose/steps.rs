//! The free and held parameters' finite-difference steps, lengthened where the runs' chaos
//! hides a parameter's effect.
//!
//! A free parameter measured over a step too short for the runs' scatter has a slope that is
//! mostly noise. Least squares then shrinks its shift towards zero (errors in variables), the
//! misfit of a miscalibrated parameter is left in the residuals, and the candidate whose
//! signature is most like the parameter's takes the credit: with rolling friction 0.05 off
//! and no effect hidden, a 5 % step called a candidate significant in 8 seeds of 20, a 10 %
//! step in none (docs/discovery-proof.md, "A free parameter off"). So each parameter starts
//! at `--param-step` and, while noise is more than [`MOST_NOISE`] of its column's |x|^2,
//! its step is doubled and its variant run again, up to `--longest-param-step` of its range
//! (default 20 %): a longer step measures a secant, which a parameter off by a large share of its range needs
//! anyway, and which lets it absorb a candidate that mimics it (an honest outcome: such a
//! candidate cannot be told from the parameter on these readings).

use super::runs::{Simulations, Variant, param_variant, probe_variant, rerun_variant, usable_rows};
use super::sensitivity::Differences;
use super::{DiagnoseArgs, Inputs};
use crate::study::lab_runs::TestSetting;
use anyhow::Result;
use tilth_tools::diagnose::noise_share;

/// The most of a free parameter's measured |x|^2 that may be its estimate's noise: its shift
/// is then shrunk by at most about a tenth.
pub const MOST_NOISE: f64 = 0.1;

/// Lengthens each free parameter's step (variants 2.. in `variants`, runs in `sims`) while
/// its noise share is above [`MOST_NOISE`] and twice its step is within
/// `--longest-param-step`; returns each parameter's step as a fraction of its range. Each
/// held parameter's step (the last variants) is lengthened the same way, by the same
/// factor at most (`--longest-param-step` over `--param-step`): a probe measured as noise
/// loses to a candidate that mimics it (docs/discovery-proof.md, "A held parameter off").
pub(super) fn lengthen_steps(
    args: &DiagnoseArgs,
    set: &[TestSetting],
    inputs: &Inputs,
    variants: &mut [Variant],
    sims: &mut Simulations,
) -> Result<Vec<f64>> {
    let params = inputs.params.len();
    let first_probe = variants.len() - inputs.probes.len();
    // Column (variant index), step as the factor over its first, and the most it may reach.
    let most = args.longest_param_step / args.param_step;
    let mut factor = vec![1.0; params + inputs.probes.len()];
    let column = |c: usize| {
        if c < params {
            2 + c
        } else {
            first_probe + c - params
        }
    };
    loop {
        let used = usable_rows(args, &inputs.rows, sims)?.used;
        let fd = Differences {
            variants,
            sims,
            used: &used,
        };
        let short: Vec<(usize, f64)> = (0..factor.len())
            .map(|c| {
                (
                    c,
                    noise_share(&fd.sensitivity(column(c)), &fd.variance(column(c))),
                )
            })
            .filter(|&(c, share)| share > MOST_NOISE && 2.0 * factor[c] <= most + 1e-9)
            .collect();
        if short.is_empty() {
            return Ok(factor[..params]
                .iter()
                .map(|f| f * args.param_step)
                .collect());
        }
        for (c, share) in short {
            let v = column(c);
            factor[c] *= 2.0;
            let (what, from, to) = if c < params {
                let p = &inputs.params[c];
                variants[v] = param_variant(args, inputs, p, factor[c] * args.param_step)?;
                let pct = |f: f64| crate::sweep::plan::num(100.0 * f * args.param_step);
                (
                    format!("{}.{}", p.pair, p.key),
                    format!("{} % of its range", pct(factor[c] / 2.0)),
                    format!("{} %", pct(factor[c])),
                )
            } else {
                let (key, step) = &inputs.probes[c - params];
                variants[v] = probe_variant(args, inputs, key, factor[c] * step, true)?;
                let num = |f: f64| crate::sweep::plan::num(f * step);
                (format!("held {key}"), num(factor[c] / 2.0), num(factor[c]))
            };
            if !args.lab.quiet {
                eprintln!(
                    "diagnose: {what}'s slope over {from} is {:.0} % noise; measuring it over {to}",
                    100.0 * share
                );
            }
            rerun_variant(args, set, &inputs.rows, &variants[v], v, sims)?;
        }
    }
}
