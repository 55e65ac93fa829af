//! A plan shown: as JSON, or as a table of its runs with coded and real values side by side.

use super::Plan;
use anyhow::Result;
use std::collections::BTreeMap;
use std::io::Write;

impl Plan {
    /// The plan as JSON: `{name, design, factors, runs: [{id, coded, values, seed, ...}]}`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "name": self.name,
            "sweep": self.origin,
            "design": self.title,
            "scene": self.scene.origin,
            "threads_per_run": self.threads,
            "factors": self.factors,
            "runs": self.runs,
        })
    }

    /// The plan as a table, coded and real values side by side.
    pub fn write_table(&self, out: &mut dyn Write) -> Result<()> {
        writeln!(
            out,
            "{}: {}; {} runs",
            self.name,
            self.title,
            self.runs.len()
        )?;
        if let Some(d) = &self.description {
            writeln!(out, "{}", d.trim())?;
        }
        writeln!(
            out,
            "scene {}, {} thread(s) per run\n",
            self.scene.origin, self.threads
        )?;
        if self.factors.is_empty() {
            return self.write_seeds(out);
        }
        self.write_factors(out)?;
        writeln!(out)?;
        self.write_runs(out)
    }

    /// A plan without factors, one setting over several seeds: the setting (the fixed
    /// values), then each run's replicate and seed.
    fn write_seeds(&self, out: &mut dyn Write) -> Result<()> {
        for (target, value) in &self.fixed {
            writeln!(out, "fixed  {target} = {value}")?;
        }
        writeln!(out, "\n{:>4}  {:>4}  {:>6}", "run", "rep", "seed")?;
        for r in &self.runs {
            writeln!(out, "{:>4}  {:>4}  {:>6}", r.id, r.replicate, r.seed)?;
        }
        Ok(())
    }

    /// One line per factor: its target, its range and what it is.
    fn write_factors(&self, out: &mut dyn Write) -> Result<()> {
        let nw = self
            .factors
            .iter()
            .map(|f| f.name.len())
            .max()
            .unwrap_or(4)
            .max(6);
        let tw = self
            .factors
            .iter()
            .map(|f| f.target.len())
            .max()
            .unwrap_or(6)
            .max(6);
        writeln!(
            out,
            "{:nw$}  {:tw$}  {:>10}  {:>10}  label",
            "factor", "target", "low (-1)", "high (+1)"
        )?;
        for f in &self.factors {
            writeln!(
                out,
                "{:nw$}  {:tw$}  {:>10}  {:>10}  {}{}",
                f.name,
                f.target,
                num(f.low),
                num(f.high),
                f.label.as_deref().unwrap_or(""),
                f.unit
                    .as_ref()
                    .map(|u| format!(" ({u})"))
                    .unwrap_or_default()
            )?;
        }
        Ok(())
    }

    /// One line per run: its numbers and seed, its coded values, then its real values.
    fn write_runs(&self, out: &mut dyn Write) -> Result<()> {
        let cw = self
            .factors
            .iter()
            .map(|f| f.name.len())
            .max()
            .unwrap_or(2)
            .max(6);
        let mut head = format!("{:>4}  {:>4}  {:>4}  {:>6} |", "run", "std", "rep", "seed");
        for f in &self.factors {
            head += &format!(" {:>cw$}", f.name);
        }
        head += " |";
        for f in &self.factors {
            head += &format!(" {:>10}", f.name);
        }
        writeln!(
            out,
            "{:>27}{:^w$}| real values",
            "",
            "coded",
            w = (cw + 1) * self.factors.len() + 1
        )?;
        writeln!(out, "{head}")?;
        for r in &self.runs {
            let mut line = format!(
                "{:>4}  {:>4}  {:>4}  {:>6} |",
                r.id, r.std, r.replicate, r.seed
            );
            for f in &self.factors {
                line += &format!(" {:>cw$}", coded(r.coded[&f.name]));
            }
            line += " |";
            for f in &self.factors {
                line += &format!(" {:>10}", num(r.values[&f.name]));
            }
            writeln!(out, "{line}")?;
        }
        Ok(())
    }
}

/// `x1 = 0.2, x2 = 0.5`.
pub fn describe(values: &BTreeMap<String, f64>) -> String {
    values
        .iter()
        .map(|(k, v)| format!("{k} = {}", num(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A coded value: `+1`, `-1`, `0`, or three decimals.
fn coded(c: f64) -> String {
    if c == c.round() {
        if c > 0.0 {
            format!("+{c:.0}")
        } else {
            format!("{c:.0}")
        }
    } else {
        format!("{c:+.3}")
    }
}

/// A real value in at most 6 significant digits, without trailing zeros.
pub fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}
