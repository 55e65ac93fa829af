//! Factor targets: a dotted path into the scene's TOML where a value is set.
//!
//! `simulation.duration`, `materials.soil.density`, `pairs[soil-steel].friction` (a pair
//! picked by its two materials, in either order), `walls[floor].radius` (a table picked by
//! its `name`), `factories[0].count` (by index). The last key may be new (a parameter the
//! scene leaves at its default); everything before it must exist.

use anyhow::{Result, anyhow, bail};
use toml::Value;

/// One step of a path: a key, optionally followed by a selector into an array of tables.
#[derive(Debug, PartialEq)]
struct Step<'a> {
    key: &'a str,
    select: Option<&'a str>,
}

fn steps(path: &str) -> Result<Vec<Step<'_>>> {
    let mut out = vec![];
    for part in path.split('.') {
        let step = match part.split_once('[') {
            Some((key, rest)) => {
                let sel = rest
                    .strip_suffix(']')
                    .ok_or_else(|| anyhow!("`{part}` opens `[` without closing it"))?;
                Step {
                    key,
                    select: Some(sel),
                }
            }
            None => Step {
                key: part,
                select: None,
            },
        };
        if step.key.is_empty() || step.select.is_some_and(str::is_empty) {
            bail!("`{path}` has an empty part; write keys separated by dots");
        }
        out.push(step);
    }
    Ok(out)
}

/// Whether table `t` is the one `sel` names: its `name`, or its `materials` pair.
fn matches(t: &toml::Table, sel: &str) -> bool {
    if t.get("name").and_then(Value::as_str) == Some(sel) {
        return true;
    }
    if let Some(Value::Array(m)) = t.get("materials") {
        let m: Vec<&str> = m.iter().filter_map(Value::as_str).collect();
        if m.len() == 2 {
            return sel == format!("{}-{}", m[0], m[1]) || sel == format!("{}-{}", m[1], m[0]);
        }
    }
    false
}

/// Sets `value` at `path` in `root`.
pub fn set(root: &mut Value, path: &str, value: Value) -> Result<()> {
    let steps = steps(path)?;
    let mut here = root;
    let mut walked = String::new();
    for (k, step) in steps.iter().enumerate() {
        let last = k + 1 == steps.len();
        let table = here
            .as_table_mut()
            .ok_or_else(|| anyhow!("`{walked}` is not a table"))?;
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(step.key);
        if last && step.select.is_none() {
            table.insert(step.key.to_string(), value);
            return Ok(());
        }
        let child = table
            .get_mut(step.key)
            .ok_or_else(|| anyhow!("the scene has no `{walked}`"))?;
        here = match step.select {
            None => child,
            Some(sel) => {
                let list = child.as_array_mut().ok_or_else(|| {
                    anyhow!("`{walked}` is not a list, so `[{sel}]` cannot pick from it")
                })?;
                let len = list.len();
                let pos = match sel.parse::<usize>() {
                    Ok(i) if i < len => i,
                    Ok(i) => bail!("`{walked}[{i}]`: the scene has {len} entries (0-based)"),
                    Err(_) => list
                        .iter()
                        .position(|v| v.as_table().is_some_and(|t| matches(t, sel)))
                        .ok_or_else(|| {
                            anyhow!(
                                "`{walked}[{sel}]`: no entry has name `{sel}` or materials `{sel}`"
                            )
                        })?,
                };
                walked.push_str(&format!("[{sel}]"));
                &mut list[pos]
            }
        };
        if last {
            *here = value;
            return Ok(());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Value {
        toml::from_str(
            r#"
            [simulation]
            dt = 1e-5
            [[pairs]]
            materials = ["soil", "steel"]
            friction = 0.5
            [[walls]]
            name = "floor"
            radius = 1.0
            "#,
        )
        .unwrap()
    }

    #[test]
    fn paths_reach_tables_pairs_and_named_walls() {
        let mut s = scene();
        set(&mut s, "simulation.duration", Value::Float(0.3)).unwrap();
        set(&mut s, "pairs[steel-soil].friction", Value::Float(0.7)).unwrap();
        set(&mut s, "walls[floor].radius", Value::Float(2.0)).unwrap();
        set(&mut s, "walls[0].length", Value::Float(3.0)).unwrap();
        assert_eq!(s["simulation"]["duration"].as_float(), Some(0.3));
        assert_eq!(s["pairs"][0]["friction"].as_float(), Some(0.7));
        assert_eq!(s["walls"][0]["radius"].as_float(), Some(2.0));
        assert_eq!(s["walls"][0]["length"].as_float(), Some(3.0));
    }

    #[test]
    fn missing_parents_are_named() {
        let mut s = scene();
        let e = set(&mut s, "pairs[soil-clay].friction", Value::Float(0.1)).unwrap_err();
        assert!(
            e.to_string().contains("no entry has name `soil-clay`"),
            "{e}"
        );
        let e = set(&mut s, "output.every.x", Value::Float(0.1)).unwrap_err();
        assert!(e.to_string().contains("no `output`"), "{e}");
        let e = set(&mut s, "walls[3].radius", Value::Float(0.1)).unwrap_err();
        assert!(e.to_string().contains("1 entries"), "{e}");
    }
}
