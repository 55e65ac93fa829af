//! The rest check on heaps built grain by grain, so that what they test does not hang on one
//! trajectory of a chaotic pour: a pyramid of 4 mm grains at rest on the tray, and on its apex
//! one grain that rocks (its speed alternating across [`observe::HEAP_SPEED`] at each check,
//! as in docs/li2022-compare.md, "Grains that never stop"), so that the cone angle flips.

use super::*;
use crate::lab::discharge::Discharge;
use crate::lab::observe::Tray;
use crate::lab::protocol::{Control, Protocol};
use glam::DVec3;
use tilth_kernel::particles::Particles;

const R: f64 = 0.002;
/// Layers of the pyramid; its top grain's top is 2 R LAYERS above the tray.
const LAYERS: usize = 7;
/// When the pour ends and the heap below the rocker stops, s.
const STILL_FROM: f64 = 0.3;
const TRAY_RADIUS: f64 = 0.0309;

/// The pyramid (simple cubic, layer L a square of side 2 (LAYERS - 1 - L) + 1 grains),
/// then the rocker on its apex; all at rest.
fn heap() -> Particles {
    let mut p = Particles::default();
    for layer in 0..LAYERS {
        let half = (LAYERS - 1 - layer) as i32;
        for i in -half..=half {
            for j in -half..=half {
                let at = DVec3::new(i as f64, j as f64, 0.0) * 2.0 * R;
                let z = R + 2.0 * R * layer as f64;
                p.push(at + DVec3::Z * z, DVec3::ZERO, R, 1500.0, 0);
            }
        }
    }
    p.push(
        DVec3::Z * (R + 2.0 * R * LAYERS as f64),
        DVec3::ZERO,
        R,
        1500.0,
        0,
    );
    p
}

/// The cone angle (deg) of a heap whose top grain's top is `top` above the tray.
fn angle(top: f64) -> f64 {
    (top / TRAY_RADIUS).atan().to_degrees()
}

fn protocol(count: usize, max_time: f64) -> ReposeProtocol {
    let p = ReposeParams {
        max_time,
        ..ReposeParams::default()
    };
    let z_out = p.drop_height;
    ReposeProtocol {
        p,
        tray: Tray {
            centre: [0.0; 3],
            radius: TRAY_RADIUS,
            ceiling: z_out,
        },
        count,
        fill_time: 0.1,
        z_out,
        outlet: 0.04,
        angles: vec![],
        mean_speeds: vec![],
        settled_at: None,
        check_every: 0.02,
        next_check: 0.0,
        diameter: 2.0 * R,
        mass_g: 40.0,
        discharge: Discharge::default(),
    }
}

/// Runs the protocol's checks on the heap until it is done. Until STILL_FROM every grain
/// moves at `pour` m/s and the apex grain is still falling onto the heap (0.2 m/s, so
/// not counted in it); from then on the grains move at `after` m/s and the apex grain
/// either rests or, if `rocks`, rocks: 0.07 m/s and 0.002 m/s at alternate checks. The
/// summary, and whether the rocker was fast at the end.
fn judge(pour: f64, after: f64, rocks: bool, max_time: f64) -> (serde_json::Value, bool) {
    let mut sim = crate::config::load_or_demo(None, Some(1)).unwrap().sim;
    sim.particles = heap();
    let n = sim.particles.len();
    let mut proto = protocol(n, max_time);
    let mut rocker_fast = false;
    for check in 0.. {
        sim.time = check as f64 * proto.check_every;
        let poured = sim.time >= STILL_FROM - 1e-9;
        let v = &mut sim.particles.velocity;
        v.fill(DVec3::X * if poured { after } else { pour });
        rocker_fast = poured && rocks && check % 2 == 0;
        v[n - 1] = DVec3::X
            * match (poured, rocks) {
                (false, _) => 0.2,
                (true, false) => after,
                (true, true) if rocker_fast => 0.07,
                (true, true) => 0.002,
            };
        if let Control::Done = proto.control(&mut sim).unwrap() {
            break;
        }
        assert!(check < 10_000, "the protocol never stopped");
    }
    (proto.summary(&sim), rocker_fast)
}

fn rest_time() -> f64 {
    ReposeParams::default().rest_time
}

/// With the heap below it still, a rocking grain does not hold the run: it is at rest
/// once the mean speed below the outlet has stayed under STILL_FRACTION x rest_speed for
/// rest_time (the angle never holds), with no warning.
#[test]
fn a_heap_whose_angle_flips_comes_to_rest_when_the_soil_is_still() {
    let (e, _) = judge(0.01, 0.0, true, 8.0);
    assert_eq!(e["settled"], true, "{e}");
    let at = e["settled_at_s"].as_f64().unwrap();
    let expected = STILL_FROM + rest_time();
    assert!((at - expected).abs() <= 0.02 + 1e-9, "{e}");
    assert!(e["warning"].is_null(), "{e}");
}

/// At rest on average but never still (the heap creeps at 3 mm/s, between
/// STILL_FRACTION x rest_speed and rest_speed) and stopped by max_time a rest_time after
/// the pour: the warning names the flipping angle (between the heap with and without
/// the rocker) and the grain that moves, not more time.
#[test]
fn a_heap_whose_angle_flips_is_told_apart_from_one_still_moving() {
    let (e, fast) = judge(0.01, 0.003, true, STILL_FROM + rest_time() + 0.1);
    assert_eq!(e["settled"], false, "{e}");
    let warning = e["warning"].as_str().unwrap();
    let with = angle(2.0 * R * (LAYERS + 1) as f64);
    let without = angle(2.0 * R * LAYERS as f64);
    assert!(
        warning.contains("the soil below the outlet is at rest on average")
            && warning.contains(&format!("moved between {without:.2} and {with:.2} deg"))
            && warning.contains(&format!("{} grain(s) faster than 0.05 m/s", fast as u8))
            && !warning.contains("raise repose.max_time"),
        "{warning}"
    );
}

/// The same heap still poured when max_time stops it: more time is the answer.
#[test]
fn a_heap_still_moving_at_max_time_asks_for_more_time() {
    let (e, _) = judge(0.01, 0.0, false, STILL_FROM - 0.1);
    assert_eq!(e["settled"], false, "{e}");
    let warning = e["warning"].as_str().unwrap();
    assert!(warning.ends_with("raise repose.max_time"), "{warning}");
}

/// Without the rocker the heap is at rest a rest_time after its top grain landed, and
/// its angle is the whole pyramid's.
#[test]
fn a_still_heap_is_at_rest_a_rest_time_after_the_pour() {
    let (e, _) = judge(0.01, 0.0, false, 8.0);
    let at = e["settled_at_s"].as_f64().unwrap();
    assert!(
        (at - (STILL_FROM + rest_time())).abs() <= 0.02 + 1e-9,
        "{e}"
    );
    let top = 2.0 * R * (LAYERS + 1) as f64;
    let a = e["heap_cone_angle_deg"].as_f64().unwrap();
    assert!((a - angle(top)).abs() < 1e-9, "{e}");
    assert!(e["warning"].is_null(), "{e}");
}

/// The tray's top (m above the floor) in the study's funnel test as built at `scale`, with
/// `repose` lines added to the experiment.
fn tray_top(coarse: bool, repose: &str) -> f64 {
    let text = format!(
        "format_version = 1\nexperiment = \"repose\"\nmodel = \"models/li2022.toml\"\n\
         coarse = {coarse}\n[conditions]\nmoisture_pct = 6\n[repose]\n{repose}\n"
    );
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let built =
        crate::lab::experiment::build(toml::from_str(&text).unwrap(), "test", &root, &[]).unwrap();
    let walls = built.scene["walls"].as_array().unwrap();
    let tray = walls
        .iter()
        .find(|w| w["name"].as_str() == Some("tray"))
        .unwrap();
    tray["centre"][2].as_float().unwrap()
}

/// At the study's scale the tray stands on a 100 mm stand, so that the overflow of 200 g
/// falls away from its rim (docs/li2022-compare.md, "The tray's stand"); the coarse preset
/// keeps it on the floor; a given `stand_height` wins at either scale.
#[test]
fn the_tray_stands_on_a_stand_at_the_studys_scale_and_on_the_floor_coarse() {
    let tray = ReposeParams::default().tray_height;
    assert_eq!(tray_top(false, ""), 0.1 + tray);
    assert_eq!(tray_top(true, ""), tray);
    assert_eq!(tray_top(false, "stand_height = 0.03"), 0.03 + tray);
    assert_eq!(tray_top(true, "stand_height = 0.03"), 0.03 + tray);
}
