//! The text form of `tilth rsm` results: Design-Expert's ANOVA layout.

use std::io::Write;
use tilth_tools::rsm::{Anova, Check, Solution, SourceRow};

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$}"))
}

/// p-values as Design-Expert prints them: four decimals, "< 0.0001" below.
pub fn p(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(v) if v < 1e-4 => "< 0.0001".into(),
        Some(v) => format!("{v:.4}"),
    }
}

fn verdict(pv: Option<f64>) -> &'static str {
    match pv {
        Some(v) if v < 0.05 => "significant",
        Some(_) => "not significant",
        None => "",
    }
}

fn source_line(name: &str, s: &SourceRow, out: &mut dyn Write, tag: &str) -> std::io::Result<()> {
    writeln!(
        out,
        "{name:<16} {:>12.4} {:>4} {:>12} {:>10} {:>9}  {tag}",
        s.sum_sq,
        s.df,
        opt(s.mean_sq, 4),
        opt(s.f, 3),
        p(s.p)
    )
}

/// The ANOVA table, the fit statistics and the equations.
pub fn anova(a: &Anova, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        out,
        "{}: {} model of {} on {} ({} runs, factors coded -1..+1)",
        a.source,
        a.order.name(),
        a.response,
        a.factors.join(", "),
        a.runs
    )?;
    for (k, f) in a.factors.iter().enumerate() {
        writeln!(
            out,
            "  {f}: -1 = {}, +1 = {}",
            a.coding.low[k], a.coding.high[k]
        )?;
    }
    writeln!(out, "\nANOVA (Type III partial sums of squares)")?;
    writeln!(
        out,
        "{:<16} {:>12} {:>4} {:>12} {:>10} {:>9}",
        "source", "sum_sq", "df", "mean_sq", "F", "p"
    )?;
    source_line("model", &a.model, out, verdict(a.model.p))?;
    for t in &a.terms {
        if t.name == "curvature" {
            continue;
        }
        writeln!(
            out,
            "  {:<14} {:>12.4} {:>4} {:>12.4} {:>10} {:>9}",
            t.name,
            t.sum_sq,
            t.df,
            t.mean_sq,
            opt(t.f, 3),
            p(t.p)
        )?;
    }
    if let Some(c) = &a.curvature {
        source_line("curvature", c, out, verdict(c.p))?;
    }
    source_line("residual", &a.residual, out, "")?;
    if let Some(l) = &a.lack_of_fit {
        let tag = match l.p {
            Some(v) if v < 0.05 => "significant",
            Some(_) => "not significant",
            None => "",
        };
        source_line("  lack of fit", l, out, tag)?;
    }
    if let Some(pe) = &a.pure_error {
        source_line("  pure error", pe, out, "")?;
    }
    source_line("cor total", &a.total, out, "")?;

    writeln!(out)?;
    writeln!(
        out,
        "std dev  {:>10}    R^2             {:.4}",
        opt(a.std_dev, 4),
        a.r2
    )?;
    writeln!(
        out,
        "mean     {:>10.4}    adjusted R^2    {}",
        a.mean,
        opt(a.adj_r2, 4)
    )?;
    writeln!(
        out,
        "C.V. %   {:>10}    predicted R^2   {}",
        opt(a.cv_pct, 2),
        opt(a.pred_r2, 4)
    )?;
    writeln!(
        out,
        "PRESS    {:>10}    adeq precision  {}",
        opt(a.press, 3),
        opt(a.adeq_precision, 4)
    )?;

    writeln!(out, "\ncoefficients (coded units)")?;
    writeln!(
        out,
        "{:<16} {:>12} {:>10} {:>8}",
        "term", "estimate", "std err", "t"
    )?;
    writeln!(out, "{:<16} {:>12.5}", "intercept", a.intercept)?;
    for t in &a.terms {
        writeln!(
            out,
            "{:<16} {:>12.5} {:>10} {:>8}",
            t.name,
            t.coefficient,
            opt(t.std_error, 5),
            opt(t.t, 3)
        )?;
    }
    writeln!(out, "\ncoded:  {}", a.equation_coded)?;
    writeln!(out, "real:   {}", a.equation_real)?;
    for (name, pv) in &a.removed {
        writeln!(out, "removed by backward elimination: {name} (p = {pv:.4})")?;
    }
    for n in &a.notes {
        writeln!(out, "note: {n}")?;
    }
    Ok(())
}

/// The check against a published table; disagreements are listed last, in words.
pub fn checks(list: &[Check], file: &str, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "\nagainst {file}")?;
    writeln!(
        out,
        "{:<14} {:<16} {:>10} {:>12} {:>25}",
        "source", "field", "reported", "tilth", "within input rounding"
    )?;
    for c in list {
        writeln!(
            out,
            "{:<14} {:<16} {:>10} {:>12} {:>25}  {}{}",
            c.source,
            c.field,
            c.reported,
            c.computed.map_or("-".into(), |v| format!("{v:.6}")),
            c.range
                .map_or("-".into(), |(a, b)| format!("{} .. {}", short(a), short(b))),
            if c.agrees { "ok" } else { "DIFFERS" },
            c.note
                .as_deref()
                .map_or(String::new(), |n| format!(" ({n})"))
        )?;
    }
    let bad: Vec<&Check> = list.iter().filter(|c| !c.agrees).collect();
    writeln!(
        out,
        "{} of {} reported values agree with the data (within the rounding of the printed responses and of the value itself)",
        list.len() - bad.len(),
        list.len()
    )?;
    for c in bad {
        writeln!(
            out,
            "DIFFERS: {} {}: the source prints {}, its data give {}",
            c.source,
            c.field,
            c.reported,
            c.computed
                .map_or("nothing comparable".into(), |v| format!("{v:.4}"))
        )?;
    }
    Ok(())
}

/// Five significant digits.
fn short(v: f64) -> String {
    tilth_tools::rsm::significant(v, 5)
}

/// One target's solutions: a sample of the settings, the extent, the statement.
pub fn solution(a: &Anova, s: &Solution, show: usize, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "\n{} = {} ({})", a.response, s.target, s.label)?;
    if !s.settings.is_empty() {
        write!(out, "  ")?;
        for f in &a.factors {
            write!(out, "{f:>12}")?;
        }
        writeln!(out, "{:>14}", "predicted")?;
        let n = s.settings.len();
        let picks: Vec<usize> = if n <= show || show < 2 {
            (0..n).collect()
        } else {
            (0..show).map(|k| k * (n - 1) / (show - 1)).collect()
        };
        for k in picks {
            let st = &s.settings[k];
            write!(out, "  ")?;
            for v in &st.values {
                write!(out, "{v:>12.5}")?;
            }
            writeln!(out, "{:>14.4}", st.predicted)?;
        }
    }
    writeln!(out, "  {}", s.statement)?;
    Ok(())
}
