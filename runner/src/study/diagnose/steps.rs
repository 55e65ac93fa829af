//! The free parameters' finite-difference steps, lengthened where the runs' chaos hides a
//! parameter's effect.
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

use super::runs::{Simulations, Variant, param_variant, rerun_variant, usable_rows};
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
/// `--longest-param-step`; returns each parameter's step as a fraction of its range.
pub(super) fn lengthen_steps(
    args: &DiagnoseArgs,
    set: &[TestSetting],
    inputs: &Inputs,
    variants: &mut [Variant],
    sims: &mut Simulations,
) -> Result<Vec<f64>> {
    let mut fraction = vec![args.param_step; inputs.params.len()];
    loop {
        let used = usable_rows(args, &inputs.rows, sims)?.used;
        let fd = Differences {
            variants,
            sims,
            used: &used,
        };
        let short: Vec<(usize, f64)> = (0..fraction.len())
            .map(|c| (c, noise_share(&fd.sensitivity(2 + c), &fd.variance(2 + c))))
            .filter(|&(c, share)| {
                share > MOST_NOISE && 2.0 * fraction[c] <= args.longest_param_step + 1e-12
            })
            .collect();
        if short.is_empty() {
            return Ok(fraction);
        }
        for (c, share) in short {
            let p = &inputs.params[c];
            if !args.lab.quiet {
                eprintln!(
                    "diagnose: {}.{}'s slope over {} % of its range is {:.0} % noise; measuring it over {} %",
                    p.pair,
                    p.key,
                    crate::sweep::plan::num(100.0 * fraction[c]),
                    100.0 * share,
                    crate::sweep::plan::num(200.0 * fraction[c])
                );
            }
            fraction[c] *= 2.0;
            variants[2 + c] = param_variant(args, inputs, p, fraction[c])?;
            rerun_variant(args, set, &inputs.rows, &variants[2 + c], 2 + c, sims)?;
        }
    }
}
