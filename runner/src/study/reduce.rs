//! `tilth reduce repose|shear|ucs|tilt FILES... [--json] [--plot DIR]`: MCAP -> the study's numbers,
//! a plot per file, and Mohr-Coulomb over several shear files (the reducers are in
//! `tilth_tools::reduce`).

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use std::io::Write;
use std::path::{Path, PathBuf};
use tilth_tools::reduce::{self, ReadOptions};

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Observable {
    /// Repose angle by the study's method (silhouette halves, line fits), with a cone fit.
    Repose,
    /// Peak shear force and the force-displacement curve; Mohr-Coulomb over several files.
    Shear,
    /// Unconfined compressive strength with the corrected area.
    Ucs,
    /// The angle at which the sample slides on the tilting plate, and its tangent.
    Tilt,
}

#[derive(Debug, Args)]
pub struct ReduceArgs {
    pub what: Observable,
    /// run.mcap files (a `.partial` file is read up to its last complete chunk and marked
    /// incomplete).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// One JSON object per file (and the Mohr-Coulomb fit for several shear files).
    #[arg(long)]
    pub json: bool,
    /// Write an SVG per file here (default: beside each file).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Repose: photographs of the heap evenly around it, each giving two halves (default: the
    /// run's `repose.photographs`, else 2, the x-z and y-z views). Every photograph measures
    /// the same angle on average; more of them average out how one side's outline happens
    /// to fall.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=180))]
    pub photographs: Option<u16>,
}

fn svg_path(file: &Path, dir: Option<&PathBuf>, what: &str) -> PathBuf {
    let stem = file
        .parent()
        .and_then(|p| p.file_name())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    match dir {
        Some(d) => d.join(format!("{what}-{stem}.svg")),
        None => file.with_file_name(format!("{what}.svg")),
    }
}

/// Reduces each file, writes its plot, and returns the summary: a line per file (or JSON).
pub fn reduce(args: &ReduceArgs) -> Result<String> {
    super::summary(|out| write_reduce(args, out))
}

fn write_reduce(args: &ReduceArgs, out: &mut dyn Write) -> Result<()> {
    if let Some(d) = &args.plot {
        std::fs::create_dir_all(d).with_context(|| format!("{}: cannot create", d.display()))?;
    }
    let mut results = vec![];
    let mut shears = vec![];
    for file in &args.files {
        let run = reduce::read_run(file, &ReadOptions::default())?;
        let (value, svg, line) = match args.what {
            Observable::Repose => {
                let options = match args.photographs {
                    Some(n) => reduce::ReposeOptions {
                        views: reduce::View::around(n as usize),
                        ..Default::default()
                    },
                    None => reduce::ReposeOptions::of_run(&run),
                };
                let r = reduce::repose(&run, &options)?;
                let line = format!(
                    "repose angle {:.2} deg (halves {}; cone fit {:.2} deg, R^2 {:.3})",
                    r.analysis.repose_angle_deg,
                    r.analysis
                        .views
                        .iter()
                        .flat_map(|v| [v.left.angle_deg, v.right.angle_deg])
                        .map(|a| format!("{a:.2}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    r.analysis.cone.angle_deg,
                    r.analysis.cone.r_squared
                );
                (
                    serde_json::to_value(&r)?,
                    reduce::plot::repose_svg(&r)?,
                    line,
                )
            }
            Observable::Shear => {
                let r = reduce::shear(&run, &Default::default())?;
                let line = format!(
                    "peak shear force {:.2} N at {:.2} mm",
                    r.analysis.peak_shear_force_n,
                    r.analysis.displacement_at_peak_m * 1e3
                );
                let svg = reduce::plot::shear_svg(&r)?;
                let v = serde_json::to_value(&r)?;
                shears.push(r);
                (v, svg, line)
            }
            Observable::Ucs => {
                let r = reduce::ucs(&run, &Default::default())?;
                let line = format!(
                    "UCS {:.2} kPa ({:?} at strain {:.3})",
                    r.analysis.ucs_kpa, r.analysis.failure, r.analysis.strain_at_failure
                );
                (serde_json::to_value(&r)?, reduce::plot::ucs_svg(&r)?, line)
            }
            Observable::Tilt => {
                let r = reduce::tilt(&run)?;
                let line = match r.analysis.slide_angle_deg {
                    Some(a) => format!(
                        "slid at {a:.2} deg (static friction {:.3})",
                        a.to_radians().tan()
                    ),
                    None => format!("did not slide up to {:.2} deg", r.analysis.max_angle_deg),
                };
                (serde_json::to_value(&r)?, reduce::plot::tilt_svg(&r)?, line)
            }
        };
        let what = format!("{:?}", args.what).to_lowercase();
        let svg_file = svg_path(file, args.plot.as_ref(), &what);
        std::fs::write(&svg_file, svg)
            .with_context(|| format!("{}: cannot write", svg_file.display()))?;
        let complete = run.completeness.complete;
        if !args.json {
            let flag = if complete { "" } else { "  [INCOMPLETE FILE]" };
            writeln!(
                out,
                "{}: {line}{flag}; plot {}",
                file.display(),
                svg_file.display()
            )?;
        }
        results.push(value);
    }
    let fit = if shears.len() >= 2 {
        let fit = reduce::mohr_coulomb(&shears)?;
        if !args.json {
            writeln!(
                out,
                "Mohr-Coulomb over {} files: cohesion {:.2} kPa, friction angle {:.2} deg (R^2 {:.3})",
                shears.len(),
                fit.cohesion_pa / 1e3,
                fit.friction_angle_deg,
                fit.r_squared
            )?;
        }
        Some(fit)
    } else {
        None
    };
    if args.json {
        let v = match fit {
            Some(f) => serde_json::json!({ "runs": results, "mohr_coulomb": f }),
            None if results.len() == 1 => results.remove(0),
            None => serde_json::Value::Array(results),
        };
        serde_json::to_writer_pretty(&mut *out, &v)?;
        writeln!(out)?;
    }
    Ok(())
}
