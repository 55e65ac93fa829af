//! `tilth compare --model M.toml --data D.csv --out DIR`: simulate every measured condition
//! and put simulated next to measured.
//!
//! Each measurement row (`test, conditions, observable, value, ...`; see
//! data/li2022/README.md) becomes a run of its test's experiment at its conditions, with
//! `--replicates` seeds so that the simulation's own scatter is known. The runs go through
//! the sweep runner (pinned cores, one MCAP each, resumable: run the command again and it
//! reuses what is done), one sweep per test in `DIR/<test>/`. Writes `DIR/compare.json`,
//! `compare.csv` and `compare.md`.

use super::lab_runs::{LabRunArgs, Simulate, simulate};
use super::measurements::{Measurement, read_measurements};
use super::measurements::{TESTS, check_against_model};
use crate::lab::model::Model;
use crate::sweep::execute;
use anyhow::{Result, anyhow, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use tilth_tools::compare as compare_stats;
use tilth_tools::compare::plot as compare_plot;
use tilth_tools::compare::{mean_sd, std_error};

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Model file (conditions -> parameters), e.g. models/li2022.toml.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV), e.g. data/li2022/measurements.csv.
    #[arg(long)]
    pub data: PathBuf,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Runs per measured condition, with different seeds.
    #[arg(long, default_value_t = 1)]
    pub replicates: usize,
    /// Seed of the first replicate: replicate r at a condition runs with a seed derived
    /// from first + r and the condition's values, so that different conditions are
    /// independent draws; a validation can take seeds no calibration run used.
    #[arg(long, default_value_t = 1)]
    pub first_seed: u64,
    /// Only these tests (comma-separated: repose, direct_shear, ucs, tilt).
    #[arg(long, value_delimiter = ',')]
    pub tests: Vec<String>,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

/// One line of the comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Compared {
    #[serde(flatten)]
    pub measurement: Measurement,
    /// Simulated values of the replicates that finished.
    pub simulated: Vec<f64>,
    pub simulated_mean: Option<f64>,
    /// Sample standard deviation over replicates (needs 2).
    pub simulated_scatter: Option<f64>,
    pub residual: Option<f64>,
    pub relative_error: Option<f64>,
    /// residual / sqrt(scatter^2 / replicates + uncertainty^2): the residual in standard
    /// errors of the difference, when either the simulation scatter or the measurement's
    /// uncertainty is known.
    pub z_score: Option<f64>,
    /// Why a replicate has no value.
    pub problems: Vec<String>,
}

pub fn compare(args: &CompareArgs) -> Result<String> {
    crate::study::summary(|out| compare_into(args, out))
}

/// [`compare`], writing its summary to `out`.
fn compare_into(args: &CompareArgs, out: &mut dyn Write) -> Result<()> {
    if args.replicates == 0 {
        bail!("--replicates 0 is out of range: allowed 1 or more");
    }
    if args.first_seed == 0
        || args
            .first_seed
            .checked_add(args.replicates as u64)
            .is_none()
    {
        bail!(
            "--first-seed {} is out of range: allowed 1 to {}",
            args.first_seed,
            u64::MAX - args.replicates as u64
        );
    }
    let set = args.lab.set.parse()?;
    let model = std::path::absolute(&args.model)?;
    if !model.exists() {
        bail!("{}: no such model file", args.model.display());
    }
    let rows = read_measurements(&args.data)?;
    check_against_model(&rows, &Model::load(&args.model)?, &args.data)?;
    let mut tests: Vec<String> = vec![];
    for m in &rows {
        if !tests.contains(&m.test) && (args.tests.is_empty() || args.tests.contains(&m.test)) {
            tests.push(m.test.clone());
        }
    }
    if let Some(t) = args.tests.iter().find(|t| !TESTS.contains(&t.as_str())) {
        bail!("--tests: `{t}` is unknown: allowed {}", TESTS.join(", "));
    }
    let stop = execute::stop_on_signals()?;
    let rows: Vec<Measurement> = rows
        .into_iter()
        .filter(|m| tests.contains(&m.test))
        .collect();
    let sims = simulate(
        &rows,
        &Simulate {
            model: &model,
            data: &args.data,
            out: &args.out,
            replicates: args.replicates,
            first_seed: args.first_seed,
            lab: &args.lab,
            set: &set,
        },
        &stop,
    )?;
    let compared: Vec<Compared> = rows
        .into_iter()
        .zip(sims)
        .map(|(m, (sims, problems))| summarize(m, sims, problems))
        .collect();
    write_outputs(args, &compared, out)
}

fn summarize(m: Measurement, sims: Vec<f64>, problems: Vec<String>) -> Compared {
    let (mean, scatter) = mean_sd(&sims);
    let mean = (!sims.is_empty()).then_some(mean);
    let residual = mean.map(|s| s - m.value);
    let se = std_error(scatter, sims.len(), m.uncertainty);
    Compared {
        relative_error: residual.map(|r| r / m.value),
        z_score: residual.zip(se).map(|(r, se)| r / se),
        measurement: m,
        simulated: sims,
        simulated_mean: mean,
        simulated_scatter: scatter,
        residual,
        problems,
    }
}

/// A compared row as the analysis sees it.
fn analysis_row(c: &Compared) -> compare_stats::Row {
    let m = &c.measurement;
    compare_stats::Row {
        test: m.test.clone(),
        observable: m.observable.clone(),
        unit: m.unit.clone(),
        conditions: m.conditions.clone(),
        measured: m.value,
        simulated: c.simulated_mean,
        std_error: std_error(c.simulated_scatter, c.simulated.len(), m.uncertainty),
    }
}

/// Per test and observable: simulated against measured, and the residual against every
/// condition that varies. One plot per observable, because a test's observables have units
/// of their own (the funnel's cone angle in degrees, its flow rate in g/s): on one pair of
/// axes the largest would flatten the rest, under a unit that is only the first one's.
/// Returns the file names written.
fn write_plots(dir: &Path, rows: &[compare_stats::Row]) -> Result<Vec<String>> {
    let mut names = vec![];
    let mut groups: Vec<(&str, &str)> = vec![];
    for r in rows {
        let key = (r.test.as_str(), r.observable.as_str());
        if !groups.contains(&key) {
            groups.push(key);
        }
    }
    for (test, observable) in groups {
        let mine: Vec<&compare_stats::Row> = rows
            .iter()
            .filter(|r| r.test == test && r.observable == observable)
            .collect();
        if mine.iter().all(|r| r.simulated.is_none()) {
            continue;
        }
        let name = format!("simulated-vs-measured-{test}-{observable}.svg");
        let svg = compare_plot::simulated_vs_measured_svg(&mine).map_err(|e| anyhow!(e))?;
        std::fs::write(dir.join(&name), svg)?;
        names.push(name);
        let mut varied: Vec<String> = super::measurements::conditions_of(test)
            .iter()
            .map(|c| c.to_string())
            .collect();
        varied.extend(
            mine.iter()
                .flat_map(|r| r.conditions.keys())
                .filter(|k| super::measurements::setting_of(k).is_some() && !varied.contains(k))
                .cloned()
                .collect::<std::collections::BTreeSet<_>>(),
        );
        for cond in &varied {
            let mut xs: Vec<f64> = mine
                .iter()
                .filter_map(|r| r.conditions.get(cond.as_str()).copied())
                .collect();
            xs.sort_by(f64::total_cmp);
            xs.dedup();
            if xs.len() < 2 {
                continue;
            }
            let name = format!("residual-{test}-{observable}-{cond}.svg");
            let svg = compare_plot::residuals_svg(&mine, cond).map_err(|e| anyhow!(e))?;
            std::fs::write(dir.join(&name), svg)?;
            names.push(name);
        }
    }
    Ok(names)
}

/// RMSE, mean relative error and row count of each observable over the rows that have a
/// simulated value: RMSE = sqrt(sum r^2 / n), mean relative error = sum |r / measured| / n.
fn error_per_observable(rows: &[Compared]) -> BTreeMap<String, serde_json::Value> {
    let mut per_observable: BTreeMap<String, (f64, f64, usize)> = BTreeMap::new();
    for r in rows {
        if let (Some(res), Some(rel)) = (r.residual, r.relative_error) {
            let e = per_observable
                .entry(r.measurement.observable.clone())
                .or_default();
            e.0 += res * res;
            e.1 += rel.abs();
            e.2 += 1;
        }
    }
    per_observable
        .iter()
        .map(|(k, (ss, rel, n))| {
            (
                k.clone(),
                serde_json::json!({ "rmse": (ss / *n as f64).sqrt(), "mean_relative_error": rel / *n as f64, "n": n }),
            )
        })
        .collect()
}

fn write_outputs(args: &CompareArgs, rows: &[Compared], out: &mut dyn Write) -> Result<()> {
    std::fs::create_dir_all(&args.out)?;
    let summary = error_per_observable(rows);
    let analysed: Vec<compare_stats::Row> = rows.iter().map(analysis_row).collect();
    let verdicts = compare_stats::analyse(&analysed);
    let words = compare_stats::summary(&analysed, &verdicts);
    let plots = write_plots(&args.out, &analysed)?;
    let measured: Vec<Measurement> = rows.iter().map(|r| r.measurement.clone()).collect();
    let shear_ucs = super::check::shear_ucs_pairs(&measured);
    let created = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    let json = serde_json::json!({
        "created": created,
        "model": args.model.display().to_string(),
        "data": args.data.display().to_string(),
        "coarse": args.lab.coarse,
        "set": args.lab.set.set,
        "replicates": args.replicates,
        "first_seed": args.first_seed,
        "rows": rows,
        "observables": summary,
        "verdicts": verdicts,
        "summary": words,
        "plots": plots,
        "shear_ucs": shear_ucs,
    });
    std::fs::write(
        args.out.join("compare.json"),
        serde_json::to_vec_pretty(&json)?,
    )?;
    let fmt =
        |x: Option<f64>, p: usize| x.map(|v| format!("{v:.p$}")).unwrap_or_else(|| "-".into());
    let mut md = String::from(
        "| test | moisture % | firmness MPa | observable | measured | simulated | scatter | error |\n|---|---|---|---|---|---|---|---|\n",
    );
    let settings = super::measurements::setting_columns(&measured);
    let mut csv = format!(
        "row,test,moisture_pct,firmness_mpa,normal_pressure_pa,{}observable,measured,simulated_mean,simulated_scatter,relative_error,problems\n",
        settings.iter().map(|k| format!("{k},")).collect::<String>()
    );
    for r in rows {
        let m = &r.measurement;
        let c = |k: &str| {
            m.conditions
                .get(k)
                .map(|v| format!("{v}"))
                .unwrap_or_default()
        };
        let test = std::iter::once(m.test.clone())
            .chain(
                settings
                    .iter()
                    .filter_map(|k| Some(format!("{k} = {}", m.conditions.get(k)?))),
            )
            .collect::<Vec<_>>()
            .join(", ");
        md += &format!(
            "| {} | {} | {} | {} | {} {} | {} | {} | {} |\n",
            test,
            c("moisture_pct"),
            c("firmness_mpa"),
            m.observable,
            m.value,
            m.unit,
            fmt(r.simulated_mean, 2),
            fmt(r.simulated_scatter, 2),
            r.relative_error
                .map(|e| format!("{:+.1} %", 100.0 * e))
                .unwrap_or_else(|| { r.problems.first().cloned().unwrap_or_else(|| "-".into()) })
        );
        csv += &format!(
            "{},{},{},{},{},{}{},{},{},{},{},{}\n",
            m.row,
            m.test,
            c("moisture_pct"),
            c("firmness_mpa"),
            c("normal_pressure_pa"),
            settings
                .iter()
                .map(|k| format!("{},", c(k)))
                .collect::<String>(),
            m.observable,
            m.value,
            fmt(r.simulated_mean, 4),
            fmt(r.simulated_scatter, 4),
            fmt(r.relative_error, 4),
            r.problems.join("; ").replace(',', ";")
        );
    }
    md += "\n";
    for (k, v) in &summary {
        md += &format!(
            "{k}: RMSE {:.3}, mean relative error {:.1} % over {} conditions\n",
            v["rmse"].as_f64().unwrap_or(f64::NAN),
            100.0 * v["mean_relative_error"].as_f64().unwrap_or(f64::NAN),
            v["n"]
        );
    }
    md += &format!("\n## Where the model fails\n\n{words}\n");
    let allowed = super::check::describe(&shear_ucs);
    if !allowed.is_empty() {
        md += &format!("\n## What the measurements allow\n\n{allowed}");
    }
    for p in &plots {
        md += &format!("![{p}]({p})\n");
    }
    std::fs::write(args.out.join("compare.md"), &md)?;
    std::fs::write(args.out.join("compare.csv"), csv)?;
    out.write_all(md.as_bytes())?;
    writeln!(
        out,
        "\nwritten: {}/compare.{{json,csv,md}}",
        args.out.display()
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{compare_stats, write_plots};
    use crate::study::lab_runs::condition_seed;
    use std::collections::BTreeMap;

    /// The funnel test's readings have units of their own: each gets its own plots, under
    /// its own name and unit, holding only its own rows.
    #[test]
    fn each_observable_of_a_test_gets_plots_of_its_own() {
        let row = |observable: &str, unit: &str, moisture: f64, measured: f64| compare_stats::Row {
            test: "repose".into(),
            observable: observable.into(),
            unit: unit.into(),
            conditions: at(moisture),
            measured,
            simulated: Some(measured * 1.1),
            std_error: Some(0.1),
        };
        let rows = vec![
            row("heap_cone_angle_deg", "deg", 3.0, 38.0),
            row("funnel_flow_rate_g_s", "g/s", 3.0, 480.0),
            row("heap_cone_angle_deg", "deg", 12.0, 43.0),
            row("funnel_flow_rate_g_s", "g/s", 12.0, 390.0),
        ];
        let dir = std::env::temp_dir().join(format!("tilth-compare-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let names = write_plots(&dir, &rows).unwrap();
        assert_eq!(
            names,
            [
                "simulated-vs-measured-repose-heap_cone_angle_deg.svg",
                "residual-repose-heap_cone_angle_deg-moisture_pct.svg",
                "simulated-vs-measured-repose-funnel_flow_rate_g_s.svg",
                "residual-repose-funnel_flow_rate_g_s-moisture_pct.svg",
            ]
        );
        let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
        let cone = read(&names[0]);
        assert!(
            cone.contains("measured heap_cone_angle_deg (deg)"),
            "{cone}"
        );
        assert!(
            !cone.contains("g/s"),
            "the cone angle's plot holds another reading"
        );
        let flow = read(&names[2]);
        assert!(
            flow.contains("measured funnel_flow_rate_g_s (g/s)"),
            "{flow}"
        );
        assert!(read(&names[3]).contains("simulated - measured (g/s)"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn at(moisture: f64) -> BTreeMap<String, f64> {
        BTreeMap::from([("moisture_pct".to_string(), moisture)])
    }

    #[test]
    fn a_condition_seed_depends_on_the_replicate_and_the_condition_only() {
        assert_eq!(condition_seed(3, &at(6.0)), condition_seed(3, &at(6.0)));
        assert_ne!(condition_seed(3, &at(6.0)), condition_seed(3, &at(9.0)));
        assert_ne!(condition_seed(3, &at(6.0)), condition_seed(4, &at(6.0)));
    }

    /// 16 replicates at 7 moisture levels: 112 different seeds, each a positive TOML
    /// integer below 2^31.
    #[test]
    fn condition_seeds_are_distinct_and_in_range() {
        let mut seen = std::collections::BTreeSet::new();
        for base in 1..=16u64 {
            for level in [3.0, 4.5, 6.0, 7.5, 9.0, 10.5, 12.0] {
                let s = condition_seed(base, &at(level));
                assert!((1..1u64 << 31).contains(&s), "{s}");
                seen.insert(s);
            }
        }
        assert_eq!(seen.len(), 112);
    }
}
