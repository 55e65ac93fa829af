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
    let span = table.span();
    let t = table.get_ref();
    let err = |msg: String| source.err(&span, format!("[design] {msg}"));
    let kind = match t.get("type") {
        Some(Value::String(s)) => s.as_str(),
        Some(v) => return Err(err(format!("type = {v} must be a string"))),
        None => return Err(err(format!("needs `type`: one of {}", KINDS.join(", ")))),
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
            return Err(err(format!(
                "type = \"{other}\" is unknown: allowed {}",
                KINDS.join(", ")
            )));
        }
    };
    for key in t.keys() {
        if !COMMON.contains(&key.as_str()) && !own.contains(&key.as_str()) {
            let mut allowed: Vec<&str> = COMMON.to_vec();
            allowed.extend_from_slice(own);
            return Err(err(format!(
                "unknown key `{key}` for type = \"{kind}\": allowed {}",
                allowed.join(", ")
            )));
        }
    }
    let k = factors.len();
    let uint = |key: &str| -> Result<Option<usize>> {
        match t.get(key) {
            None => Ok(None),
            Some(Value::Integer(i)) if *i >= 0 => Ok(Some(*i as usize)),
            Some(v) => Err(err(format!("{key} = {v} must be a whole number >= 0"))),
        }
    };
    let centre_given = uint("centre_points")?;
    let names: Vec<&str> = factors.iter().map(|f| f.name.get_ref().as_str()).collect();
    let de = |e: design::DesignError| err(e.to_string());
    let (title, mut rows, default_centres) = match kind {
        "full_factorial" => {
            let default_levels = uint("levels")?.unwrap_or(2);
            let levels: Vec<usize> = factors
                .iter()
                .map(|f| f.level_count().unwrap_or(default_levels))
                .collect();
            let rows = design::full_factorial(&levels).map_err(de)?;
            let shape: Vec<String> = levels.iter().map(|l| l.to_string()).collect();
            (format!("full factorial {}", shape.join("x")), rows, 0)
        }
        "plackett_burman" => {
            let runs = match uint("runs")? {
                Some(r) => r,
                None => design::plackett_burman_size(k).map_err(de)?,
            };
            let rows = design::plackett_burman(runs, k).map_err(de)?;
            (format!("Plackett-Burman, {runs} runs"), rows, 0)
        }
        "box_behnken" => {
            let rows = design::box_behnken(k).map_err(de)?;
            let c = design::box_behnken_default_centres(k).unwrap_or(0);
            (format!("Box-Behnken, {} runs", rows.len()), rows, c)
        }
        "central_composite" => {
            let alpha = match t.get("alpha") {
                None => design::Alpha::Rotatable,
                Some(Value::String(s)) if s == "rotatable" => design::Alpha::Rotatable,
                Some(Value::String(s)) if s == "face_centred" || s == "face_centered" => {
                    design::Alpha::FaceCentred
                }
                Some(Value::Float(a)) => design::Alpha::Value(*a),
                Some(Value::Integer(a)) => design::Alpha::Value(*a as f64),
                Some(v) => {
                    return Err(err(format!(
                        "alpha = {v}: allowed \"rotatable\", \"face_centred\" or a number > 0"
                    )));
                }
            };
            let rows = design::central_composite(k, alpha).map_err(de)?;
            (
                format!(
                    "central composite, alpha = {:.4}, {} runs",
                    alpha.value(k),
                    rows.len()
                ),
                rows,
                0,
            )
        }
        "steepest_ascent" => {
            let coef = |key: &str, required: bool| -> Result<Vec<f64>> {
                let mut out = vec![0.0; k];
                let table = match t.get(key) {
                    Some(Value::Table(tab)) => tab,
                    None if !required => return Ok(out),
                    _ => {
                        return Err(err(format!(
                            "{key} must be a table of factor name -> number, e.g. {key} = {{ {} = 1.0 }}",
                            names[0]
                        )));
                    }
                };
                for (name, v) in table {
                    let j = names.iter().position(|n| n == name).ok_or_else(|| {
                        err(format!(
                            "{key}.{name}: unknown factor; the factors are {}",
                            names.join(", ")
                        ))
                    })?;
                    out[j] = match v {
                        Value::Float(x) => *x,
                        Value::Integer(x) => *x as f64,
                        _ => return Err(err(format!("{key}.{name} = {v} must be a number"))),
                    };
                }
                Ok(out)
            };
            let direction = coef("direction", true)?;
            let origin = coef("origin", false)?;
            let step = match t.get("step") {
                Some(Value::Float(x)) => *x,
                Some(Value::Integer(x)) => *x as f64,
                _ => return Err(err("needs `step`, a number (coded units)".into())),
            };
            let steps =
                uint("steps")?.ok_or_else(|| err("needs `steps`, a whole number".into()))?;
            let rows = design::steepest_ascent(&direction, &origin, step, steps).map_err(de)?;
            (format!("steepest-ascent path, {steps} points"), rows, 0)
        }
        ONE_SETTING => {
            if centre_given.is_some_and(|c| c > 0) {
                return Err(err(format!(
                    "centre_points: a type = \"{ONE_SETTING}\" design has no centre to add; give replicates"
                )));
            }
            let n = uint("replicates")?.unwrap_or(1);
            let title = if n == 1 {
                "one setting, 1 seed".to_string()
            } else {
                format!("one setting, {n} seeds")
            };
            (title, vec![vec![]], 0)
        }
        _ => {
            let runs = uint("runs")?.ok_or_else(|| err("needs `runs`, a whole number".into()))?;
            let seed = uint("seed")?.unwrap_or(1) as u64;
            let rows = if kind == "sobol" {
                design::sobol(runs, k, seed).map_err(de)?
            } else {
                design::latin_hypercube(runs, k, seed).map_err(de)?
            };
            let name = if kind == "sobol" {
                "Sobol' sequence"
            } else {
                "Latin hypercube"
            };
            (format!("{name}, {runs} runs"), rows, 0)
        }
    };
    if kind != "full_factorial" {
        if let Some(f) = factors.iter().find(|f| f.levels.is_some()) {
            return Err(source.err(
                &f.name.span(),
                format!(
                    "factor `{}` lists `levels`, which only a full_factorial design uses; give low and high",
                    f.name.get_ref()
                ),
            ));
        }
    }
    let centres = centre_given.unwrap_or(default_centres);
    rows = design::with_centre_points(rows, centres);
    let title = if centres > 0 {
        format!("{title} + {centres} centre points")
    } else {
        title
    };
    let replicates = uint("replicates")?.unwrap_or(1);
    if replicates == 0 {
        return Err(err(
            "replicates = 0 is out of range: allowed 1 or more".into()
        ));
    }
    let seed = uint("seed")?.unwrap_or(1) as u64;
    let n = rows.len();
    let order = match (t.get("run_order"), t.get("randomize")) {
        (Some(_), Some(Value::Boolean(true))) => {
            return Err(err("give run_order or randomize = true, not both".into()));
        }
        (Some(Value::Array(list)), _) => {
            let mut order = Vec::with_capacity(list.len());
            let mut seen = vec![false; n];
            for v in list {
                let std = match v {
                    Value::Integer(i) if (1..=n as i64).contains(i) => *i as usize,
                    _ => {
                        return Err(err(format!(
                            "run_order entry {v} is out of range: allowed 1 to {n} (standard order numbers)"
                        )));
                    }
                };
                if std::mem::replace(&mut seen[std - 1], true) {
                    return Err(err(format!("run_order lists standard run {std} twice")));
                }
                order.push(std - 1);
            }
            if order.len() != n {
                return Err(err(format!(
                    "run_order has {} entries; the design has {n} runs (with centre points)",
                    order.len()
                )));
            }
            order
        }
        (Some(v), _) => return Err(err(format!("run_order = {v} must be a list of numbers"))),
        (None, Some(Value::Boolean(true))) => {
            let mut order: Vec<usize> = (0..n).collect();
            order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
            order
        }
        (None, Some(Value::Boolean(false)) | None) => (0..n).collect(),
        (None, Some(v)) => return Err(err(format!("randomize = {v} must be true or false"))),
    };
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
