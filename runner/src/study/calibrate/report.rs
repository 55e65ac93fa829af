//! What `tilth calibrate` writes: the posterior samples, the calibrated model file and the
//! markdown summary.

use super::{CalibrateArgs, ConditionResult, Param, describe, params_text};
use crate::study::model_edit::in_bond_only;
use anyhow::{Context, Result, anyhow, bail};
use std::collections::{BTreeMap, BTreeSet};
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
/// varies (or a constant with one condition); everything else kept as written. Where the
/// calibrated conditions share a fixed value (`--where moisture_pct=6`, or one condition
/// only), the new value applies there only: it becomes the first case of a `cases` table
/// whose last case keeps the model's previous value for every other condition (see
/// [`only_where`]), so that calibrating one condition loses nothing written for the others.
pub fn write_model(
    from: &Path,
    to: &Path,
    params: &[Param],
    results: &[ConditionResult],
    test: Option<&str>,
) -> Result<()> {
    let text = std::fs::read_to_string(from)
        .with_context(|| format!("{}: cannot read", from.display()))?;
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", from.display()))?;
    let declared = declared_conditions(&doc);
    let varying: Vec<&String> = results
        .first()
        .map(|r| {
            r.conditions
                .keys()
                .filter(|k| results.iter().any(|o| o.conditions[*k] != r.conditions[*k]))
                .collect()
        })
        .unwrap_or_default();
    if let Some(k) = varying.iter().find(|k| !declared.contains(k.as_str())) {
        bail!(
            "calibrated values vary with {k}, which {} does not declare in `conditions`: a model value cannot depend on it; calibrate each {k} separately (--where {k}=...)",
            from.display()
        );
    }
    let fixed = declared_only(
        &doc,
        shared_conditions(results.iter().map(|r| &r.conditions)),
    );
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
        let value = only_where(&fixed, test, value, current(&doc, p));
        set(&mut doc, from, p, value, "tilth calibrate")?;
    }
    std::fs::write(to, doc.to_string()).with_context(|| format!("{}: cannot write", to.display()))
}

/// The conditions the model file declares (`conditions = { moisture_pct = [3, 12], ... }`).
/// A measurement's other columns, such as the shear box's `normal_pressure_pa`, are settings
/// of the test: an experiment does not evaluate the model at them, so a case naming them
/// would never match.
fn declared_conditions(doc: &toml_edit::DocumentMut) -> BTreeSet<String> {
    doc.get("conditions")
        .and_then(|c| c.as_table_like())
        .map(|t| t.iter().map(|(k, _)| k.to_string()).collect())
        .unwrap_or_default()
}

/// `conds` without the columns the model does not declare ([`declared_conditions`]).
fn declared_only(
    doc: &toml_edit::DocumentMut,
    mut conds: BTreeMap<String, f64>,
) -> BTreeMap<String, f64> {
    let declared = declared_conditions(doc);
    conds.retain(|k, _| declared.contains(k));
    conds
}

/// The conditions every one of `conds` has, with the same value in all.
pub fn shared_conditions<'a>(
    conds: impl IntoIterator<Item = &'a BTreeMap<String, f64>>,
) -> BTreeMap<String, f64> {
    let mut it = conds.into_iter();
    let Some(first) = it.next() else {
        return BTreeMap::new();
    };
    let mut shared = first.clone();
    for c in it {
        shared.retain(|k, v| c.get(k).is_some_and(|o| (o - *v).abs() < 1e-9));
    }
    shared
}

/// `value` where the conditions are `fixed`, the model's `previous` value elsewhere:
/// `{ cases = [ { when = fixed, value }, ...previous ] }`, the previous cases appended when
/// it was a `cases` table (the first match wins, so the new case overrides the old one at
/// its conditions), else one last case `{ when = {}, value = previous }` (an empty `when`
/// matches every condition). With no fixed condition, or nothing previous, `value` alone.
///
/// With `test` (`calibrate --per-test`), the new case names the test too
/// (`when = { test = "ucs", ... }`), so the value holds for that test's specimens only.
pub fn only_where(
    fixed: &BTreeMap<String, f64>,
    test: Option<&str>,
    value: toml_edit::Value,
    previous: Option<toml_edit::Value>,
) -> toml_edit::Value {
    let Some(previous) = previous.filter(|_| !fixed.is_empty() || test.is_some()) else {
        return value;
    };
    let case = |when: toml_edit::InlineTable, value: toml_edit::Value| {
        let mut c = toml_edit::InlineTable::new();
        c.insert("when", toml_edit::Value::InlineTable(when));
        c.insert("value", value);
        toml_edit::Value::InlineTable(c)
    };
    let mut when = toml_edit::InlineTable::new();
    if let Some(t) = test {
        when.insert("test", t.into());
    }
    for (k, v) in fixed {
        when.insert(k, (*v).into());
    }
    // An old case for exactly these conditions (an earlier calibration there) is replaced.
    let same_conditions = |c: &toml_edit::Value| {
        let Some(w) = c
            .as_inline_table()
            .and_then(|t| t.get("when"))
            .and_then(|w| w.as_inline_table())
        else {
            return false;
        };
        w.len() == fixed.len() + usize::from(test.is_some())
            && w.iter().all(|(k, v)| {
                if k == "test" {
                    return v.as_str() == test;
                }
                let v = v.as_float().or(v.as_integer().map(|i| i as f64));
                v.zip(fixed.get(k))
                    .is_some_and(|(a, b)| (a - b).abs() < 1e-9)
            })
    };
    let mut cases = toml_edit::Array::new();
    cases.push(case(when, value));
    let old_cases = previous
        .as_inline_table()
        .and_then(|t| t.get("cases"))
        .and_then(|c| c.as_array())
        .cloned();
    match old_cases {
        Some(old) => {
            for c in old.iter().filter(|c| !same_conditions(c)) {
                cases.push(c.clone());
            }
        }
        None => {
            let mut prev = previous;
            prev.decor_mut().clear();
            cases.push(case(toml_edit::InlineTable::new(), prev));
        }
    }
    for c in cases.iter_mut() {
        c.decor_mut().set_prefix(" ");
    }
    let mut t = toml_edit::InlineTable::new();
    t.insert("cases", toml_edit::Value::Array(cases));
    toml_edit::Value::InlineTable(t)
}

/// Where the model keeps `p`: `[pairs.PAIR]`, or `[bond.pairs.PAIR]` where only that has it.
fn home(doc: &toml_edit::DocumentMut, p: &Param) -> &'static [&'static str] {
    if in_bond_only(doc, &p.pair, &p.key) {
        &["bond", "pairs"]
    } else {
        &["pairs"]
    }
}

/// The model's value of `p` as written (see [`home`]).
fn current(doc: &toml_edit::DocumentMut, p: &Param) -> Option<toml_edit::Value> {
    let mut item = doc.as_item();
    for part in home(doc, p)
        .iter()
        .copied()
        .chain([p.pair.as_str(), p.key.as_str()])
    {
        item = item.get(part)?;
    }
    item.as_value().cloned()
}

/// The starting model with each parameter set to one value (a joint calibration), written
/// where the model has it (`[pairs.PAIR]`, else `[bond.pairs.PAIR]`); everything else kept.
/// Where every measurement fitted shares a condition (`--where moisture_pct=6`), the value
/// applies there only and the previous value stays for the rest ([`only_where`]).
pub fn write_constants(
    from: &Path,
    to: &Path,
    params: &[Param],
    values: &[f64],
    fixed: &BTreeMap<String, f64>,
) -> Result<()> {
    let text = std::fs::read_to_string(from)
        .with_context(|| format!("{}: cannot read", from.display()))?;
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", from.display()))?;
    let fixed = declared_only(&doc, fixed.clone());
    for (p, v) in params.iter().zip(values) {
        let value = only_where(
            &fixed,
            None,
            toml_edit::Value::from((v * 1e6).round() / 1e6),
            current(&doc, p),
        );
        set(&mut doc, from, p, value, "tilth calibrate --joint")?;
    }
    std::fs::write(to, doc.to_string()).with_context(|| format!("{}: cannot write", to.display()))
}

/// Sets `p` to `value` where the model keeps it ([`home`]).
fn set(
    doc: &mut toml_edit::DocumentMut,
    from: &Path,
    p: &Param,
    value: toml_edit::Value,
    by: &str,
) -> Result<()> {
    let path = home(doc, p);
    let mut table = doc.as_item_mut();
    for part in path.iter().copied().chain([p.pair.as_str()]) {
        table = &mut table[part];
    }
    let pair = table
        .as_table_like_mut()
        .ok_or_else(|| anyhow!("{}: no [{}.{}]", from.display(), path.join("."), p.pair))?;
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
    format!("tilth {}", crate::provenance::GIT_COMMIT)
}

pub fn markdown(args: &CalibrateArgs, params: &[Param], rows: &[ConditionResult]) -> String {
    let mut s = format!(
        "# Calibration of {} against {}\n\n{} free parameter(s): {}; {} seeds per surface setting, {} per check{}; tolerance {} %{}.\n\n",
        args.test,
        args.data.display(),
        params.len(),
        params_text(params),
        args.seeds,
        args.check_seeds.unwrap_or(args.seeds),
        match args.check_se {
            Some(pct) => format!(
                " (more, up to {}, until the mean's standard error is at most {pct} % of the measurement)",
                args.max_check_seeds
                    .unwrap_or(4 * args.check_seeds.unwrap_or(args.seeds))
            ),
            None => String::new(),
        },
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::model::evaluate;

    /// The written form as the model reader sees it, evaluated at `conds`.
    fn at(form: &toml_edit::Value, conds: &[(&str, f64)]) -> f64 {
        let t: toml::Table = format!("v = {form}").parse().unwrap();
        let c = conds.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        evaluate(&t["v"], &c).unwrap()
    }

    fn case_count(v: &toml_edit::Value) -> usize {
        v.as_inline_table().unwrap()["cases"]
            .as_array()
            .unwrap()
            .len()
    }

    fn fixed(conds: &[(&str, f64)]) -> BTreeMap<String, f64> {
        conds.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn shared_conditions_are_those_all_have_alike() {
        let a = fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 0.34)]);
        let b = fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 2.76)]);
        let c = fixed(&[("moisture_pct", 6.0)]);
        assert_eq!(
            shared_conditions([&a, &b, &c]),
            fixed(&[("moisture_pct", 6.0)])
        );
        assert!(shared_conditions([&a, &fixed(&[("moisture_pct", 9.0)])]).is_empty());
    }

    #[test]
    fn a_value_calibrated_at_one_condition_keeps_the_previous_one_elsewhere() {
        let previous: toml_edit::Value =
            "{ interpolate = \"moisture_pct\", x = [3, 12], y = [0.1, 0.4] }"
                .parse()
                .unwrap();
        let v = only_where(
            &fixed(&[("moisture_pct", 6.0)]),
            None,
            0.9.into(),
            Some(previous),
        );
        assert_eq!(at(&v, &[("moisture_pct", 6.0)]), 0.9);
        assert!((at(&v, &[("moisture_pct", 9.0)]) - 0.3).abs() < 1e-12);
        assert!((at(&v, &[("moisture_pct", 3.0)]) - 0.1).abs() < 1e-12);
        // No fixed condition: the new value replaces the old one everywhere.
        let all = only_where(&BTreeMap::new(), None, 0.9.into(), Some(1.0.into()));
        assert_eq!(at(&all, &[("moisture_pct", 9.0)]), 0.9);
    }

    #[test]
    fn a_cases_table_gets_the_new_case_first_and_keeps_its_own() {
        let previous: toml_edit::Value =
            "{ cases = [ { when = { moisture_pct = 6 }, value = 1.0 }, { when = { firmness_mpa = 1.55 }, value = 2.0 } ] }"
                .parse()
                .unwrap();
        let v = only_where(
            &fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]),
            None,
            5.0.into(),
            Some(previous),
        );
        assert_eq!(case_count(&v), 3);
        assert_eq!(
            at(&v, &[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]),
            5.0
        );
        assert_eq!(
            at(&v, &[("moisture_pct", 6.0), ("firmness_mpa", 0.34)]),
            1.0
        );
        assert_eq!(
            at(&v, &[("moisture_pct", 9.0), ("firmness_mpa", 1.55)]),
            2.0
        );
        // Calibrated there again: the earlier case is replaced, not shadowed.
        let again = only_where(
            &fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]),
            None,
            7.0.into(),
            Some(v),
        );
        assert_eq!(case_count(&again), 3);
        assert_eq!(
            at(&again, &[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]),
            7.0
        );
        assert_eq!(
            at(&again, &[("moisture_pct", 9.0), ("firmness_mpa", 1.55)]),
            2.0
        );
    }

    #[test]
    fn a_value_calibrated_per_test_holds_for_that_test_only() {
        use crate::lab::model::{At, evaluate_at};
        let in_test = |form: &toml_edit::Value, conds: &[(&str, f64)], test: &str| {
            let t: toml::Table = format!("v = {form}").parse().unwrap();
            let c = conds.iter().map(|(k, v)| (k.to_string(), *v)).collect();
            evaluate_at(&t["v"], At::test(&c, test)).unwrap()
        };
        let here = fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]);
        let v = only_where(&here, Some("ucs"), 4.0.into(), Some(1.0.into()));
        let c = [("moisture_pct", 6.0), ("firmness_mpa", 1.55)];
        assert_eq!(in_test(&v, &c, "ucs"), 4.0);
        assert_eq!(in_test(&v, &c, "direct_shear"), 1.0);
        assert_eq!(
            in_test(&v, &[("moisture_pct", 9.0), ("firmness_mpa", 1.55)], "ucs"),
            1.0
        );
        // The other test calibrated at the same conditions: both cases kept.
        let w = only_where(&here, Some("direct_shear"), 3.0.into(), Some(v));
        assert_eq!(in_test(&w, &c, "ucs"), 4.0);
        assert_eq!(in_test(&w, &c, "direct_shear"), 3.0);
        assert_eq!(case_count(&w), 3);
        // The same test again: its case is replaced.
        let again = only_where(&here, Some("ucs"), 5.0.into(), Some(w));
        assert_eq!(in_test(&again, &c, "ucs"), 5.0);
        assert_eq!(in_test(&again, &c, "direct_shear"), 3.0);
        assert_eq!(case_count(&again), 3);
    }

    /// The shear rows' `normal_pressure_pa` is a setting of the test, not a model condition:
    /// a written case that named it would never match in a run.
    #[test]
    fn a_written_case_names_only_the_models_own_conditions() {
        use crate::lab::model::{At, Model, evaluate_at};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let dir = std::env::temp_dir().join(format!("tilth-declared-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let to = dir.join("model.toml");
        let p = super::super::parse_param("soil-soil.friction=0.4:1.0").unwrap();
        let rows = fixed(&[
            ("moisture_pct", 6.0),
            ("firmness_mpa", 1.55),
            ("normal_pressure_pa", 1e5),
        ]);
        write_constants(&root.join("models/li2022.toml"), &to, &[p], &[0.55], &rows).unwrap();
        let model = Model::load(&to).unwrap();
        let form = &model.file.pairs["soil-soil"]["friction"];
        let here = fixed(&[("moisture_pct", 6.0), ("firmness_mpa", 1.55)]);
        assert_eq!(
            evaluate_at(form, At::test(&here, "direct_shear")).unwrap(),
            0.55
        );
        let elsewhere = fixed(&[("moisture_pct", 9.0), ("firmness_mpa", 1.55)]);
        assert_eq!(
            evaluate_at(form, At::test(&elsewhere, "direct_shear")).unwrap(),
            0.8
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
