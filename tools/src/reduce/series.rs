//! A scalar time series (`/scalars/<name>`) and the pairing of two of them.

use serde::{Deserialize, Serialize};

/// Samples of one `/scalars/<name>` channel in log-time order: time (s) and value (the
/// channel's unit, see the `unit` channel metadata).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub time_s: Vec<f64>,
    pub value: Vec<f64>,
}

impl Series {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when the series has no sample.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// `(self, other)` value pairs at the times both series have a sample, in time order.
    ///
    /// The runner writes every scalar of one record with the same log time, so curves such
    /// as force against displacement pair exactly; a sample without its partner (the last
    /// record of a cut file, or a channel that starts later) is dropped rather than
    /// interpolated, so no number in a curve is made up. Times compare exactly because both
    /// come from the same integer nanosecond log time.
    pub fn paired(&self, other: &Series) -> Vec<(f64, f64)> {
        let (mut i, mut j) = (0, 0);
        let mut out = Vec::with_capacity(self.len().min(other.len()));
        while i < self.len() && j < other.len() {
            let (a, b) = (self.time_s[i], other.time_s[j]);
            if a < b {
                i += 1;
            } else if b < a {
                j += 1;
            } else {
                out.push((self.value[i], other.value[j]));
                i += 1;
                j += 1;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_only_common_times() {
        let a = Series {
            time_s: vec![0.0, 0.1, 0.2, 0.3],
            value: vec![1.0, 2.0, 3.0, 4.0],
        };
        let b = Series {
            time_s: vec![0.1, 0.2, 0.25, 0.3, 0.4],
            value: vec![20.0, 30.0, 35.0, 40.0, 50.0],
        };
        assert_eq!(a.paired(&b), vec![(2.0, 20.0), (3.0, 30.0), (4.0, 40.0)]);
    }
}
