//! What `tilth calibrate` writes: the posterior samples, the calibrated model file and the
//! markdown summary.

use super::calibrate::{CalibrateArgs, ConditionResult, Param, describe};
use anyhow::{Context, Result, anyhow, bail};
use std::path::Path;
use tilth_tools::calibrate::Posterior;

pub fn write_samples(path: &Path, params: &[Param], post: &Posterior) -> Result<()> {
    let mut text = params
        .iter()
        .map(|p| p.name.clone())
        .collect::<Vec<_>>()
        .join(",")
        + "\n";
    for s in &post.samples {
        text += &(s
            .iter()
            .map(|v| format!("{v}"))
            .collect::<Vec<_>>()
            .join(",")
            + "\n");
    }
    std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))
}

/// The starting model with each parameter replaced by a table over the single condition that
/// varies (or a constant with one condition); everything else kept as written.
pub fn write_model(
    from: &Path,
    to: &Path,
    params: &[Param],
    results: &[ConditionResult],
) -> Result<()> {
    let text = std::fs::read_to_string(from)
        .with_context(|| format!("{}: cannot read", from.display()))?;
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", from.display()))?;
    let varying: Vec<&String> = results
        .first()
        .map(|r| {
            r.conditions
                .keys()
                .filter(|k| results.iter().any(|o| o.conditions[*k] != r.conditions[*k]))
                .collect()
        })
        .unwrap_or_default();
    for (i, p) in params.iter().enumerate() {
        let value: toml_edit::Value = match varying.as_slice() {
            [] => results[0].calibrated[i].into(),
            [cond] => {
                let mut pts: Vec<(f64, f64)> = results
                    .iter()
                    .map(|r| (r.conditions[*cond], r.calibrated[i]))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut t = toml_edit::InlineTable::new();
                t.insert("interpolate", cond.as_str().into());
                t.insert(
                    "x",
                    toml_edit::Value::Array(pts.iter().map(|p| p.0).collect()),
                );
                t.insert(
                    "y",
                    toml_edit::Value::Array(
                        pts.iter().map(|p| (p.1 * 1e6).round() / 1e6).collect(),
                    ),
                );
                toml_edit::Value::InlineTable(t)
            }
            _ => bail!(
                "calibrated values vary over several conditions ({}); a model table needs one",
                varying
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        set(&mut doc, from, p, value, "tilth calibrate")?;
    }
    std::fs::write(to, doc.to_string()).with_context(|| format!("{}: cannot write", to.display()))
}

/// The starting model with each parameter set to one value (a joint calibration), written
/// where the model has it (`[pairs.PAIR]`, else `[bond.pairs.PAIR]`); everything else kept.
pub fn write_constants(from: &Path, to: &Path, params: &[Param], values: &[f64]) -> Result<()> {
    let text = std::fs::read_to_string(from)
        .with_context(|| format!("{}: cannot read", from.display()))?;
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", from.display()))?;
    for (p, v) in params.iter().zip(values) {
        set(
            &mut doc,
            from,
            p,
            toml_edit::Value::from((v * 1e6).round() / 1e6),
            "tilth calibrate --joint",
        )?;
    }
    std::fs::write(to, doc.to_string()).with_context(|| format!("{}: cannot write", to.display()))
}

/// Sets `p` to `value` in `[pairs.PAIR]` or, where only that has it, `[bond.pairs.PAIR]`.
fn set(
    doc: &mut toml_edit::DocumentMut,
    from: &Path,
    p: &Param,
    value: toml_edit::Value,
    by: &str,
) -> Result<()> {
    let in_pairs = doc
        .get("pairs")
        .and_then(|t| t.get(&p.pair))
        .and_then(|t| t.get(&p.key))
        .is_some();
    let in_bond = doc
        .get("bond")
        .and_then(|t| t.get("pairs"))
        .and_then(|t| t.get(&p.pair))
        .and_then(|t| t.get(&p.key))
        .is_some();
    let pair = if in_bond && !in_pairs {
        doc["bond"]["pairs"][&p.pair]
            .as_table_like_mut()
            .ok_or_else(|| anyhow!("{}: no [bond.pairs.{}]", from.display(), p.pair))?
    } else {
        doc["pairs"][&p.pair]
            .as_table_like_mut()
            .ok_or_else(|| anyhow!("{}: no [pairs.{}]", from.display(), p.pair))?
    };
    let mut item = toml_edit::value(value);
    if let Some(v) = item.as_value_mut() {
        v.decor_mut()
            .set_suffix(format!("  # calibrated by {by} ({})", chrono_free_note()));
    }
    pair.insert(&p.key, item);
    Ok(())
}

/// `name 95 % [low, high]` for each parameter of a posterior sample.
pub fn posterior_intervals(params: &[Param], post: &Posterior) -> String {
    params
        .iter()
        .enumerate()
        .map(|(i, p)| format!("{} 95 % [{:.4}, {:.4}]", p.name, post.q025[i], post.q975[i]))
        .collect::<Vec<_>>()
        .join(", ")
}

fn chrono_free_note() -> String {
    format!("tilth {}", crate::GIT_COMMIT)
}

pub fn markdown(args: &CalibrateArgs, params: &[Param], rows: &[ConditionResult]) -> String {
    let mut s = format!(
        "# Calibration of {} against {}\n\n{} free parameter(s): {}; {} seeds per surface setting, {} per check; tolerance {} %{}.\n\n",
        args.test,
        args.data.display(),
        params.len(),
        params
            .iter()
            .map(|p| format!("{}.{} in [{}, {}]", p.pair, p.key, p.low, p.high))
            .collect::<Vec<_>>()
            .join(", "),
        args.seeds,
        args.check_seeds.unwrap_or(args.seeds),
        args.tolerance,
        if args.coarse { "; coarse preset" } else { "" }
    );
    s += "| conditions | measured | start | calibrated | simulated (mean +- sd) | error +- s.e. | within | beyond scatter |\n|---|---|---|---|---|---|---|---|\n";
    let v = |x: &[f64]| {
        x.iter()
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.2} +- {:.2} (n={}) | {:+.2} +- {} % | {} | {} |\n",
            describe(&r.conditions),
            r.measured,
            v(&r.start),
            v(&r.calibrated),
            r.simulated_mean,
            r.simulated_sd.unwrap_or(f64::NAN),
            r.iterations.last().map_or(0, |i| i.values.len()),
            r.error_pct,
            r.error_se_pct.map_or("-".into(), |v| format!("{v:.2}")),
            if r.within_tolerance { "yes" } else { "NO" },
            if r.within_beyond_scatter { "yes" } else { "no" }
        );
    }
    s += &format!(
        "\nerror +- s.e.: the mean's relative error and its standard error (sd / sqrt(n) / measured); \
         \"beyond scatter\": |error| + 2 s.e. <= {} %, so that the scatter between seeds cannot have put \
         the mean inside the tolerance by chance.\n\n",
        args.tolerance
    );
    for r in rows {
        s += &format!("## {}\n\n", describe(&r.conditions));
        s += &format!(
            "- surface: {} runs ({} failed), quadratic R^2 {:.4}, residual sd {}\n- {}\n",
            r.surface_runs,
            r.surface_failed,
            r.r2,
            r.residual_sd.map_or("-".into(), |v| format!("{v:.3}")),
            r.ridge_statement
        );
        for (k, it) in r.iterations.iter().enumerate() {
            s += &format!(
                "- run {k}: setting ({}) predicted {:.2}, simulated {:.2} +- {:.2} ({:+.2} %)\n",
                v(&it.setting),
                it.predicted,
                it.mean,
                it.sd.unwrap_or(f64::NAN),
                it.error_pct
            );
        }
        let l = &r.linearised;
        if l.rank < params.len() {
            s += &format!(
                "- linearised: the measurement fixes {} of {} parameter combinations; the parameters trade off along ({}) without changing the fit\n",
                l.rank,
                params.len(),
                l.null_directions.first().map_or(String::new(), |d| v(d))
            );
        }
        for (i, p) in params.iter().enumerate() {
            if let Some((a, b)) = l.conditional_ci95[i] {
                s += &format!(
                    "- {} with the others held: 95 % interval [{a:.4}, {b:.4}]\n",
                    p.name
                );
            }
        }
        let post = &r.posterior;
        s += &format!(
            "- posterior (SMC, {} stages): {}{}\n\n",
            post.stages,
            posterior_intervals(params, post),
            if params.len() == 2 {
                format!(", correlation {:.2}", post.correlation[0][1])
            } else {
                String::new()
            }
        );
    }
    s
}
