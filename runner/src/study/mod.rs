//! The study: algorithms over runs and measurements. Compare a model with measured rows,
//! diagnose which candidate effect its misfit calls for, fit free parameters and effect
//! strengths, calibrate against one test or all, make synthetic data, plan the next
//! measurement, fit response surfaces (`rsm`), and gather a project's history into a report.
//! Each module takes its options (parsed by the CLI) and writes its files and summary.

pub mod calibrate;
pub mod check;
pub mod compare;
pub mod diagnose;
pub mod fit;
pub mod lab_runs;
pub mod measurements;
pub mod model_edit;
pub mod next;
pub mod project_report;
pub mod project_story;
pub mod reduce;
pub mod rsm;
pub mod synth;

use crate::text::summary;
