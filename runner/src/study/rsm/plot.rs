//! Writing `tilth rsm` pictures to files.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use tilth_tools::rsm::{Anova, Solution, plot};

fn write(path: PathBuf, svg: String) -> Result<PathBuf> {
    std::fs::write(&path, svg).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(path)
}

/// File-name-safe form of a label.
pub fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The contour plot of one target's solutions, when two factors are free.
pub fn contour(
    a: &Anova,
    s: &Solution,
    fixed: &[(usize, f64)],
    dir: &Path,
) -> Result<Option<PathBuf>> {
    match plot::contour_svg(a, s, fixed)? {
        Some(svg) => Ok(Some(write(
            dir.join(format!(
                "contour-{}-{}.svg",
                slug(&a.response),
                slug(&s.label)
            )),
            svg,
        )?)),
        None => Ok(None),
    }
}

/// The response against the one free factor, with every target and its setting.
pub fn curve(
    a: &Anova,
    solutions: &[Solution],
    fixed: &[(usize, f64)],
    dir: &Path,
) -> Result<Option<PathBuf>> {
    match plot::response_curve_svg(a, solutions, fixed)? {
        Some(svg) => Ok(Some(write(
            dir.join(format!("solve-{}.svg", slug(&a.response))),
            svg,
        )?)),
        None => Ok(None),
    }
}

/// Pareto, main-effects and predicted-vs-actual pictures of a fit.
pub fn fit(a: &Anova, dir: &Path) -> Result<Vec<PathBuf>> {
    let r = slug(&a.response);
    Ok(vec![
        write(dir.join(format!("pareto-{r}.svg")), plot::pareto_svg(a)?)?,
        write(
            dir.join(format!("main-effects-{r}.svg")),
            plot::main_effects_svg(a)?,
        )?,
        write(
            dir.join(format!("predicted-vs-actual-{r}.svg")),
            plot::predicted_vs_actual_svg(a)?,
        )?,
    ])
}
