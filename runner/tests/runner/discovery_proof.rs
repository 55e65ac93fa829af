//! The discovery loop proven on synthetic data at the coarse preset (docs/discovery-proof.md, "The
//! proof with simulations"), through the scripts a user runs. The slow tier: every test here
//! is `#[ignore]`d and runs with `cargo test --workspace --release -- --ignored` (about 27
//! minutes on 2 cores; one run cache serves all, so the model's own runs are made once).
//!
//! The data are one realisation of the noise and of the grains' chaos, and any change of the
//! kernel's rounding redraws the chaos, so each bar is set on several draws and from the
//! measured rate at which a correct program meets it, such that it passes with probability
//! at least 0.999 (binomial tails, `P(X >= k | n, p)`):
//!
//! - a hidden fine fraction (0.15) and hidden wall adhesion (0.02): `diagnose` ranks the
//!   hidden effect first with a corrected p below 0.01 on every draw measured so far (32 of
//!   32 for each, over three builds whose chaos differs); at the rule-of-succession rate
//!   p = 33/34 = 0.97, "at least 4 of 8 draws" fails with probability 1.1e-6. A diagnosis
//!   that named it only as often as the null study's false alarms (0.05) would pass with
//!   probability 3.7e-4;
//! - hidden plastic adhesion (0.04): with funnel-only readings its signature is close to a
//!   higher rolling friction's (the free parameter) and to the other adhesions', so it is
//!   rarely significant, and the loop must not name something else. On seeds 3-22 it is
//!   ranked first among the effects on 17 of 20 draws (with and without the model's probes;
//!   a held surface energy or restitution, which it resembles on the funnel, ranks above it
//!   on 10 of them) and no verdict names an effect (ambiguous sets that hold it, no effect,
//!   none of the candidates). "At least 6 of 20 first among the effects" fails with
//!   probability 3.1e-4 at a rate of 0.65, below the measured rate's 95 % lower bound
//!   (0.66). A verdict names a candidate
//!   the data do not call for at a Holm-corrected rate of at most 0.01 a draw: "at most 2
//!   of 20 wrong" fails with probability 1.0e-3;
//! - after `fit` on the first draw where the fine fraction is ranked first, the data no
//!   longer reject the model: over the study's 16 rows, chi^2 = sum z_i^2 (`tilth compare`'s
//!   z-scores) has P(chi^2_16 > chi^2) >= ALPHA = 1e-6, and it is below the chi^2 before the
//!   fit. The scatters in z are sampled from 4 runs, so the statistic's tail is heavier than
//!   chi^2's: `tools/discovery/criterion_odds.py STUDY --chi2-test 4 --alpha 1e-6` puts the
//!   chance that a fit that found the truth fails at 2e-4 for the fine-fraction study (at
//!   ALPHA = 0.001 it was 0.008);
//! - data the model itself made (no hidden effect), 20 seeds: at most 5 raise an alarm. With
//!   the Holm-corrected 5 % level the per-seed rate is at most about 0.05 (0 of 20 seeds
//!   measured), and 6 or more of 20 then has probability 3.3e-4 (0.011 at a rate of 0.1);
//!   a rate of 0.5 passes with probability 0.021.

use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// Draws of the data for the effects that are found on every draw so far.
const DRAWS_CLEAR: u64 = 8;
/// Draws of the data for hidden plastic adhesion (module docs).
const DRAWS_PLASTIC: u64 = 20;
/// Hidden plastic adhesion: the fewest draws ranking it first among the effects, the most
/// naming a wrong effect (module docs).
const PLASTIC_LEAST_FIRST: usize = 6;
const PLASTIC_MOST_WRONG: usize = 2;
/// The significance below which the data reject the fitted model (module docs).
const ALPHA: f64 = 1e-6;
/// Seeds of the null study and the most of them that may raise an alarm (module docs).
const NULL_SEEDS: usize = 20;
const NULL_MOST_ALARMS: usize = 5;

/// One study at a time: they share the cache, and each uses both cores.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scratch() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("discovery-proof")
}

/// The run cache, emptied once per test process (it is keyed by the model's content, not by
/// the build: runs of an older tilth must not be reused).
fn cache() -> PathBuf {
    static FRESH: OnceLock<PathBuf> = OnceLock::new();
    FRESH
        .get_or_init(|| {
            let c = scratch().join("cache");
            let _ = std::fs::remove_dir_all(&c);
            c
        })
        .clone()
}

fn script(name: &str, args: &[&str]) {
    let o = Command::new("bash")
        .arg(root().join("tools/discovery").join(name))
        .args(args)
        .env("TILTH", env!("CARGO_BIN_EXE_tilth"))
        .env("CACHE", cache())
        // The truth's own compare (OUT/5-truth), the yardstick of a draw no model can follow.
        .env("TRUTH", "1")
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{name} {args:?}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("{name} {args:?}:\n{}", String::from_utf8_lossy(&o.stdout));
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(
        &std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
    .unwrap()
}

/// A compare's chi^2 over all its rows: the sum of its readings' `sum z_i^2`, the number of
/// rows, and P(chi^2_rows > chi^2).
fn chi2(compare: &serde_json::Value) -> (f64, usize, f64) {
    let (mut x, mut n) = (0.0, 0);
    for v in compare["verdicts"].as_array().unwrap() {
        x += v["chi2"][0].as_f64().unwrap_or_else(|| {
            panic!(
                "{}: no chi^2 (rows without an uncertainty?)",
                v["observable"]
            )
        });
        n += v["n"].as_u64().unwrap() as usize;
    }
    let p = ChiSquared::new(n as f64).unwrap().sf(x);
    (x, n, p)
}

/// Each reading's RMSE before and after the fit against the data's noise (the RMS of its
/// `uncertainty`) and the truth's own RMSE: the 1.5x reading, printed, not asserted.
fn print_rmse_against_noise(
    effect: &str,
    before: &serde_json::Value,
    after: &serde_json::Value,
    truth: &serde_json::Value,
) {
    for observable in after["observables"].as_object().unwrap().keys() {
        let u: Vec<f64> = before["rows"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["observable"] == observable.as_str())
            .map(|r| r["uncertainty"].as_f64().unwrap())
            .collect();
        let noise = (u.iter().map(|x| x * x).sum::<f64>() / u.len() as f64).sqrt();
        let rmse = |c: &serde_json::Value| c["observables"][observable]["rmse"].as_f64().unwrap();
        eprintln!(
            "{effect}: {observable}: RMSE before {:.3}, after {:.3} ({:.2}x the noise {noise:.3}, {:.2}x the truth's own {:.3})",
            rmse(before),
            rmse(after),
            rmse(after) / noise,
            rmse(after) / rmse(truth),
            rmse(truth)
        );
    }
}

/// Runs `detection_rate.sh` for `effect` over `seeds`: each seed's diagnosis.json.
fn diagnoses(effect: &str, strength: f64, seeds: &[u64]) -> Vec<serde_json::Value> {
    let rate = scratch().join(format!("rate-{effect}"));
    let _ = std::fs::remove_dir_all(&rate);
    let mut args = vec![
        effect.to_string(),
        strength.to_string(),
        rate.display().to_string(),
    ];
    args.extend(seeds.iter().map(u64::to_string));
    script(
        "detection_rate.sh",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    seeds
        .iter()
        .map(|seed| json(&rate.join(format!("seed{seed}/2-diagnose/diagnosis.json"))))
        .collect()
}

/// Runs `detection_rate.sh` for `effect` over `seeds` and returns the seeds on which the hidden
/// effect came first with p < 0.01, and a line for each other seed naming what came first.
fn detect(effect: &str, strength: f64, seeds: &[u64]) -> (Vec<u64>, Vec<String>) {
    let (mut hits, mut misses) = (vec![], vec![]);
    for (seed, d) in seeds.iter().zip(diagnoses(effect, strength, seeds)) {
        let first = &d["candidates"][0];
        let p = first["p_value"].as_f64().unwrap();
        if first["name"] == effect && first["significant"] == true && p < 0.01 {
            hits.push(*seed);
        } else {
            misses.push(format!("seed {seed}: {} (p = {p})", first["name"]));
        }
    }
    eprintln!(
        "{effect} hidden at {strength}: ranked first with p < 0.01 in {} of {} draws; misses: {misses:?}",
        hits.len(),
        seeds.len()
    );
    (hits, misses)
}

fn assert_detected(effect: &str, strength: f64, first_seed: u64, draws: u64, at_least: usize) {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let seeds: Vec<u64> = (first_seed..first_seed + draws).collect();
    let (hits, misses) = detect(effect, strength, &seeds);
    assert!(
        hits.len() >= at_least,
        "{effect} hidden at {strength}: ranked first with p < 0.01 in {} of {draws} draws (bar: {at_least}); first instead: {}",
        hits.len(),
        misses.join(", ")
    );
}

#[test]
#[ignore = "slow tier: the discovery proof"]
fn a_hidden_fine_fraction_is_ranked_first_on_at_least_4_of_8_draws() {
    assert_detected("fines", 0.15, 1, DRAWS_CLEAR, 4);
}

#[test]
#[ignore = "slow tier: the discovery proof"]
fn hidden_wall_adhesion_is_ranked_first_on_at_least_4_of_8_draws() {
    assert_detected("wall_adhesion", 0.02, 2, DRAWS_CLEAR, 4);
}

#[test]
#[ignore = "slow tier: the discovery proof"]
fn hidden_plastic_adhesion_is_ranked_first_and_no_other_effect_is_named() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let effect = "plastic_adhesion";
    let seeds: Vec<u64> = (3..3 + DRAWS_PLASTIC).collect();
    let (mut first, mut wrong) = (vec![], vec![]);
    for (seed, d) in seeds.iter().zip(diagnoses(effect, 0.04, &seeds)) {
        // First among the effects: a held parameter (a probe) may rank above it.
        let first_effect = d["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["held_parameter"] != true);
        if first_effect.is_some_and(|c| c["name"] == effect) {
            first.push(*seed);
        }
        let v = &d["verdict"];
        let named: Vec<&str> = v["effects"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["name"].as_str().unwrap())
            .collect();
        if v["verdict"] == "effect" && named.iter().any(|n| *n != effect) {
            wrong.push(format!("seed {seed}: {named:?}"));
        }
    }
    eprintln!(
        "{effect} hidden at 0.04: ranked first among the effects in {} of {DRAWS_PLASTIC} draws; a wrong effect named in {wrong:?}",
        first.len()
    );
    assert!(
        wrong.len() <= PLASTIC_MOST_WRONG,
        "a wrong effect named: {wrong:?}"
    );
    assert!(
        first.len() >= PLASTIC_LEAST_FIRST,
        "{effect} ranked first in only {} of {DRAWS_PLASTIC}: {first:?}",
        first.len()
    );
}

#[test]
#[ignore = "slow tier: the discovery proof"]
fn fitting_a_hidden_fine_fraction_brings_the_data_chi2_to_the_noise() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (effect, strength) = ("fines", 0.15);
    // The first draw on which the diagnosis names it (the same draws as the detection test,
    // so with one cache these runs are made once).
    let seeds: Vec<u64> = (1..=DRAWS_CLEAR).collect();
    let (hits, misses) = detect(effect, strength, &seeds);
    let Some(seed) = hits.first() else {
        panic!("{effect} was not ranked first on any of {seeds:?}: {misses:?}")
    };
    let out = scratch().join(format!("hidden-{effect}"));
    let _ = std::fs::remove_dir_all(&out);
    script(
        "hidden_effect.sh",
        &[
            effect,
            &strength.to_string(),
            out.to_str().unwrap(),
            &seed.to_string(),
        ],
    );
    let before = json(&out.join("1-compare/compare.json"));
    let after = json(&out.join("4-compare/compare.json"));
    let truth = json(&out.join("5-truth/compare.json"));
    print_rmse_against_noise(effect, &before, &after, &truth);
    let (x_before, n_before, p_before) = chi2(&before);
    let (x_after, n_after, p_after) = chi2(&after);
    let (x_truth, n_truth, p_truth) = chi2(&truth);
    eprintln!(
        "{effect} hidden at {strength}: chi^2 before the fit {x_before:.1} on {n_before} rows (p = {p_before:.2e}), after {x_after:.1} on {n_after} (p = {p_after:.3}), the truth's own {x_truth:.1} on {n_truth} (p = {p_truth:.3})"
    );
    assert!(
        p_after >= ALPHA,
        "{effect} hidden at {strength}: after the fit the data still reject the model: chi^2 = {x_after:.1} on {n_after} rows, p = {p_after:.2e} < {ALPHA} (the truth's own: chi^2 = {x_truth:.1}, p = {p_truth:.3})"
    );
    assert!(
        x_after < x_before,
        "{effect} hidden at {strength}: the fit did not lower the error: chi^2 {x_before:.1} before, {x_after:.1} after"
    );
}

#[test]
#[ignore = "slow tier: the discovery proof"]
fn without_a_hidden_effect_at_most_5_of_20_seeds_raise_an_alarm() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let out = scratch().join("null");
    let _ = std::fs::remove_dir_all(&out);
    script(
        "null_study.sh",
        &[out.to_str().unwrap(), &NULL_SEEDS.to_string()],
    );
    let mut flagged = vec![];
    for seed in 1..=NULL_SEEDS {
        let d = json(&out.join(format!("seed-{seed}/diagnose/diagnosis.json")));
        let hits: Vec<String> = d["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["significant"] == true)
            .map(|c| format!("{} (p = {})", c["name"], c["p_value"]))
            .collect();
        if !hits.is_empty() {
            flagged.push(format!("seed {seed}: {}", hits.join(", ")));
        }
    }
    eprintln!(
        "false alarms in {} of {NULL_SEEDS} seeds: {flagged:?}",
        flagged.len()
    );
    assert!(
        flagged.len() <= NULL_MOST_ALARMS,
        "false alarms in {} of {NULL_SEEDS} seeds:\n{}",
        flagged.len(),
        flagged.join("\n")
    );
}
