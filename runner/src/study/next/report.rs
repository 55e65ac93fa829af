//! `next.md` and `conditions.csv`: the ranking in words and the best as a conditions file.

use super::{Criterion, NextArgs, Suggestion, Unscored};
use anyhow::Result;
use std::path::Path;
use tilth_tools::diagnose::discriminate::{Separation, worst};

/// The options as a conditions file: test, every condition any of them uses, observable.
pub(super) fn write_conditions(path: &Path, options: &[Suggestion]) -> Result<()> {
    let names: Vec<&String> = {
        let mut n: Vec<&String> = options.iter().flat_map(|o| o.conditions.keys()).collect();
        n.sort();
        n.dedup();
        n
    };
    let mut text = format!(
        "test,{},observable\n",
        names
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join(",")
    );
    for o in options {
        for obs in &o.observables {
            let cells: Vec<String> = names
                .iter()
                .map(|n| {
                    o.conditions
                        .get(*n)
                        .map_or(String::new(), |v| v.to_string())
                })
                .collect();
            text += &format!("{},{},{obs}\n", o.test, cells.join(","));
        }
    }
    std::fs::write(path, text)?;
    Ok(())
}

/// "NAME VALUE, ..." of a measurement's conditions.
pub(super) fn conditions_text(conditions: &std::collections::BTreeMap<String, f64>) -> String {
    conditions
        .iter()
        .map(|(c, v)| format!("{c} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// "NAME VALUE, ..." with `digits` decimals: each rival's strength or weight.
fn named(rivals: &[String], values: &[f64], digits: usize) -> String {
    rivals
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} {v:.digits$}"))
        .collect::<Vec<_>>()
        .join(", ")
}

pub(super) fn report(
    args: &NextArgs,
    (rivals, strengths, weights, mode): (&[String], &[f64], &[f64], &str),
    now: Option<&Separation>,
    (options, unscored): (&[Suggestion], &[Unscored]),
) -> String {
    let mut md = format!(
        "# The next measurement: telling {} apart\n\n{} The power is that test's at the diagnosis's alpha. {} specimen{} per measurement; the lab's noise {}.\n\n",
        rivals.join(", "),
        if mode == "fitted" {
            format!(
                "Each rival as the diagnosis fitted it on simulations ({}). The score of a measurement is the noncentrality of the test that would reject the wrong rival on it alone, sum (mu_a - mu_b)^2 / (lab^2 + s_b^2 / R) over its readings, for the pair hardest to tell apart, less what the runs' scatter brings to it; the rival is not refitted to the new readings, so this is an upper bound.",
                named(rivals, strengths, 4)
            )
        } else {
            format!(
                "Each rival at its estimated strength ({}). The score of a measurement is the noncentrality of the test that would reject the wrong rival, for the pair hardest to tell apart once it is added, less what the finite differences' noise brings.",
                named(rivals, strengths, 4)
            )
        },
        args.specimens,
        if args.specimens == 1 { "" } else { "s" },
        if args.noise.is_empty() {
            "taken as the runs' own scatter".to_string()
        } else {
            args.noise.clone()
        }
    );
    md += &match args.criterion {
        Criterion::ExpectedPower => format!(
            "Ranked by the expected power: each rival's weight, its chance of being the truth on the data so far (from its fit's misfit, Box and Hill 1967; {}), times the power against its hardest rival, summed.\n\n",
            named(rivals, weights, 3)
        ),
        Criterion::Maximin => {
            "Ranked by the hardest pair's separation (T-optimal).\n\n".to_string()
        }
    };
    if let Some(w) = now {
        md += &format!(
            "Now: {} against {} is the hardest pair, separation {:.2} (power {:.2}).\n\n",
            w.truth,
            w.rival,
            w.noncentrality - w.noise,
            w.power
        );
    }
    md += "| rank | test | conditions | readings | expected power | separation | power | hardest pair | runs |\n|---|---|---|---|---|---|---|---|---|\n";
    for (k, o) in options.iter().enumerate() {
        let w = worst(&o.pairs).expect("pairs");
        md += &format!(
            "| {} | {} | {} | {} | {:.3} | {:.2} | {:.2} | {} vs {} | {} |\n",
            k + 1,
            o.test,
            conditions_text(&o.conditions),
            o.observables.len(),
            o.expected_power,
            o.separation,
            o.power,
            w.truth,
            w.rival,
            o.runs
        );
    }
    let best = &options[0];
    md += &format!(
        "\nMeasure **{} at {}** next: `conditions.csv` holds it. Add the measurements to the data and diagnose again.",
        best.test,
        conditions_text(&best.conditions)
    );
    let chance = match args.criterion {
        Criterion::ExpectedPower => best.expected_power,
        Criterion::Maximin => best.power,
    };
    if chance < 0.5 {
        md += " Even this one is more likely than not to leave them ambiguous: measure it with more specimens, or several of the list.";
    }
    md += "\n";
    if !unscored.is_empty() {
        md += "\nNot ranked, as their readings are missing (a measurement on which one rival's runs fail and another's do not may still tell them apart, but not by this score):\n\n";
        for u in unscored {
            md += &format!("- {}\n", u.describe());
        }
    }
    md
}
