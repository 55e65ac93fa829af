//! Tables 6, 7 and 9 of the reference study.

use super::*;
use tilth_tools::rsm::{compare_reported, fit};

fn pb() -> (Data, FitOptions) {
    let t = Table::read(study("table06_pb_runs.csv")).unwrap();
    let factors: Vec<String> = (1..=7).map(|i| format!("x{i}")).collect();
    let data = Data::from_table(&t, &factors, "repose_angle_deg", None).unwrap();
    let options = FitOptions {
        order: Order::Linear,
        curvature: true,
        backward: None,
    };
    (data, options)
}

#[test]
fn table6_matches_statsmodels() {
    let (data, options) = pb();
    let a = fit(&data, options).unwrap();
    let g = &golden()["table06"];
    assert!(close(
        a.intercept,
        g["coefficients"]["Intercept"].as_f64().unwrap(),
        1e-10
    ));
    for t in &a.terms {
        let name = t.name.as_str();
        assert!(
            close(
                t.coefficient,
                g["coefficients"][name].as_f64().unwrap(),
                1e-10
            ),
            "{name}"
        );
        assert!(
            close(t.sum_sq, g["sum_sq"][name].as_f64().unwrap(), 1e-9),
            "{name}"
        );
        assert!(
            close(t.p.unwrap(), g["p"][name].as_f64().unwrap(), 1e-8),
            "{name}"
        );
    }
    assert!(close(
        a.residual.sum_sq,
        g["residual_sum_sq"].as_f64().unwrap(),
        1e-10
    ));
    assert_eq!(a.residual.df, 6);
    assert!(close(a.r2, g["r2"].as_f64().unwrap(), 1e-12));
    assert!(close(
        a.adj_r2.unwrap(),
        g["adj_r2"].as_f64().unwrap(),
        1e-12
    ));
    assert!(close(
        a.pred_r2.unwrap(),
        g["pred_r2"].as_f64().unwrap(),
        1e-10
    ));
    // Three centre points: 2 pure-error df, 4 lack-of-fit df.
    assert_eq!(a.pure_error.as_ref().unwrap().df, 2);
    assert_eq!(a.lack_of_fit.as_ref().unwrap().df, 4);
}

/// Table 7 reproduces within the rounding of table 6's printed angles, except x4's p-value
/// (printed 0.007; the data give 0.0022), which the check must report.
#[test]
fn table7_reproduces_except_x4() {
    let (data, options) = pb();
    let a = fit(&data, options).unwrap();
    let reported = Table::read(study("table07_pb_anova_reported.csv")).unwrap();
    let checks = compare_reported(&a, &data, options, &reported, None).unwrap();
    let sum_sq_or_p = checks
        .iter()
        .filter(|c| c.field == "mean_sq" || c.field == "p")
        .count();
    assert!(
        sum_sq_or_p >= 18,
        "every term's mean square and p-value is checked"
    );
    let differ: Vec<(String, String)> = checks
        .iter()
        .filter(|c| !c.agrees)
        .map(|c| (c.source.clone(), c.field.clone()))
        .collect();
    assert_eq!(differ, vec![("x4".to_string(), "p".to_string())]);
    let x4 = checks
        .iter()
        .find(|c| c.source == "x4" && c.field == "p")
        .unwrap();
    let v = x4.computed.unwrap();
    assert!((0.0021..0.0023).contains(&v), "x4 p = {v}");
}

/// The check is not a rubber stamp: a table 7 with a wrong sum of squares fails it.
#[test]
fn a_wrong_reported_value_is_flagged() {
    let (data, options) = pb();
    let a = fit(&data, options).unwrap();
    let mut reported = Table::read(study("table07_pb_anova_reported.csv")).unwrap();
    let ms = reported.column("mean_square").unwrap();
    let x6 = reported.rows.iter().position(|r| r[0] == "x6").unwrap();
    reported.rows[x6][ms] = "1835.89".into();
    let checks = compare_reported(&a, &data, options, &reported, None).unwrap();
    assert!(
        checks
            .iter()
            .any(|c| c.source == "x6" && c.field == "mean_sq" && !c.agrees)
    );
}

/// Equations (10)-(13): each moisture's quadratic in coded units, against statsmodels to
/// 1e-9 (the issue asks 0.01 against the printed equations), and R^2 as the issue gives them.
#[test]
fn table9_quadratics() {
    let g = golden();
    for (m, r2) in [(3, 0.9495), (6, 0.9575), (9, 0.9646), (12, 0.9543)] {
        let key = format!("err_{m}pct");
        let a = fit(&bbd(&key), quadratic()).unwrap();
        let g = &g[format!("table09_{key}")];
        assert!(close(
            a.intercept,
            g["coefficients"]["Intercept"].as_f64().unwrap(),
            1e-9
        ));
        assert_eq!(a.terms.len(), 9);
        for t in &a.terms {
            let want = g["coefficients"][t.name.as_str()].as_f64().unwrap();
            assert!(
                (t.coefficient - want).abs() < 1e-9,
                "{key} {}: {} vs {want}",
                t.name,
                t.coefficient
            );
            let p = g["p"][t.name.as_str()].as_f64().unwrap();
            assert!(close(t.p.unwrap(), p, 1e-7), "{key} {}", t.name);
        }
        assert_eq!(format!("{:.4}", a.r2), format!("{r2:.4}"), "{key}");
        assert!(close(
            a.pred_r2.unwrap(),
            g["pred_r2"].as_f64().unwrap(),
            1e-9
        ));
    }
}

/// The equation in real units is the coded one with z = (x - centre) / half-range.
#[test]
fn real_equation_is_the_coded_one_substituted() {
    let d = bbd("err_6pct").from_coded(&[(0.25, 0.65), (0.15, 0.35), (0.125, 0.625)]);
    let a = fit(&d, quadratic()).unwrap();
    let eval = |x: &[f64]| {
        a.real_coefficients
            .iter()
            .map(|(name, b)| {
                let v = |n: &str| x[["x4", "x6", "x7"].iter().position(|f| *f == n).unwrap()];
                b * match name.as_str() {
                    "intercept" => 1.0,
                    n if n.ends_with("^2") => v(&n[..2]).powi(2),
                    n if n.contains('*') => v(&n[..2]) * v(&n[3..]),
                    n => v(n),
                }
            })
            .sum::<f64>()
    };
    for x in [[0.3, 0.2, 0.4], [0.45, 0.25, 0.375], [0.6, 0.34, 0.15]] {
        let z = a.coding.code(&x);
        assert!((eval(&x) - a.predict_coded(&z)).abs() < 1e-9);
    }
}

/// Backward elimination on table 6 keeps the three factors the study kept.
#[test]
fn backward_elimination_keeps_x4_x6_x7() {
    let (data, mut options) = pb();
    options.backward = Some(0.1);
    let a = fit(&data, options).unwrap();
    let kept: Vec<&str> = a.terms.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(kept, ["x4", "x6", "x7", "curvature"]);
    assert_eq!(a.removed.len(), 4);
    assert!(a.removed.iter().all(|(_, p)| *p > 0.1));
}

/// Table 8's path, scored against the four moistures' measured angles (table 1), gives the
/// study's Box-Behnken ranges (table 9's levels) with two rows either side of the best run.
#[test]
fn table8_path_leads_to_table9_ranges() {
    use tilth_tools::rsm::next_region;
    let path = Table::read(study("table08_steepest_ascent.csv")).unwrap();
    let measured = Table::read(study("table01_friction_repose.csv")).unwrap();
    let targets = measured.numbers("repose_angle_deg").unwrap();
    let factors = strings(&["x4", "x6", "x7"]);
    let r = next_region(&path, &factors, "repose_angle_deg", &targets, 2).unwrap();
    assert_eq!(r.best_row, 3, "run 4 of table 8");
    let levels = Table::read(study("table09_bbd_levels.csv")).unwrap();
    let (lo, mid, hi) = (
        levels.numbers("minus1").unwrap(),
        levels.numbers("zero").unwrap(),
        levels.numbers("plus1").unwrap(),
    );
    for k in 0..3 {
        assert!((r.low[k] - lo[k]).abs() < 1e-12 && (r.high[k] - hi[k]).abs() < 1e-12);
        assert!((r.centre[k] - mid[k]).abs() < 1e-12);
    }
}

/// The steepest-ascent path from table 6's screening fit follows its coefficients: the
/// leading factor moves one step per point, the others in proportion, and the first-order
/// prediction rises by step * |b_max| + the others' share per point.
#[test]
fn steepest_path_follows_the_screening_coefficients() {
    use tilth_tools::rsm::steepest_path;
    let (data, options) = pb();
    let a = fit(&data, options).unwrap();
    let p = steepest_path(&a, &[3, 5, 6], 0.5, 5, false).unwrap();
    let b: Vec<f64> = [3, 5, 6].iter().map(|&i| a.terms[i].coefficient).collect();
    let bmax = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let rise = 0.5 * b.iter().map(|v| v * v).sum::<f64>() / bmax;
    for (k, z) in p.coded.iter().enumerate() {
        assert!((z[6] - 0.5 * k as f64).abs() < 1e-12, "x7 leads");
        assert!((z[3] - 0.5 * k as f64 * b[0] / bmax).abs() < 1e-12);
        assert_eq!(z[0], 0.0);
        assert!((p.predicted[k] - a.intercept - rise * k as f64).abs() < 1e-9);
    }
}

/// Table 9 prints 14 of its 15 runs; one centre run is missing. Searching the centre run's
/// angle so that the four fits' R^2 match table 10's printed R^2 finds one angle for all four
/// moistures (about 40.89 degrees), and with that run every other value of table 10, 48 in
/// all (each term's p-value, lack of fit, adequate precision), agrees too: an independent
/// check of the p-values, lack-of-fit test and adequate precision against Design-Expert's.
#[test]
fn table10_reproduces_with_the_missing_centre_run() {
    let base = Table::read(study("table09_bbd_runs.csv")).unwrap();
    let measured = Table::read(study("table01_friction_repose.csv")).unwrap();
    let angles = measured.numbers("repose_angle_deg").unwrap();
    let moistures = [3, 6, 9, 12];
    let reported = Table::read(study("table10_bbd_anova_reported.csv")).unwrap();
    let r2_reported: Vec<f64> = moistures
        .iter()
        .map(|m| {
            let c = reported.column(&format!("p_{m}pct")).unwrap();
            let row = reported
                .rows
                .iter()
                .position(|r| r[0] == "r_squared")
                .unwrap();
            reported.rows[row][c].parse().unwrap()
        })
        .collect();
    // Table 9 with a 15th run at the centre with angle `a`, its errors printed as table 9's.
    let with_centre = |a: f64| {
        let mut t = base.clone();
        let mut row = vec![
            "15".to_string(),
            "0".into(),
            "0".into(),
            "0".into(),
            format!("{a:.2}"),
        ];
        row.extend(angles.iter().map(|m| format!("{:.4}", (a - m).abs() / m)));
        t.rows.push(row);
        t.lines.push(16);
        t
    };
    let fit_at = |t: &Table, m: i32| {
        let d = Data::from_table(
            t,
            &strings(&["x4_coded", "x6_coded", "x7_coded"]),
            &format!("err_{m}pct"),
            None,
        )
        .unwrap()
        .renamed(&strings(&["x4", "x6", "x7"]))
        .unwrap();
        (fit(&d, quadratic()).unwrap(), d)
    };
    let mismatch = |a: f64| {
        let t = with_centre(a);
        moistures
            .iter()
            .zip(&r2_reported)
            .map(|(m, r)| (fit_at(&t, *m).0.r2 - r).powi(2))
            .sum::<f64>()
    };
    let best = (3000..5000)
        .map(|k| k as f64 / 100.0)
        .min_by(|a, b| mismatch(*a).total_cmp(&mismatch(*b)))
        .unwrap();
    assert!(
        (40.5..41.3).contains(&best),
        "the missing centre run: {best} degrees"
    );
    let t = with_centre(best);
    let mut checked = 0;
    for m in moistures {
        let (a, d) = fit_at(&t, m);
        let checks =
            compare_reported(&a, &d, quadratic(), &reported, Some(&format!("p_{m}pct"))).unwrap();
        for c in &checks {
            assert!(
                c.agrees,
                "{m} %: {} {} reported {} computed {:?}",
                c.source, c.field, c.reported, c.computed
            );
        }
        checked += checks.len();
    }
    assert_eq!(checked, 52);
}
