//! The runs to fit: factor settings and one response, with the factors' coding.

use super::{Coding, RsmError, Table};

/// Factor settings (real units) and a response, one row per run.
#[derive(Debug, Clone)]
pub struct Data {
    /// Where the runs came from, for messages.
    pub source: String,
    pub factors: Vec<String>,
    pub response: String,
    /// Real settings, one row per run.
    pub x: Vec<Vec<f64>>,
    pub y: Vec<f64>,
    pub coding: Coding,
    /// Decimals the response was printed with, when every cell is plain decimal text: a
    /// published table rounds its responses, and a check against its statistics must allow
    /// for that.
    pub response_decimals: Option<u32>,
}

impl Data {
    /// Picks `factors` and `response` from `table`. Each factor is coded from `ranges`
    /// (low, high) when given, else from its smallest and largest value in the table (right
    /// for two- and three-level designs; give the ranges for a central composite design,
    /// whose axial points lie beyond +-1).
    pub fn from_table(
        table: &Table,
        factors: &[String],
        response: &str,
        ranges: Option<&[(f64, f64)]>,
    ) -> Result<Data, RsmError> {
        if factors.is_empty() {
            return Err(RsmError::Request(
                "no factors given (--factors A,B,...)".into(),
            ));
        }
        let columns: Vec<Vec<f64>> = factors
            .iter()
            .map(|f| table.numbers(f))
            .collect::<Result<_, _>>()?;
        let y = table.numbers(response)?;
        let response_decimals = table.text(response)?.iter().try_fold(0u32, |d, cell| {
            if cell.contains(['e', 'E']) {
                return None;
            }
            Some(d.max(cell.split_once('.').map_or(0, |(_, f)| f.len() as u32)))
        });
        let mut low = Vec::new();
        let mut high = Vec::new();
        for (k, col) in columns.iter().enumerate() {
            let lo = col.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = col.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if col.is_empty() || lo == hi {
                return Err(RsmError::Constant {
                    file: table.source.clone(),
                    column: factors[k].clone(),
                    value: if col.is_empty() { f64::NAN } else { lo },
                });
            }
            let (l, h) = match ranges {
                Some(r) => r[k],
                None => (lo, hi),
            };
            if !(h > l) {
                return Err(RsmError::Request(format!(
                    "range of {}: low {l} must be below high {h}",
                    factors[k]
                )));
            }
            low.push(l);
            high.push(h);
        }
        let n = y.len();
        let x = (0..n)
            .map(|r| columns.iter().map(|c| c[r]).collect())
            .collect();
        Ok(Data {
            source: table.source.clone(),
            factors: factors.to_vec(),
            response: response.to_string(),
            x,
            y,
            coding: Coding { low, high },
            response_decimals,
        })
    }

    /// Gives the factors other names (a table's `x4_coded` column as `x4`).
    pub fn renamed(mut self, names: &[String]) -> Result<Data, RsmError> {
        if names.len() != self.factors.len() {
            return Err(RsmError::Request(format!(
                "{} names for {} factors ({})",
                names.len(),
                self.factors.len(),
                self.factors.join(", ")
            )));
        }
        self.factors = names.to_vec();
        Ok(self)
    }

    /// Reads the factor columns as coded values whose -1 and +1 are the real `levels`
    /// (low, high): the equation in real units then uses those levels.
    pub fn from_coded(mut self, levels: &[(f64, f64)]) -> Data {
        self.coding = Coding {
            low: levels.iter().map(|l| l.0).collect(),
            high: levels.iter().map(|l| l.1).collect(),
        };
        let coding = self.coding.clone();
        for x in &mut self.x {
            *x = coding.real(x);
        }
        self
    }

    /// Coded settings of every run.
    pub fn coded(&self) -> Vec<Vec<f64>> {
        self.x.iter().map(|x| self.coding.code(x)).collect()
    }

    /// The same runs with another response.
    pub fn with_response(&self, name: &str, y: Vec<f64>) -> Data {
        Data {
            response: name.to_string(),
            y,
            ..self.clone()
        }
    }
}
