//! A finished run's recording reduced to the observable its experiment measures.

use anyhow::Result;
use std::path::Path;

/// Reduces a finished run's MCAP file with the reducer of its experiment `kind`.
pub fn reduce_run(path: &Path, kind: &str) -> serde_json::Value {
    use tilth_tools::reduce;
    let result = (|| -> Result<serde_json::Value> {
        let run = reduce::read_run(path, &reduce::ReadOptions::default())?;
        Ok(match kind {
            "repose" => {
                let r = reduce::repose(&run, &reduce::ReposeOptions::of_run(&run))?;
                std::fs::write(
                    path.with_file_name("repose.svg"),
                    reduce::plot::repose_svg(&r)?,
                )?;
                serde_json::json!({
                    "repose_angle_deg": r.analysis.repose_angle_deg,
                    "cone_fit_deg": r.analysis.cone.angle_deg,
                })
            }
            "direct_shear" => {
                let r = reduce::shear(&run, &Default::default())?;
                std::fs::write(
                    path.with_file_name("shear.svg"),
                    reduce::plot::shear_svg(&r)?,
                )?;
                serde_json::json!({
                    "peak_shear_force_n": r.analysis.peak_shear_force_n,
                    "max_inertial_number": r.analysis.max_inertial_number,
                })
            }
            "ucs" => {
                let r = reduce::ucs(&run, &Default::default())?;
                std::fs::write(path.with_file_name("ucs.svg"), reduce::plot::ucs_svg(&r)?)?;
                serde_json::json!({
                    "ucs_kpa": r.analysis.ucs_kpa,
                    "failure": format!("{:?}", r.analysis.failure),
                    "max_inertial_number": r.analysis.max_inertial_number,
                })
            }
            "tilt" => {
                let r = reduce::tilt(&run)?;
                std::fs::write(path.with_file_name("tilt.svg"), reduce::plot::tilt_svg(&r)?)?;
                serde_json::json!({
                    "slide_angle_deg": r.analysis.slide_angle_deg,
                    "static_friction": r.analysis.static_friction,
                })
            }
            other => serde_json::json!({ "error": format!("no reducer for `{other}`") }),
        })
    })();
    result.unwrap_or_else(|e| serde_json::json!({ "error": format!("{e:#}") }))
}
