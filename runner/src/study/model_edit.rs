//! Edits of a model file that keep its comments (`toml_edit`): raise a parameter, give it a
//! slope along a condition, switch a candidate effect on. `diagnose` and `fit` build their
//! variants with these; every variant is loaded back, so the lab's checks refuse a bad one
//! before any run.

use crate::lab::model::Model;
use anyhow::{Context, Result, anyhow, bail};
use std::path::{Path, PathBuf};

/// A TOML number as f64.
fn number(v: &toml_edit::Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

/// Which array of a value table [`add_to`] shifts: every `y` of an `interpolate` table
/// (true: all of it) or the constant of a `polynomial`'s `coefficients` (false: the first).
fn varied_list(t: &toml_edit::InlineTable, label: &str) -> Result<(&'static str, bool)> {
    if t.contains_key("interpolate") {
        Ok(("y", true))
    } else if t.contains_key("polynomial") {
        Ok(("coefficients", false))
    } else {
        bail!("{label}: only a number, an interpolate, a polynomial or a cases table can be varied")
    }
}

/// The table a `HEAD.KEY` path names: `[particles]` for `particles.KEY` (the size mix;
/// created when missing); else `[pairs.HEAD]`, or `[bond.pairs.HEAD]` where only that one has
/// the key (bond stiffness and strength; the convention of `tilth calibrate --param`).
fn table_mut<'a>(
    doc: &'a mut toml_edit::DocumentMut,
    head: &str,
    key: &str,
) -> Result<&'a mut dyn toml_edit::TableLike> {
    if head == "particles" {
        if doc.get("particles").is_none() {
            doc.insert("particles", toml_edit::table());
        }
        return doc["particles"]
            .as_table_like_mut()
            .ok_or_else(|| anyhow!("[particles] is not a table"));
    }
    if in_bond_only(doc, head, key) {
        return doc["bond"]["pairs"][head]
            .as_table_like_mut()
            .ok_or_else(|| anyhow!("[bond.pairs.{head}] is not a table"));
    }
    doc["pairs"][head]
        .as_table_like_mut()
        .ok_or_else(|| anyhow!("the model has no [pairs.{head}]"))
}

/// Read-only twin of [`table_mut`]; `None` for a missing `[particles]`.
fn table<'a>(
    doc: &'a toml_edit::DocumentMut,
    head: &str,
    key: &str,
) -> Result<Option<&'a dyn toml_edit::TableLike>> {
    if head == "particles" {
        return Ok(doc.get("particles").and_then(|t| t.as_table_like()));
    }
    let path: &[&str] = if in_bond_only(doc, head, key) {
        &["bond", "pairs", head]
    } else {
        &["pairs", head]
    };
    let mut item = doc.as_item();
    for part in path {
        item = item
            .get(part)
            .ok_or_else(|| anyhow!("the model has no [{}]", path.join(".")))?;
    }
    Ok(item.as_table_like())
}

/// Whether `key` is in `[bond.pairs.PAIR]` and not in `[pairs.PAIR]`: where a `PAIR.KEY`
/// parameter lives (bond stiffness and strength), for every command that edits one.
pub fn in_bond_only(doc: &toml_edit::DocumentMut, pair: &str, key: &str) -> bool {
    let has = |item: Option<&toml_edit::Item>| item.and_then(|t| t.get(key)).is_some();
    !has(doc.get("pairs").and_then(|t| t.get(pair)))
        && has(doc
            .get("bond")
            .and_then(|t| t.get("pairs"))
            .and_then(|t| t.get(pair)))
}

/// Adds `delta` to `pairs.PAIR.KEY` (or `particles.KEY`, or `bond.pairs.PAIR.KEY` where only
/// the bond has it) of a model document: a number, each `y` of an `interpolate` table, the
/// constant of a `polynomial`, or each case's value of a `cases` table; a missing key becomes
/// `delta`.
pub fn add_to(doc: &mut toml_edit::DocumentMut, path: &str, delta: f64) -> Result<()> {
    let (pair, key) = path
        .split_once('.')
        .ok_or_else(|| anyhow!("`{path}`: expected PAIR.KEY"))?;
    let table = table_mut(doc, pair, key)?;
    let Some(item) = table.get_mut(key) else {
        table.insert(key, toml_edit::value(delta));
        return Ok(());
    };
    let v = item
        .as_value_mut()
        .ok_or_else(|| anyhow!("pairs.{pair}.{key} is not a value"))?;
    shift(v, delta, &format!("pairs.{pair}.{key}"))
}

/// Adds `delta` to every number [`numbers_in`] reads from a value form.
fn shift(v: &mut toml_edit::Value, delta: f64, label: &str) -> Result<()> {
    if let Some(x) = number(v) {
        *v = (x + delta).into();
        return Ok(());
    }
    let t = v
        .as_inline_table_mut()
        .ok_or_else(|| anyhow!("{label} cannot be varied"))?;
    if t.contains_key("cases") {
        let cases = t
            .get_mut("cases")
            .and_then(|a| a.as_array_mut())
            .ok_or_else(|| anyhow!("{label}.cases is not a list"))?;
        for (k, case) in cases.iter_mut().enumerate() {
            let value = case
                .as_inline_table_mut()
                .and_then(|c| c.get_mut("value"))
                .ok_or_else(|| anyhow!("{label}.cases[{k}] has no `value`"))?;
            shift(value, delta, &format!("{label}.cases[{k}].value"))?;
        }
        return Ok(());
    }
    let (list, all) = varied_list(t, label)?;
    let arr = t
        .get_mut(list)
        .and_then(|a| a.as_array_mut())
        .ok_or_else(|| anyhow!("{label}: no `{list}` array"))?;
    for k in 0..arr.len() {
        if k > 0 && !all {
            break;
        }
        let x = number(arr.get(k).unwrap())
            .ok_or_else(|| anyhow!("{label}.{list}[{k}] is not a number"))?;
        arr.replace(k, x + delta);
    }
    Ok(())
}

/// The numbers a value form holds that [`shift`] moves: the number, each `y` of an
/// `interpolate` table, the constant of a `polynomial`, those of every case's value.
fn numbers_in(v: &toml_edit::Value, label: &str) -> Result<Vec<f64>> {
    if let Some(x) = number(v) {
        return Ok(vec![x]);
    }
    let t = v
        .as_inline_table()
        .ok_or_else(|| anyhow!("{label} cannot be varied"))?;
    if let Some(cases) = t.get("cases") {
        let cases = cases
            .as_array()
            .ok_or_else(|| anyhow!("{label}.cases is not a list"))?;
        let mut all = Vec::new();
        for (k, case) in cases.iter().enumerate() {
            let value = case
                .as_inline_table()
                .and_then(|c| c.get("value"))
                .ok_or_else(|| anyhow!("{label}.cases[{k}] has no `value`"))?;
            all.extend(numbers_in(value, &format!("{label}.cases[{k}].value"))?);
        }
        return Ok(all);
    }
    let (list, all) = varied_list(t, label)?;
    let arr = t
        .get(list)
        .and_then(|a| a.as_array())
        .ok_or_else(|| anyhow!("{label}: no `{list}` array"))?;
    Ok(arr
        .iter()
        .take(if all { arr.len() } else { 1 })
        .filter_map(number)
        .collect())
}

/// Adds `slope * (c - mid)` to `pairs.PAIR.KEY` along condition `c` (mid the middle of its
/// range [lo, hi]): a number becomes an `interpolate` table over [lo, hi]; an `interpolate`
/// table over `c` gets the slope added at each of its points.
pub fn add_slope(
    doc: &mut toml_edit::DocumentMut,
    path: &str,
    cond: &str,
    lo: f64,
    hi: f64,
    slope: f64,
) -> Result<()> {
    let (pair, key) = path
        .split_once('.')
        .ok_or_else(|| anyhow!("`{path}`: expected PAIR.KEY"))?;
    let mid = 0.5 * (lo + hi);
    let table = table_mut(doc, pair, key)?;
    let current = table.get(key).and_then(|i| i.as_value().cloned());
    let base = match &current {
        None => Some(0.0),
        Some(v) => number(v),
    };
    if let Some(b) = base {
        let mut t = toml_edit::InlineTable::new();
        t.insert("interpolate", cond.into());
        t.insert("x", toml_edit::Value::Array([lo, hi].into_iter().collect()));
        t.insert(
            "y",
            toml_edit::Value::Array(
                [b + slope * (lo - mid), b + slope * (hi - mid)]
                    .into_iter()
                    .collect(),
            ),
        );
        table.insert(key, toml_edit::value(t));
        return Ok(());
    }
    let mut v = current.unwrap();
    let t = v
        .as_inline_table_mut()
        .filter(|t| t.get("interpolate").and_then(|c| c.as_str()) == Some(cond))
        .ok_or_else(|| {
            anyhow!("pairs.{pair}.{key}: only a number or an interpolate table over {cond} can take a slope along {cond}")
        })?;
    let xs: Vec<f64> = t
        .get("x")
        .and_then(|a| a.as_array())
        .map(|a| a.iter().filter_map(number).collect())
        .unwrap_or_default();
    let ys = t
        .get_mut("y")
        .and_then(|a| a.as_array_mut())
        .ok_or_else(|| anyhow!("pairs.{pair}.{key}: no `y` array"))?;
    if xs.len() != ys.len() {
        bail!("pairs.{pair}.{key}: x and y differ in length");
    }
    for (k, x) in xs.iter().enumerate() {
        let y = number(ys.get(k).unwrap())
            .ok_or_else(|| anyhow!("pairs.{pair}.{key}.y[{k}] is not a number"))?;
        ys.replace(k, y + slope * (x - mid));
    }
    table.insert(key, toml_edit::value(v));
    Ok(())
}

/// The model with candidate `name` switched on at `strength`.
pub fn switch_on(
    doc: &mut toml_edit::DocumentMut,
    model: &Model,
    name: &str,
    strength: f64,
) -> Result<()> {
    let c = &model.file.candidates[name];
    if let Some(law) = &c.extra {
        let contact = doc["contact"]
            .as_table_like_mut()
            .ok_or_else(|| anyhow!("the model has no [contact]"))?;
        if contact.get("extra").is_none() {
            contact.insert("extra", toml_edit::value(toml_edit::Array::new()));
        }
        let arr = contact
            .get_mut("extra")
            .and_then(|e| e.as_array_mut())
            .ok_or_else(|| anyhow!("contact.extra is not a list"))?;
        if !arr.iter().any(|v| v.as_str() == Some(law)) {
            arr.push(law.as_str());
        }
    }
    for (pair, values) in &c.pairs {
        let table = doc["pairs"][pair.as_str()]
            .as_table_like_mut()
            .ok_or_else(|| {
                anyhow!("candidates.{name}.pairs.{pair}: the model has no [pairs.{pair}]")
            })?;
        for (k, v) in values {
            let parsed: toml_edit::Value = v
                .to_string()
                .parse()
                .with_context(|| format!("candidates.{name}.pairs.{pair}.{k}"))?;
            table.insert(k, toml_edit::value(parsed));
        }
    }
    for path in &c.strength {
        match &c.along {
            None => add_to(doc, path, strength),
            Some(cond) => {
                let [lo, hi] = *model.file.conditions.get(cond).ok_or_else(|| {
                    anyhow!(
                        "candidates.{name}.along = \"{cond}\": the model has no such condition; it has {}",
                        model.file.conditions.keys().cloned().collect::<Vec<_>>().join(", ")
                    )
                })?;
                add_slope(doc, path, cond, lo, hi, strength)
            }
        }
        .with_context(|| format!("candidates.{name}.strength"))?;
    }
    Ok(())
}

/// Writes a variant of the model file and returns its path.
pub fn variant(
    model: &Model,
    text: &str,
    dir: &Path,
    name: &str,
    edit: impl FnOnce(&mut toml_edit::DocumentMut) -> Result<()>,
) -> Result<PathBuf> {
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", model.path.display()))?;
    edit(&mut doc).with_context(|| format!("{}: variant {name}", model.path.display()))?;
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, doc.to_string())?;
    // Refuse a variant the lab would refuse, before any run.
    Model::load(&path).with_context(|| format!("variant {name}"))?;
    Ok(path)
}

/// An error unless the model file has `[candidates.NAME]`, naming the ones it has; `what`
/// says which argument asked (`--param "candidate.x=0:1"`).
pub fn has_candidate(model: &Model, name: &str, what: &str) -> Result<()> {
    if model.file.candidates.contains_key(name) {
        return Ok(());
    }
    let all: Vec<&str> = model.file.candidates.keys().map(String::as_str).collect();
    bail!(
        "{what}: {} has no [candidates.{name}]; it has {}",
        model.path.display(),
        all.join(", ")
    )
}

/// The numbers `pairs.PAIR.KEY` holds (see [`add_to`] for where it looks); a missing key
/// holds 0. What [`add_to`] shifts.
pub fn values_of(doc: &toml_edit::DocumentMut, path: &str) -> Result<Vec<f64>> {
    let (pair, key) = path
        .split_once('.')
        .ok_or_else(|| anyhow!("`{path}`: expected PAIR.KEY"))?;
    let Some(table) = table(doc, pair, key)? else {
        return Ok(vec![0.0]);
    };
    match table.get(key).and_then(|i| i.as_value()) {
        None => Ok(vec![0.0]),
        Some(v) => numbers_in(v, &format!("pairs.{pair}.{key}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc() -> toml_edit::DocumentMut {
        "[pairs.soil-soil]\nfriction = 0.8\nrolling = { interpolate = \"moisture_pct\", x = [3, 6, 12], y = [0.1, 0.2, 0.4] }\npoly = { polynomial = \"moisture_pct\", coefficients = [1.0, 2.0] }\n"
            .parse()
            .unwrap()
    }

    #[test]
    fn particles_keys_go_to_the_particles_table() {
        let mut d = doc();
        assert_eq!(values_of(&d, "particles.fine_fraction").unwrap(), vec![0.0]);
        add_to(&mut d, "particles.fine_fraction", 0.1).unwrap();
        add_to(&mut d, "particles.fine_fraction", 0.05).unwrap();
        assert_eq!(d["particles"]["fine_fraction"].as_float(), Some(0.1 + 0.05));
        assert_eq!(
            values_of(&d, "particles.fine_fraction").unwrap(),
            vec![0.1 + 0.05]
        );
        assert!(d["pairs"].get("particles").is_none());
    }

    fn value(d: &toml_edit::DocumentMut, key: &str) -> String {
        d["pairs"]["soil-soil"][key].as_value().unwrap().to_string()
    }

    #[test]
    fn add_to_raises_numbers_tables_and_polynomial_constants() {
        let mut d = doc();
        add_to(&mut d, "soil-soil.friction", 0.25).unwrap();
        add_to(&mut d, "soil-soil.rolling", 0.5).unwrap();
        add_to(&mut d, "soil-soil.poly", 0.5).unwrap();
        add_to(&mut d, "soil-soil.new_key", 0.125).unwrap();
        assert_eq!(d["pairs"]["soil-soil"]["friction"].as_float(), Some(1.05));
        assert!(
            value(&d, "rolling").contains("y = [0.6, 0.7, 0.9]"),
            "{}",
            value(&d, "rolling")
        );
        assert!(
            value(&d, "poly").contains("coefficients = [1.5, 2.0]"),
            "{}",
            value(&d, "poly")
        );
        assert_eq!(d["pairs"]["soil-soil"]["new_key"].as_float(), Some(0.125));
        assert!(add_to(&mut d, "soil-steel.friction", 0.1).is_err());
    }

    fn ys(d: &toml_edit::DocumentMut, key: &str) -> Vec<f64> {
        d["pairs"]["soil-soil"][key]["y"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect()
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn add_slope_tilts_about_the_middle_of_the_range() {
        let mut d = doc();
        // Range [3, 12], middle 7.5: a number becomes a two-point table.
        add_slope(
            &mut d,
            "soil-soil.friction",
            "moisture_pct",
            3.0,
            12.0,
            0.02,
        )
        .unwrap();
        assert!(value(&d, "friction").contains("x = [3.0, 12.0]"));
        assert!(
            close(&ys(&d, "friction"), &[0.8 - 0.09, 0.8 + 0.09]),
            "{:?}",
            ys(&d, "friction")
        );
        // A table over the same condition: each point tilted (3: -0.09, 6: -0.03, 12: +0.09).
        add_slope(&mut d, "soil-soil.rolling", "moisture_pct", 3.0, 12.0, 0.02).unwrap();
        assert!(
            close(&ys(&d, "rolling"), &[0.1 - 0.09, 0.2 - 0.03, 0.4 + 0.09]),
            "{:?}",
            ys(&d, "rolling")
        );
        // A polynomial cannot take a slope.
        assert!(add_slope(&mut d, "soil-soil.poly", "moisture_pct", 3.0, 12.0, 0.02).is_err());
    }

    #[test]
    fn bond_keys_and_cases_tables_are_shifted_where_the_model_has_them() {
        let mut d: toml_edit::DocumentMut = concat!(
            "[pairs.soil-soil]\nfriction = 0.8\n",
            "[bond.pairs.soil-soil]\nnormal_stiffness_per_area = 1.0e8\n",
            "critical_shear_stress = { cases = [\n",
            "  { when = { moisture_pct = 6 }, value = { interpolate = \"firmness_mpa\", x = [0.34, 2.76], y = [16500.0, 62600.0] } },\n",
            "  { when = { firmness_mpa = 1.55 }, value = 58700.0 },\n",
            "] }\n",
        )
        .parse()
        .unwrap();
        assert_eq!(
            values_of(&d, "soil-soil.critical_shear_stress").unwrap(),
            vec![16500.0, 62600.0, 58700.0]
        );
        add_to(&mut d, "soil-soil.critical_shear_stress", 1000.0).unwrap();
        add_to(&mut d, "soil-soil.normal_stiffness_per_area", 1.0e8).unwrap();
        assert_eq!(
            values_of(&d, "soil-soil.critical_shear_stress").unwrap(),
            vec![17500.0, 63600.0, 59700.0]
        );
        assert_eq!(
            d["bond"]["pairs"]["soil-soil"]["normal_stiffness_per_area"].as_float(),
            Some(2.0e8)
        );
        // Nothing leaked into [pairs.soil-soil]; a key neither table has goes there.
        assert!(
            d["pairs"]["soil-soil"]
                .get("critical_shear_stress")
                .is_none()
        );
        add_to(&mut d, "soil-soil.twisting_friction", 0.5).unwrap();
        assert_eq!(
            d["pairs"]["soil-soil"]["twisting_friction"].as_float(),
            Some(0.5)
        );
        // The conditions of each case are kept.
        let text = d.to_string();
        assert!(text.contains("when = { moisture_pct = 6 }"), "{text}");
        assert!(text.contains("when = { firmness_mpa = 1.55 }"), "{text}");
    }

    #[test]
    fn values_of_reads_what_add_to_shifts() {
        let d = doc();
        assert_eq!(values_of(&d, "soil-soil.friction").unwrap(), vec![0.8]);
        assert_eq!(
            values_of(&d, "soil-soil.rolling").unwrap(),
            vec![0.1, 0.2, 0.4]
        );
        assert_eq!(values_of(&d, "soil-soil.poly").unwrap(), vec![1.0]);
        assert_eq!(values_of(&d, "soil-soil.missing").unwrap(), vec![0.0]);
        assert!(values_of(&d, "soil-steel.friction").is_err());
    }
}
