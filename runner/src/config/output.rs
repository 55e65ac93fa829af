//! `[output]`: what the run records besides the final summary.

use super::check;
use anyhow::Result;
use serde::{Deserialize, Serialize};

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Simulated time between recorded samples (time, particles, contacts, kinetic energy), s.
    /// No samples when omitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub every: Option<f64>,
}

impl OutputSection {
    /// Steps between samples (at least 1).
    pub fn resolve(&self, dt: f64) -> Result<Option<u64>> {
        self.every
            .map(|e| {
                check::positive("output.every", e, "s")?;
                Ok(((e / dt).round() as u64).max(1))
            })
            .transpose()
    }
}
