//! The story of a project for `tilth report`: every step of the discovery loop found under
//! the project directory (`compare.json`, `diagnosis.json`, `next.json`, `fit.json`), oldest
//! first, each with what it concluded: a compare's errors, a diagnosis's verdict, the
//! measurement `next` suggests, and a fit's model diff (each parameter or effect strength
//! moved, with its standard error), so that the error history reads beside what changed.

use anyhow::{Context, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// What a step's file says it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepKind {
    Compare,
    Diagnose,
    Next,
    Fit,
}

impl StepKind {
    fn file(self) -> &'static str {
        match self {
            StepKind::Compare => "compare.json",
            StepKind::Diagnose => "diagnosis.json",
            StepKind::Next => "next.json",
            StepKind::Fit => "fit.json",
        }
    }

    fn name(self) -> &'static str {
        match self {
            StepKind::Compare => "compare",
            StepKind::Diagnose => "diagnose",
            StepKind::Next => "next",
            StepKind::Fit => "fit",
        }
    }
}

/// One step of the loop.
pub struct Step {
    pub kind: StepKind,
    /// The directory its file is in.
    pub dir: PathBuf,
    /// Its directory relative to the project.
    pub label: String,
    /// Seconds since the epoch: `created` in the file, else the file's modification time.
    pub created: f64,
    pub json: Value,
}

const KINDS: [StepKind; 4] = [
    StepKind::Compare,
    StepKind::Diagnose,
    StepKind::Next,
    StepKind::Fit,
];

/// Every step below `project` (up to four levels down), oldest first.
pub fn find_steps(project: &Path) -> Result<Vec<Step>> {
    let mut dirs = vec![];
    walk(project, 4, &mut dirs)?;
    let mut steps = vec![];
    for dir in dirs {
        for kind in KINDS {
            let file = dir.join(kind.file());
            if !file.is_file() {
                continue;
            }
            let json: Value = serde_json::from_slice(&std::fs::read(&file)?)
                .with_context(|| format!("{}: not JSON", file.display()))?;
            let created = json["created"].as_f64().unwrap_or_else(|| modified(&file));
            let label = dir
                .strip_prefix(project)
                .unwrap_or(&dir)
                .display()
                .to_string();
            steps.push(Step {
                kind,
                dir: dir.clone(),
                label: if label.is_empty() { ".".into() } else { label },
                created,
                json,
            });
        }
    }
    steps.sort_by(|a, b| a.created.total_cmp(&b.created).then(a.label.cmp(&b.label)));
    Ok(steps)
}

fn modified(file: &Path) -> f64 {
    std::fs::metadata(file)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0.0, |d| d.as_secs_f64())
}

fn walk(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) -> Result<()> {
    out.push(dir.to_path_buf());
    // A compare run's subdirectories are its sweeps: nothing of the loop's below them.
    if depth == 0 || dir.join("compare.json").is_file() {
        return Ok(());
    }
    let mut subs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    subs.sort();
    for s in subs {
        walk(&s, depth - 1, out)?;
    }
    Ok(())
}

fn num(v: &Value) -> String {
    v.as_f64().map_or("?".into(), |x| format!("{x:.4}"))
}

fn p_text(p: f64) -> String {
    if p < 1e-6 {
        "< 1e-6".into()
    } else if p < 0.01 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// A compare's errors: the RMSE of each observable.
fn compare_text(j: &Value) -> String {
    let errors: Vec<String> = j["observables"]
        .as_object()
        .into_iter()
        .flatten()
        .map(|(o, v)| format!("{o} {}", num(&v["rmse"])))
        .collect();
    format!(
        "{} against {}: RMSE {}",
        j["model"].as_str().unwrap_or("?"),
        j["data"].as_str().unwrap_or("?"),
        errors.join(", ")
    )
}

/// A diagnosis's verdict in one line.
fn verdict_text(j: &Value) -> String {
    let v = &j["verdict"];
    let names = |key: &str| -> Vec<String> {
        v[key]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|n| n.as_str().map(String::from))
            .collect()
    };
    let misfit = &v["misfit"];
    let misfit = format!(
        "misfit chi^2 {:.1} on {} degrees of freedom, p {}",
        misfit["chi2"].as_f64().unwrap_or(f64::NAN),
        misfit["dof"],
        p_text(misfit["p_value"].as_f64().unwrap_or(f64::NAN))
    );
    match v["verdict"].as_str() {
        Some("effect") => {
            let effects: Vec<String> = v["effects"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|e| {
                    format!(
                        "{} (strength {} ± {})",
                        e["name"].as_str().unwrap_or("?"),
                        num(&e["strength"]),
                        num(&e["standard_error"])
                    )
                })
                .collect();
            format!("effect: {}; {misfit}", effects.join(" and "))
        }
        Some("ambiguous") => format!(
            "ambiguous: {} cannot be told apart on these data",
            names("ambiguous").join(", ")
        ),
        Some("none_of_the_candidates") => {
            format!("none of the candidates explains the misfit ({misfit})")
        }
        Some("no_effect") => "no effect beyond what the free parameters take out".into(),
        _ => "(made before diagnose wrote verdicts)".into(),
    }
}

/// The measurement `next` ranks first.
fn next_text(j: &Value) -> String {
    let Some(best) = j["options"].as_array().and_then(|o| o.first()) else {
        return "no measurement on the menu".into();
    };
    let conditions: Vec<String> = best["conditions"]
        .as_object()
        .into_iter()
        .flatten()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    let observables: Vec<&str> = best["observables"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|o| o.as_str())
        .collect();
    format!(
        "to tell apart {}: measure {} at {} ({}), power {:.2} at alpha {}, {} runs",
        j["rivals"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|r| r.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        best["test"].as_str().unwrap_or("?"),
        conditions.join(", "),
        observables.join(", "),
        best["power"].as_f64().unwrap_or(f64::NAN),
        j["alpha"],
        best["runs"]
    )
}

/// A fit's model diff: each parameter from its start to the estimate ± standard error.
fn fit_text(j: &Value) -> String {
    let params = j["parameters"].as_array().cloned().unwrap_or_default();
    let moved: Vec<String> = params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let estimate = &j["estimate"][k];
            let se = &j["standard_error"][k];
            let label = p["label"].as_str().unwrap_or("?");
            if p["target"].get("candidate").is_some() {
                format!("+ effect {label}: strength {} ± {}", num(estimate), num(se))
            } else {
                let shift = estimate.as_f64().unwrap_or(f64::NAN);
                format!("~ {label}: moved by {shift:+.4} ± {}", num(se))
            }
        })
        .collect();
    format!(
        "{} -> {}: {}; chi^2 {:.1} on {} degrees of freedom",
        j["model"].as_str().unwrap_or("?"),
        j["fitted_model"].as_str().unwrap_or("?"),
        moved.join("; "),
        j["chi2"].as_f64().unwrap_or(f64::NAN),
        j["dof"]
    )
}

/// What the step concluded, in one line of plain text.
pub fn step_text(step: &Step) -> String {
    match step.kind {
        StepKind::Compare => compare_text(&step.json),
        StepKind::Diagnose => verdict_text(&step.json),
        StepKind::Next => next_text(&step.json),
        StepKind::Fit => fit_text(&step.json),
    }
}

/// The story as an HTML table (`escape` escapes text for HTML).
pub fn story_html(steps: &[Step], escape: fn(&str) -> String) -> String {
    let mut html = String::from(
        "<h2>The story, step by step</h2>\n<p>Every step of the loop below the project, oldest first: \
         what each compare measured, each diagnosis's verdict, the measurement <code>next</code> \
         suggested, and what each fit changed in the model (<code>+</code> an effect added, \
         <code>~</code> a parameter moved, with standard errors).</p>\n\
         <table><tr><th>#</th><th class=\"l\">step</th><th class=\"l\">directory</th><th class=\"l\">what it says</th></tr>\n",
    );
    for (k, s) in steps.iter().enumerate() {
        html += &format!(
            "<tr><td>{}</td><td class=\"l\">{}</td><td class=\"l path\">{}</td><td class=\"l\">{}</td></tr>\n",
            k + 1,
            s.kind.name(),
            escape(&s.label),
            escape(&step_text(s))
        );
    }
    html + "</table>\n"
}
