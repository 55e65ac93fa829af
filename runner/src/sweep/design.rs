//! `[design]`: which design, how many centre points and replicates, in which order.
//!
//! Keys every design takes: `type`, `centre_points`, `replicates` (default 1), `seed` (the
//! first run's seed, default 1; run k gets seed + k - 1), `run_order` (the standard-order
//! numbers, 1-based, in the order to run them: Design-Expert's "Std" column read down its
//! "Run" column) or `randomize = true` (a shuffled order from `seed`).
//! Keys per `type`:
//! - `full_factorial`: `levels` (levels of every low/high factor, default 2);
//! - `plackett_burman`: `runs` (8, 12, 16, 20 or 24; default the smallest that fits);
//! - `box_behnken`: none (3 to 7 factors);
//! - `central_composite`: `alpha` (`"rotatable"` (default), `"face_centred"` or a number);
//! - `steepest_ascent`: `direction` (a table factor -> first-order coefficient in coded
//!   units), `origin` (factor -> coded start, default 0), `step` (coded step of the factor
//!   with the largest coefficient), `steps` (points on the path, the origin included);
//! - `latin_hypercube`, `sobol`: `runs`;
//! - `replicates`: none, and no `[[factors]]`: the `[fixed]` setting run `replicates` times,
//!   seeds `seed` to `seed + replicates - 1` (extra specimens at a solved setting, or the
//!   scatter between seeds of one model).

use super::file::{FactorSection, Source};
use anyhow::Result;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use std::ops::Range;
use tilth_tools::design;
use toml::{Spanned, Table, Value};

/// A design expanded in coded units, standard order, centre points included.
#[derive(Debug, Clone)]
pub struct Expanded {
    /// What it is, for the plan's header (`Plackett-Burman, 12 runs + 3 centre points`).
    pub title: String,
    /// Coded rows in standard order.
    pub rows: Vec<Vec<f64>>,
    /// Standard-order indices (0-based) in run order.
    pub order: Vec<usize>,
    pub replicates: usize,
    pub seed: u64,
}

const COMMON: [&str; 6] = [
    "type",
    "centre_points",
    "replicates",
    "seed",
    "run_order",
    "randomize",
];

/// Expands `[design]` for `factors`.
pub fn expand(
    source: &Source,
    table: &Spanned<Table>,
    factors: &[&FactorSection],
) -> Result<Expanded> {
    let d = DesignTable {
        source,
        span: table.span(),
        table: table.get_ref(),
    };
    let kind = d.kind()?;
    let k = factors.len();
    let centre_given = d.uint("centre_points")?;
    let base = match kind {
        "full_factorial" => full_factorial(&d, factors)?,
        "plackett_burman" => plackett_burman(&d, k)?,
        "box_behnken" => box_behnken(&d, k)?,
        "central_composite" => central_composite(&d, k)?,
        "steepest_ascent" => steepest_ascent(&d, factors)?,
        ONE_SETTING => one_setting(&d, centre_given)?,
        // `kind` has refused every other type: this is latin_hypercube or sobol.
        _ => space_filling(&d, kind, k)?,
    };
    if kind != "full_factorial" {
        refuse_levels(source, factors)?;
    }
    let centres = centre_given.unwrap_or(base.default_centres);
    let rows = design::with_centre_points(base.rows, centres);
    let title = if centres > 0 {
        format!("{} + {centres} centre points", base.title)
    } else {
        base.title
    };
    let replicates = d.uint("replicates")?.unwrap_or(1);
    if replicates == 0 {
        return Err(d.err("replicates = 0 is out of range: allowed 1 or more".into()));
    }
    let seed = d.uint("seed")?.unwrap_or(1) as u64;
    let order = d.run_order(rows.len(), seed)?;
    Ok(Expanded {
        title,
        rows,
        order,
        replicates,
        seed,
    })
}

/// The design of one setting over several seeds (no factors).
pub const ONE_SETTING: &str = "replicates";

/// Every `type` a design may have.
pub const KINDS: [&str; 8] = [
    "full_factorial",
    "plackett_burman",
    "box_behnken",
    "central_composite",
    "steepest_ascent",
    "latin_hypercube",
    "sobol",
    ONE_SETTING,
];

/// The `[design]` table with where it is, so that every refusal names the file and line.
struct DesignTable<'a> {
    source: &'a Source,
    span: Range<usize>,
    table: &'a Table,
}

/// A design's own rows before centre points are added.
struct BaseDesign {
    /// What it is, without the centre points.
    title: String,
    /// Coded rows in standard order.
    rows: Vec<Vec<f64>>,
    /// Centre points added when `centre_points` is not given.
    default_centres: usize,
}

impl BaseDesign {
    /// Rows with no centre points unless the sweep asks for some.
    fn new(title: String, rows: Vec<Vec<f64>>) -> BaseDesign {
        BaseDesign {
            title,
            rows,
            default_centres: 0,
        }
    }
}

impl DesignTable<'_> {
    /// A refusal at the `[design]` table: `file:line: [design] msg`.
    fn err(&self, msg: String) -> anyhow::Error {
        self.source.err(&self.span, format!("[design] {msg}"))
    }

    /// A refusal of the design library, reported at the `[design]` table.
    fn design_err(&self, e: design::DesignError) -> anyhow::Error {
        self.err(e.to_string())
    }

    /// The whole number at `key`, if given.
    fn uint(&self, key: &str) -> Result<Option<usize>> {
        match self.table.get(key) {
            None => Ok(None),
            Some(Value::Integer(i)) if *i >= 0 => Ok(Some(*i as usize)),
            Some(v) => Err(self.err(format!("{key} = {v} must be a whole number >= 0"))),
        }
    }

    /// The number (float or integer) at `key`, if given as a number.
    fn number(&self, key: &str) -> Option<f64> {
        match self.table.get(key) {
            Some(Value::Float(x)) => Some(*x),
            Some(Value::Integer(x)) => Some(*x as f64),
            _ => None,
        }
    }

    /// The design's `type`, after checking that every key of the table belongs to it.
    fn kind(&self) -> Result<&str> {
        let kind = match self.table.get("type") {
            Some(Value::String(s)) => s.as_str(),
            Some(v) => return Err(self.err(format!("type = {v} must be a string"))),
            None => {
                return Err(self.err(format!("needs `type`: one of {}", KINDS.join(", "))));
            }
        };
        let own: &[&str] = match kind {
            "full_factorial" => &["levels"],
            "plackett_burman" => &["runs"],
            "box_behnken" => &[],
            "central_composite" => &["alpha"],
            "steepest_ascent" => &["direction", "origin", "step", "steps"],
            "latin_hypercube" | "sobol" => &["runs"],
            ONE_SETTING => &[],
            other => {
                return Err(self.err(format!(
                    "type = \"{other}\" is unknown: allowed {}",
                    KINDS.join(", ")
                )));
            }
        };
        for key in self.table.keys() {
            if !COMMON.contains(&key.as_str()) && !own.contains(&key.as_str()) {
                let mut allowed: Vec<&str> = COMMON.to_vec();
                allowed.extend_from_slice(own);
                return Err(self.err(format!(
                    "unknown key `{key}` for type = \"{kind}\": allowed {}",
                    allowed.join(", ")
                )));
            }
        }
        Ok(kind)
    }

    /// A table factor name -> number (`direction`, `origin`) as one value per factor, 0 for
    /// the factors it leaves out.
    fn per_factor(&self, key: &str, names: &[&str], required: bool) -> Result<Vec<f64>> {
        let mut out = vec![0.0; names.len()];
        let table = match self.table.get(key) {
            Some(Value::Table(tab)) => tab,
            None if !required => return Ok(out),
            _ => {
                return Err(self.err(format!(
                    "{key} must be a table of factor name -> number, e.g. {key} = {{ {} = 1.0 }}",
                    names[0]
                )));
            }
        };
        for (name, v) in table {
            let j = names.iter().position(|n| n == name).ok_or_else(|| {
                self.err(format!(
                    "{key}.{name}: unknown factor; the factors are {}",
                    names.join(", ")
                ))
            })?;
            out[j] = match v {
                Value::Float(x) => *x,
                Value::Integer(x) => *x as f64,
                _ => return Err(self.err(format!("{key}.{name} = {v} must be a number"))),
            };
        }
        Ok(out)
    }

    /// Standard-order indices (0-based) in run order, for `n` rows: as `run_order` lists
    /// them, shuffled from `seed` when `randomize = true`, else in standard order.
    fn run_order(&self, n: usize, seed: u64) -> Result<Vec<usize>> {
        match (self.table.get("run_order"), self.table.get("randomize")) {
            (Some(_), Some(Value::Boolean(true))) => {
                Err(self.err("give run_order or randomize = true, not both".into()))
            }
            (Some(Value::Array(list)), _) => self.listed_order(list, n),
            (Some(v), _) => Err(self.err(format!("run_order = {v} must be a list of numbers"))),
            (None, Some(Value::Boolean(true))) => {
                let mut order: Vec<usize> = (0..n).collect();
                order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
                Ok(order)
            }
            (None, Some(Value::Boolean(false)) | None) => Ok((0..n).collect()),
            (None, Some(v)) => Err(self.err(format!("randomize = {v} must be true or false"))),
        }
    }

    /// `run_order` as written: every standard run of the `n`, 1-based, once each.
    fn listed_order(&self, list: &[Value], n: usize) -> Result<Vec<usize>> {
        let mut order = Vec::with_capacity(list.len());
        let mut seen = vec![false; n];
        for v in list {
            let std = match v {
                Value::Integer(i) if (1..=n as i64).contains(i) => *i as usize,
                _ => {
                    return Err(self.err(format!(
                        "run_order entry {v} is out of range: allowed 1 to {n} (standard order numbers)"
                    )));
                }
            };
            if std::mem::replace(&mut seen[std - 1], true) {
                return Err(self.err(format!("run_order lists standard run {std} twice")));
            }
            order.push(std - 1);
        }
        if order.len() != n {
            return Err(self.err(format!(
                "run_order has {} entries; the design has {n} runs (with centre points)",
                order.len()
            )));
        }
        Ok(order)
    }
}

/// `full_factorial`: every combination of the levels (each factor's own `levels`, else the
/// design's `levels`, default 2).
fn full_factorial(d: &DesignTable, factors: &[&FactorSection]) -> Result<BaseDesign> {
    let default_levels = d.uint("levels")?.unwrap_or(2);
    let levels: Vec<usize> = factors
        .iter()
        .map(|f| f.level_count().unwrap_or(default_levels))
        .collect();
    let rows = design::full_factorial(&levels).map_err(|e| d.design_err(e))?;
    let shape: Vec<String> = levels.iter().map(|l| l.to_string()).collect();
    Ok(BaseDesign::new(
        format!("full factorial {}", shape.join("x")),
        rows,
    ))
}

/// `plackett_burman` for `k` factors: `runs` runs, default the smallest that fits.
fn plackett_burman(d: &DesignTable, k: usize) -> Result<BaseDesign> {
    let runs = match d.uint("runs")? {
        Some(r) => r,
        None => design::plackett_burman_size(k).map_err(|e| d.design_err(e))?,
    };
    let rows = design::plackett_burman(runs, k).map_err(|e| d.design_err(e))?;
    Ok(BaseDesign::new(
        format!("Plackett-Burman, {runs} runs"),
        rows,
    ))
}

/// `box_behnken` for `k` factors, with the usual centre points for `k` by default.
fn box_behnken(d: &DesignTable, k: usize) -> Result<BaseDesign> {
    let rows = design::box_behnken(k).map_err(|e| d.design_err(e))?;
    Ok(BaseDesign {
        title: format!("Box-Behnken, {} runs", rows.len()),
        rows,
        default_centres: design::box_behnken_default_centres(k).unwrap_or(0),
    })
}

/// `central_composite` for `k` factors, its axial distance from `alpha`.
fn central_composite(d: &DesignTable, k: usize) -> Result<BaseDesign> {
    let alpha = match d.table.get("alpha") {
        None => design::Alpha::Rotatable,
        Some(Value::String(s)) if s == "rotatable" => design::Alpha::Rotatable,
        Some(Value::String(s)) if s == "face_centred" || s == "face_centered" => {
            design::Alpha::FaceCentred
        }
        Some(Value::Float(a)) => design::Alpha::Value(*a),
        Some(Value::Integer(a)) => design::Alpha::Value(*a as f64),
        Some(v) => {
            return Err(d.err(format!(
                "alpha = {v}: allowed \"rotatable\", \"face_centred\" or a number > 0"
            )));
        }
    };
    let rows = design::central_composite(k, alpha).map_err(|e| d.design_err(e))?;
    Ok(BaseDesign::new(
        format!(
            "central composite, alpha = {:.4}, {} runs",
            alpha.value(k),
            rows.len()
        ),
        rows,
    ))
}

/// `steepest_ascent`: `steps` points along `direction` from `origin`, `step` apart.
fn steepest_ascent(d: &DesignTable, factors: &[&FactorSection]) -> Result<BaseDesign> {
    let names: Vec<&str> = factors.iter().map(|f| f.name.get_ref().as_str()).collect();
    let direction = d.per_factor("direction", &names, true)?;
    let origin = d.per_factor("origin", &names, false)?;
    let step = d
        .number("step")
        .ok_or_else(|| d.err("needs `step`, a number (coded units)".into()))?;
    let steps = d
        .uint("steps")?
        .ok_or_else(|| d.err("needs `steps`, a whole number".into()))?;
    let rows =
        design::steepest_ascent(&direction, &origin, step, steps).map_err(|e| d.design_err(e))?;
    Ok(BaseDesign::new(
        format!("steepest-ascent path, {steps} points"),
        rows,
    ))
}

/// `replicates`: the one setting of the fixed values, which has no centre to add.
fn one_setting(d: &DesignTable, centre_given: Option<usize>) -> Result<BaseDesign> {
    if centre_given.is_some_and(|c| c > 0) {
        return Err(d.err(format!(
            "centre_points: a type = \"{ONE_SETTING}\" design has no centre to add; give replicates"
        )));
    }
    let n = d.uint("replicates")?.unwrap_or(1);
    let title = if n == 1 {
        "one setting, 1 seed".to_string()
    } else {
        format!("one setting, {n} seeds")
    };
    Ok(BaseDesign::new(title, vec![vec![]]))
}

/// `latin_hypercube` or `sobol` (`kind`): `runs` points spread over the coded cube, drawn
/// from the design's `seed`.
fn space_filling(d: &DesignTable, kind: &str, k: usize) -> Result<BaseDesign> {
    let runs = d
        .uint("runs")?
        .ok_or_else(|| d.err("needs `runs`, a whole number".into()))?;
    let seed = d.uint("seed")?.unwrap_or(1) as u64;
    let (rows, name) = if kind == "sobol" {
        (design::sobol(runs, k, seed), "Sobol' sequence")
    } else {
        (design::latin_hypercube(runs, k, seed), "Latin hypercube")
    };
    let rows = rows.map_err(|e| d.design_err(e))?;
    Ok(BaseDesign::new(format!("{name}, {runs} runs"), rows))
}

/// Refuses explicit factor `levels` in any design but a full factorial, which alone reads
/// them.
fn refuse_levels(source: &Source, factors: &[&FactorSection]) -> Result<()> {
    match factors.iter().find(|f| f.levels.is_some()) {
        Some(f) => Err(source.err(
            &f.name.span(),
            format!(
                "factor `{}` lists `levels`, which only a full_factorial design uses; give low and high",
                f.name.get_ref()
            ),
        )),
        None => Ok(()),
    }
}
