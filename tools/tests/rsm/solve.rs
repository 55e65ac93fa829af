//! Solving the fitted repose angle for each moisture's measured angle (table 1).

use super::*;
use tilth_tools::rsm::{fit, solve};

/// Table 9's angles with the real levels of table 9 (x4 restitution, x6 rolling friction,
/// x7 surface energy).
fn angle_fit() -> tilth_tools::rsm::Anova {
    let d = bbd("repose_angle_deg").from_coded(&[(0.25, 0.65), (0.15, 0.35), (0.125, 0.625)]);
    fit(&d, quadratic()).unwrap()
}

#[test]
fn one_angle_gives_a_ridge_of_rolling_friction_and_surface_energy() {
    let a = angle_fit();
    for (label, target) in [("3%", 32.76), ("6%", 35.53), ("9%", 37.89), ("12%", 43.87)] {
        let s = solve(&a, label, target, &[(0, 0.45)]).unwrap();
        assert!(!s.identifiable, "{label}");
        assert_eq!(s.dimension, 1);
        assert!(
            s.settings.len() > 50,
            "{label}: {} points",
            s.settings.len()
        );
        for st in &s.settings {
            assert!((st.predicted - target).abs() < 1e-8);
            assert!((a.predict(&st.values) - target).abs() < 1e-8);
            assert_eq!(st.values[0], 0.45);
        }
        // Along the ridge, more rolling friction needs less surface energy.
        let first = &s.settings[0].values;
        let last = &s.settings[s.settings.len() - 1].values;
        assert!(
            first[1] < last[1] && first[2] > last[2],
            "{label}: {first:?} -> {last:?}"
        );
        for (k, (name, lo, hi)) in s.extent.iter().enumerate().skip(1) {
            let range = a.coding.high[k] - a.coding.low[k];
            assert!(hi - lo > 0.3 * range, "{label}: {name} spans {lo}..{hi}");
        }
        assert!(
            s.statement.contains("one target cannot separate x6 and x7"),
            "{}",
            s.statement
        );
    }
}

#[test]
fn one_free_factor_is_pinned() {
    let a = angle_fit();
    let s = solve(&a, "6%", 35.53, &[(0, 0.45), (1, 0.25)]).unwrap();
    assert!(s.identifiable);
    assert_eq!(s.settings.len(), 1);
    assert!((a.predict(&s.settings[0].values) - 35.53).abs() < 1e-9);
}

#[test]
fn an_unreachable_target_reports_the_closest_setting() {
    let a = angle_fit();
    let s = solve(&a, "too high", 150.0, &[(0, 0.45)]).unwrap();
    assert!(s.settings.is_empty());
    let c = s.closest.unwrap();
    assert!(c.predicted < 150.0 && c.predicted > 60.0);
    assert!(
        s.statement
            .starts_with("no setting within the design's ranges predicts 150")
    );
}
