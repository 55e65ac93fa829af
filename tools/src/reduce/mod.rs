//! Offline reducers: a run's MCAP file -> the numbers a soil lab reports.
//!
//! Read a file once with [`read_run`] (a truncated or interrupted file is read up to its
//! last whole chunk and marked `complete: false`), then reduce it:
//!
//! - [`repose`]: angle of repose of the heap on the tray, by the study's photograph method
//!   (silhouette halves fitted in a height band), with a cone fit as cross-check;
//! - [`shear`]: peak shear force of a direct shear run; [`mohr_coulomb`] fits
//!   tau = c + sigma tan(phi) through several runs' peaks;
//! - [`ucs`]: unconfined compressive strength on the corrected area;
//! - [`tilt`]: the angle at which a sample slides on a tilting steel plate.
//!
//! Every result is `Serialize` to one flat JSON object with the stable key of its number
//! (`repose_angle_deg`, `peak_shear_force_n`, `ucs_kpa`, `slide_angle_deg`) beside `file`,
//! `complete` and `incomplete_reason`, and the curve or silhouette it came from. [`plot`]
//! draws each as SVG.
//!
//! What the runner writes and which channels each experiment adds: runner/MCAP.md and the
//! channel contract in each reducer's documentation. The reference study and its tests:
//! docs/experiments.md (Li et al. 2022).
//!
//! One concern per file: reading the file, the point-cloud layout, scalar series, the
//! least-squares line, the silhouette, the cone fit, one file per test, one per picture.

mod cloud;
mod cone_fit;
mod error;
mod line_fit;
mod mohr_coulomb;
pub mod plot;
mod read;
mod repose;
mod series;
mod shear;
mod silhouette;
mod tilt;
mod ucs;

pub use cloud::ParticleCloud;
pub use cone_fit::ConeFit;
pub use error::ReduceError;
pub use line_fit::{LineFit, fit_line};
pub use mohr_coulomb::{MohrCoulombFit, MohrPoint, fit_mohr_coulomb, mohr_coulomb};
pub use read::{
    CloudChoice, Completeness, EXPERIMENT_RECORD, PARTICLES, RECORD_LIMIT, RUN_RECORD, ReadOptions,
    Run, RunSource, SCALARS, read_run,
};
pub use repose::{
    ENVELOPE_BINS_PER_DIAMETER, HalfFit, REPOSE, ReposeAnalysis, ReposeOptions, ReposeResult, Tray,
    ViewFit, repose, repose_angle,
};
pub use series::Series;
pub use shear::{
    DIRECT_SHEAR, ShearAnalysis, ShearOptions, ShearResult, ShearSpecimen, analyse_shear, shear,
};
pub use silhouette::{SilhouetteMethod, View, silhouette};
pub use tilt::{TILT, TiltAnalysis, TiltResult, analyse_tilt, tilt};
pub use ucs::{Failure, UCS, UcsAnalysis, UcsOptions, UcsResult, UcsSpecimen, analyse_ucs, ucs};
