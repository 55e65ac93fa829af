//! `tilth report PROJECT_DIR`: every `tilth compare` run under a project directory as a
//! history, one HTML page that works offline (`PROJECT_DIR/report.html`).
//!
//! The compare runs are found by their `compare.json` (up to four levels down) and ordered by
//! when they were made (`created`, else the file's modification time). The page has: the runs
//! (model, data, replicates), the error of every observable with one column per run, the RMSE
//! history of every observable as a chart, each run's summary in words, and each plot of the
//! runs side by side, oldest first, so that the effect of a model change is seen at a glance;
//! and the story of the discovery loop: each compare, verdict, suggested measurement and
//! fit with its model diff, in order (`project_story`).
//! Plots are inlined (SVG); nothing is fetched.

use super::project_story::{Step, StepKind, find_steps, story_html};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::compare::plot::history_svg;

#[derive(Debug, Args)]
pub struct ReportArgs {
    /// The project directory: the compare runs are found below it.
    pub project: PathBuf,
    /// Where to write the page (default: PROJECT/report.html).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// tilth's own SVG, ready to inline: anything before the first tag (an XML prolog) removed.
fn inline_svg(svg: &str) -> &str {
    let svg = svg.trim_start_matches(|c| c != '<');
    if svg.starts_with("<?xml") {
        svg.split_once("?>").map_or(svg, |(_, rest)| rest)
    } else {
        svg
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

pub fn report(args: &ReportArgs) -> Result<String> {
    crate::study::summary(|out| report_into(args, out))
}

/// [`report`], writing its summary to `out`.
fn report_into(args: &ReportArgs, out: &mut dyn Write) -> Result<()> {
    if !args.project.is_dir() {
        bail!("{}: not a directory", args.project.display());
    }
    let steps = find_steps(&args.project)?;
    let runs: Vec<&Step> = steps
        .iter()
        .filter(|s| s.kind == StepKind::Compare)
        .collect();
    if runs.is_empty() {
        bail!(
            "{}: no compare run below it (no compare.json within four levels); run `tilth compare --out {}/NAME ...` first",
            args.project.display(),
            args.project.display()
        );
    }
    let observables = observables_of(&runs);

    let mut html = page_head(&args.project, runs.len());
    html += &runs_table(&runs);
    html += &story_html(&steps, escape);
    html += &error_table(&runs, &observables);
    html += &rmse_charts(&runs, &observables)?;
    html += &failure_summaries(&runs);
    html += &plots_side_by_side(&runs);
    html += "</body></html>\n";

    let path = args
        .out
        .clone()
        .unwrap_or_else(|| args.project.join("report.html"));
    std::fs::write(&path, html).with_context(|| format!("{}: cannot write", path.display()))?;
    writeln!(
        out,
        "{} compare runs -> {} (open it in a browser; it needs no network)",
        runs.len(),
        path.display()
    )?;
    Ok(())
}

/// Observables over all runs, with their unit ("" when no run names one).
fn observables_of(runs: &[&Step]) -> BTreeMap<String, String> {
    let mut observables: BTreeMap<String, String> = BTreeMap::new();
    for r in runs {
        for v in r.json["verdicts"].as_array().into_iter().flatten() {
            if let Some(o) = v["observable"].as_str() {
                observables.insert(o.into(), v["unit"].as_str().unwrap_or("").into());
            }
        }
        for (o, _) in r.json["observables"].as_object().into_iter().flatten() {
            observables.entry(o.clone()).or_default();
        }
    }
    observables
}

/// A run's RMSE of observable `o`, in its unit.
fn rmse(r: &Step, o: &str) -> Option<f64> {
    r.json["observables"][o]["rmse"].as_f64()
}

/// A run's mean relative error of observable `o`.
fn mre(r: &Step, o: &str) -> Option<f64> {
    r.json["observables"][o]["mean_relative_error"].as_f64()
}

/// The document head, its style sheet and the page's title.
fn page_head(project: &std::path::Path, runs: usize) -> String {
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>tilth report</title>\n<style>\
         body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse}\
         td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}th{background:#f3f3f3}\
         td.l,th.l{text-align:left}td.path{overflow-wrap:anywhere;max-width:36em}.row{display:flex;gap:12px;overflow-x:auto;align-items:flex-start}.wrap{flex-wrap:wrap}\
         .fig{flex:0 0 auto;text-align:center;font-size:13px}.fig svg{max-width:480px;height:auto}\
         .better{color:#2a7a2a}.worse{color:#b02020}</style></head><body>\n",
    );
    html += &format!(
        "<h1>tilth report: {}</h1>\n<p>{} compare run{}, oldest first. Errors are simulated minus measured.</p>\n",
        escape(&project.display().to_string()),
        runs,
        if runs == 1 { "" } else { "s" }
    );
    html
}

/// The compare runs: model, data and replicates, one row each.
fn runs_table(runs: &[&Step]) -> String {
    let mut html = String::new();
    // The runs, then the errors with one column per run: a project's history grows in runs,
    // and a row per observable keeps the page as wide as the number of runs (with the paths
    // in their own table, four observables no longer push it off the screen sideways).
    html += "<h2>Runs</h2>\n<table><tr><th>#</th><th class=\"l\">run</th><th class=\"l\">model</th><th class=\"l\">data</th><th>replicates</th></tr>\n";
    for (k, r) in runs.iter().enumerate() {
        html += &format!(
            "<tr><td>{}</td><td class=\"l\">{}</td><td class=\"l path\">{}</td><td class=\"l path\">{}</td><td>{}</td></tr>\n",
            k + 1,
            escape(&r.label),
            escape(r.json["model"].as_str().unwrap_or("?")),
            escape(r.json["data"].as_str().unwrap_or("?")),
            r.json["replicates"]
        );
    }
    html += "</table>\n";
    html
}

/// The errors with one column per run (RMSE and mean relative error), coloured by the
/// change from the run before.
fn error_table(runs: &[&Step], observables: &BTreeMap<String, String>) -> String {
    let mut html = String::new();
    html += "<h2>Error per observable</h2>\n<p>RMSE in the observable's unit, and below it the mean relative error; \
             green where a run's RMSE fell from the run before it, red where it rose.</p>\n\
             <table><tr><th class=\"l\">observable</th>";
    for (k, r) in runs.iter().enumerate() {
        html += &format!("<th>{}. {}</th>", k + 1, escape(&r.label));
    }
    html += "</tr>\n";
    for (o, u) in observables {
        html += &format!(
            "<tr><td class=\"l\">{}{}</td>",
            escape(o),
            if u.is_empty() {
                String::new()
            } else {
                format!(" ({})", escape(u))
            }
        );
        for (k, r) in runs.iter().enumerate() {
            let now = rmse(r, o);
            let before = k.checked_sub(1).and_then(|p| rmse(runs[p], o));
            let class = match (now, before) {
                (Some(n), Some(b)) if n < b => " class=\"better\"",
                (Some(n), Some(b)) if n > b => " class=\"worse\"",
                _ => "",
            };
            html += &format!(
                "<td{class}>{}<br><small>{}</small></td>",
                now.map_or("-".into(), |v| format!("{v:.4}")),
                mre(r, o).map_or("-".into(), |v| format!("{:.1} %", 100.0 * v))
            );
        }
        html += "</tr>\n";
    }
    html += "</table>\n";

    html
}

/// One RMSE-history chart per observable.
fn rmse_charts(runs: &[&Step], observables: &BTreeMap<String, String>) -> Result<String> {
    let mut html = String::new();
    // The charts wrap onto the next line (the plots further down scroll instead, to keep the
    // runs of one plot side by side).
    html += "<h2>RMSE history</h2>\n<div class=\"row wrap\">\n";
    for (o, u) in observables {
        let values: Vec<f64> = runs
            .iter()
            .map(|r| rmse(r, o).unwrap_or(f64::NAN))
            .collect();
        if values.iter().all(|v| v.is_nan()) {
            continue;
        }
        let svg = history_svg(o, u, &values).map_err(anyhow::Error::msg)?;
        html += &format!("<div class=\"fig\">{svg}</div>\n");
    }
    html += "</div>\n";

    Ok(html)
}

/// Each run's summary in words.
fn failure_summaries(runs: &[&Step]) -> String {
    let mut html = String::new();
    html += "<h2>Where each model fails</h2>\n";
    for (k, r) in runs.iter().enumerate() {
        html += &format!("<h3>{}. {}</h3>\n", k + 1, escape(&r.label));
        match r.json["summary"].as_str() {
            Some(s) => {
                html += "<ul>\n";
                for line in s.lines().filter(|l| !l.trim().is_empty()) {
                    let text = line.trim_start_matches("- ").replace("**", "");
                    html += &format!("<li>{}</li>\n", escape(&text));
                }
                html += "</ul>\n";
            }
            None => html += "<p>(made before compare wrote summaries)</p>\n",
        }
    }

    html
}

/// Every plot the runs made, by name, the runs side by side.
fn plots_side_by_side(runs: &[&Step]) -> String {
    let mut html = String::new();
    // Plots by name, the runs side by side.
    let mut names: Vec<String> = vec![];
    for r in runs {
        for p in r.json["plots"].as_array().into_iter().flatten() {
            if let Some(p) = p.as_str() {
                if !names.iter().any(|n| n == p) {
                    names.push(p.into());
                }
            }
        }
    }
    html += "<h2>Plots, run by run</h2>\n";
    // A plot a run lists but that is not beside its compare.json (a project copied without
    // its SVGs) is named once at the end, not drawn as an empty heading.
    let mut missing = vec![];
    for name in &names {
        let mut figs = String::new();
        let mut found = 0;
        for (k, r) in runs.iter().enumerate() {
            let listed = r.json["plots"]
                .as_array()
                .is_some_and(|a| a.iter().any(|p| p.as_str() == Some(name.as_str())));
            let caption = format!("{}. {}", k + 1, escape(&r.label));
            match std::fs::read_to_string(r.dir.join(name)) {
                Ok(svg) => {
                    found += 1;
                    figs += &format!(
                        "<div class=\"fig\">{}<br>{caption}</div>\n",
                        inline_svg(&svg)
                    );
                }
                // Keep the runs in their columns: a run that made the plot but lost it.
                Err(_) if listed => {
                    figs += &format!("<div class=\"fig\">(file not found)<br>{caption}</div>\n")
                }
                Err(_) => {}
            }
        }
        if found == 0 {
            missing.push(escape(name));
            continue;
        }
        html += &format!(
            "<h3>{}</h3>\n<div class=\"row\">\n{figs}</div>\n",
            escape(name)
        );
    }
    if !missing.is_empty() {
        html += &format!(
            "<p>Listed by the runs' compare.json but found beside none of them: {}.</p>\n",
            missing.join(", ")
        );
    }
    html
}
