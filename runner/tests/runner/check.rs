//! `tilth check`: a measurement file's rows, and whether its direct shear and UCS rows can
//! come from one material (the Mohr-circle bound of `tilth_tools::consistency`).

use super::tilth_in_root;

/// Table 12's peak shear forces (N) and table 13's strengths (kPa), by (moisture %,
/// firmness MPa), read straight from the measurement file's columns.
fn shear_and_ucs() -> Vec<((f64, f64), f64, f64)> {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/li2022/measurements.csv"),
    )
    .unwrap();
    let mut shear = vec![];
    let mut ucs = vec![];
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        let key = (
            c[1].parse::<f64>().unwrap(),
            c[2].parse::<f64>().unwrap_or(f64::NAN),
        );
        let value: f64 = c[5].parse().unwrap();
        match c[0] {
            "direct_shear" => shear.push((key, value)),
            "ucs" => ucs.push((key, value)),
            _ => {}
        }
    }
    shear
        .into_iter()
        .map(|(k, f)| (k, f, ucs.iter().find(|(ku, _)| *ku == k).unwrap().1))
        .collect()
}

#[test]
fn the_study_s_shear_and_compression_tables_are_checked_against_one_another() {
    let out = tilth_in_root(&[
        "check",
        "data/li2022/measurements.csv",
        "--model",
        "models/li2022.toml",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["rows"], 20);
    let pairs = json["shear_ucs"].as_array().unwrap();
    let expected = shear_and_ucs();
    assert_eq!(pairs.len(), expected.len());
    // The bound written out here: a shear plane of pi (61.8 mm)^2 / 4 under 100 kPa carries
    // at least A sqrt(sigma (q - sigma)) in a soil of unconfined strength q.
    let area = std::f64::consts::PI * 0.0618 * 0.0618 / 4.0;
    let sigma = 1.0e5;
    let mut incompatible = 0;
    for ((moisture, firmness), force, ucs_kpa) in expected {
        let p = pairs
            .iter()
            .find(|p| {
                p["conditions"]["moisture_pct"] == moisture
                    && p["conditions"]["firmness_mpa"] == firmness
            })
            .unwrap_or_else(|| panic!("no pair at {moisture} %, {firmness} MPa"));
        let q = 1e3 * ucs_kpa;
        let least = if q > sigma {
            area * (sigma * (q - sigma)).sqrt()
        } else {
            0.0
        };
        let got = p["min_shear_force_n"].as_f64().unwrap();
        assert!(
            (got - least).abs() < 1e-9 * least.max(1.0),
            "{moisture} %, {firmness} MPa: {got} against {least}"
        );
        let one_material = force >= least;
        assert_eq!(
            p["compatible"], one_material,
            "{moisture} %, {firmness} MPa"
        );
        incompatible += usize::from(!one_material);
    }
    assert_eq!(json["shear_ucs_incompatible"], incompatible);
    // The study's numbers: 0.34 MPa and 3 % are weak enough in compression for their shear
    // peaks; at the other six conditions the strength asks for 1.7-2.7 times the measured
    // peak shear force.
    assert_eq!(incompatible, 6);
}

#[test]
fn the_bands_are_applied_and_refused_outside_their_range() {
    let out = tilth_in_root(&[
        "check",
        "data/li2022/measurements.csv",
        "--bands",
        "6.53,8.07",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("6 of 8 pairs cannot come from one material"),
        "{text}"
    );
    assert!(
        text.contains("Within the error bands given, 6 of them still cannot"),
        "{text}"
    );

    let bad = tilth_in_root(&["check", "data/li2022/measurements.csv", "--bands", "6.53"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--bands") && err.contains("[0, 100)"), "{err}");
}

#[test]
fn a_bad_measurement_file_is_refused_by_check_too() {
    let dir = std::env::temp_dir().join(format!("tilth-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.csv");
    std::fs::write(
        &file,
        "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty\n\
         ucs,6,1.55,,ucs_kpa,259.1,kPa,-1\n",
    )
    .unwrap();
    let out = tilth_in_root(&["check", file.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.csv") && err.contains("row 2") && err.contains("uncertainty"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_mohr_diagram_is_written_where_asked() {
    let dir = std::env::temp_dir().join(format!("tilth-check-plot-{}", std::process::id()));
    let out = tilth_in_root(&[
        "check",
        "data/li2022/measurements.csv",
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(dir.join("mohr.svg")).unwrap();
    // One point per (shear, UCS) pair of the file, each labelled by its conditions.
    assert_eq!(svg.matches("<circle").count(), 8);
    assert!(svg.contains("12 %, 1.55 MPa"), "labels missing");
    std::fs::remove_dir_all(&dir).ok();
}
