//! Same input and seed give the same bits on 1 and 2 threads; contact history survives
//! neighbour-list rebuilds (a run that rebuilds every step equals one that rarely does).

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::contact::ContactModel;
use tilth_kernel::factory::{Basis, Factory, FactorySpec, Region};
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::{Aabb, PairPath, Setup, Simulation};
use tilth_kernel::wall::{Motion, Wall, axisymmetric::Axisymmetric, mesh::Mesh};

/// A funnel-fed pile with every law family: JKR, Mindlin, EPSD, walls of three kinds and a
/// factory, 2,500 particles (several parallel chunks).
fn pile(threads: usize, skin: f64) -> Simulation {
    pile_with(jkr_epsd(), threads, skin)
}

/// JKR, Mindlin and EPSD: the pile's laws.
fn jkr_epsd() -> ContactModel {
    model(
        &spec("jkr", Some("restitution"), Some("mindlin"), Some("epsd")),
        &[
            ("restitution", 0.45),
            ("friction", 0.5),
            ("rolling_friction", 0.15),
            ("surface_energy", 0.356),
        ],
    )
}

/// Hertz, Mindlin, CDT and SJKR: the LIGGGHTS settling bed's laws.
fn hertz_sjkr() -> ContactModel {
    let mut s = spec("hertz", Some("restitution"), Some("mindlin"), Some("cdt"));
    s.extra = vec!["sjkr".into()];
    model(
        &s,
        &[
            ("restitution", 0.45),
            ("friction", 0.6),
            ("rolling_friction", 0.15),
            ("cohesion_energy_density", 0.356),
        ],
    )
}

/// [`pile`] with the contact model `m`.
fn pile_with(m: ContactModel, threads: usize, skin: f64) -> Simulation {
    pile_on(floor(), m, threads, skin)
}

/// [`pile_with`] on the floor `bottom`.
fn pile_on(bottom: Wall, m: ContactModel, threads: usize, skin: f64) -> Simulation {
    let walls = vec![
        bottom,
        Wall::new(
            "ring",
            Box::new(Axisymmetric::cylinder(DVec3::ZERO, DVec3::Z, 0.02, 0.01).unwrap()),
            0,
            Motion::Fixed,
        ),
        Wall::new(
            "funnel",
            Box::new(
                Axisymmetric::frustum(DVec3::new(0.0, 0.0, 0.03), DVec3::Z, 0.006, 0.02, 0.03)
                    .unwrap(),
            ),
            0,
            Motion::Fixed,
        ),
    ];
    let factory = Factory::new(FactorySpec {
        region: Region::Cylinder {
            base: DVec3::new(0.0, 0.0, 0.062),
            radius: 0.015,
            height: 0.035,
        },
        sizes: vec![(1e-3, 0.9), (0.7e-3, 0.1)],
        basis: Basis::Number,
        material: 0,
        density: RHO,
        rate: 100_000.0,
        count: 2_500,
        velocity: DVec3::new(0.0, 0.0, -0.5),
        start_time: 0.0,
        seed: 11,
    })
    .unwrap();
    Simulation::new(Setup {
        model: m,
        particles: Particles::default(),
        walls,
        factories: vec![factory],
        dt: 5e-6,
        gravity: DVec3::new(0.0, 0.0, -9.81),
        skin,
        threads,
        domain: Aabb {
            min: DVec3::new(-0.1, -0.1, -0.01),
            max: DVec3::new(0.1, 0.1, 0.1),
        },
    })
    .unwrap()
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    let mut a = pile(1, 4e-4);
    let mut b = pile(2, 4e-4);
    for _ in 0..8 {
        a.run(2_000).unwrap();
        b.run(2_000).unwrap();
        assert_eq!(a.particles.len(), b.particles.len());
        assert_eq!(
            a.state_hash(),
            b.state_hash(),
            "states differ at step {}",
            a.step
        );
    }
    // The scene did something: particles exist, touch and the floor or funnel carries load.
    let (pairs, walls) = a.contact_counts();
    assert!(
        a.particles.len() == 2_500 && pairs > 100 && walls > 10,
        "pairs {pairs}, wall contacts {walls}"
    );
}

/// `run` applies each step's first half kick and drift in the previous step's particle
/// phase (one pass over memory fewer); stepping one `advance` at a time does them in a pass
/// of their own. Same operations in the same order: the same bits, through the pour's
/// insertions, reorders, rebuilds and wall contacts.
/// A run that fails stops at the same step, with the same message and the same bits, on 1
/// and 2 threads: the chunks that went on to the next step's drift while another failed are
/// taken back whichever thread ran them. And it stops in the state of one `advance` at a time
/// (which never drifts ahead), to rounding: taking back `x += v dt` is `x -= v dt`.
#[test]
fn a_failed_run_stops_with_the_same_bits_on_one_and_two_threads() {
    let fail = |threads, stepwise: bool| {
        let mut s = pile(threads, 4e-4);
        s.run(6_000).unwrap();
        // A grain in the middle of the index range thrown at 1 km/s: far above any speed
        // the scene can reach, so the step's check stops the run.
        let k = s.particles.len() / 2;
        s.particles.velocity[k] = DVec3::new(0.0, 0.0, 1e3);
        let err = if stepwise {
            (0..1_000).find_map(|_| s.advance().err())
        } else {
            s.run(1_000).err()
        };
        let err = err.expect("the run fails").to_string();
        (err, s.step, s.state_hash(), s.particles)
    };
    let one = fail(1, false);
    let two = fail(2, false);
    assert!(one.0.contains("run stopped at step"), "{}", one.0);
    assert_eq!(
        (&one.0, one.1, one.2),
        (&two.0, two.1, two.2),
        "1 and 2 threads"
    );

    let step = fail(1, true);
    assert_eq!((&one.0, one.1), (&step.0, step.1));
    // Rounding of one add and subtract: a few ulps of 0.1 m and 1 m/s. A drift not taken
    // back is off by v dt, about 1e-6 m for a grain at 0.2 m/s.
    let far = |a: &[DVec3], b: &[DVec3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (*x - *y).abs().max_element())
            .fold(0.0, f64::max)
    };
    let (run, stepped) = (&one.3, &step.3);
    assert!(far(&run.position, &stepped.position) < 1e-15, "positions");
    assert!(far(&run.velocity, &stepped.velocity) < 1e-13, "velocities");
    assert!(
        far(&run.angular_velocity, &stepped.angular_velocity) < 1e-9,
        "spins"
    );
}

#[test]
fn a_run_gives_the_bits_of_one_step_at_a_time() {
    let mut fused = pile(2, 4e-4);
    let mut single = pile(2, 4e-4);
    for _ in 0..8 {
        fused.run(2_000).unwrap();
        for _ in 0..2_000 {
            single.advance().unwrap();
        }
        assert_eq!(
            fused.state_hash(),
            single.state_hash(),
            "states differ at step {}",
            fused.step
        );
    }
    // It covered the pour: particles inserted, reordered (every 1,000 steps) and in contact.
    let (pairs, walls) = fused.contact_counts();
    assert!(
        fused.particles.len() > 1_000 && fused.rebuilds > 10 && pairs > 100 && walls > 10,
        "{} particles, {} rebuilds, {pairs} pairs, {walls} wall contacts",
        fused.particles.len(),
        fused.rebuilds
    );
}

#[test]
fn history_survives_rebuilds() {
    // Skin 0 rebuilds the list every step; 0.4 mm rarely. Non-touching listed pairs add
    // exact zeros, and sums run in the same order, so the runs must agree to the bit, which
    // they can only do if every tangential and rolling spring is carried across rebuilds.
    let mut often = pile(2, 0.0);
    let mut rarely = pile(2, 4e-4);
    often.run(4_000).unwrap();
    rarely.run(4_000).unwrap();
    assert!(
        often.rebuilds > 3 * rarely.rebuilds,
        "rebuilds {} vs {}",
        often.rebuilds,
        rarely.rebuilds
    );
    assert_eq!(often.state_hash(), rarely.state_hash());
}

#[test]
fn pair_list_holds_every_contact_of_the_naive_search() {
    let mut s = pile(2, 4e-4);
    for _ in 0..5 {
        s.run(700).unwrap();
        let p = &s.particles;
        let list = s.pairs();
        let mut listed = std::collections::HashSet::new();
        for k in 0..list.len() {
            // Listed once, in either orientation (the row of the smaller id).
            listed.insert((list.i[k].min(list.j[k]), list.i[k].max(list.j[k])));
        }
        // O(N^2) oracle: every touching pair must be listed.
        let mut touching = 0;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                if (p.position[j] - p.position[i]).length() < p.radius[i] + p.radius[j] {
                    touching += 1;
                    assert!(
                        listed.contains(&(i as u32, j as u32)),
                        "touching pair ({i}, {j}) missing at step {}",
                        s.step
                    );
                }
            }
        }
        assert!(touching > 0 || s.step < 2000);
    }
}

/// The pair-phase timer (`tilth bench settling-bed --pair-phase-reps`) is a look, not a
/// step: the run that follows it has the bits of a run without it.
#[test]
fn timing_the_pair_phase_changes_nothing() {
    let mut timed = pile(1, 4e-4);
    let mut plain = pile(1, 4e-4);
    timed.run(6_000).unwrap();
    plain.run(6_000).unwrap();
    let (pairs, _) = timed.contact_counts();
    assert!(
        pairs > 100,
        "only {pairs} pairs in contact: nothing to time"
    );
    let seconds = timed.time_pair_phase(5);
    assert!(seconds > 0.0, "five pair phases took {seconds} s");
    assert_eq!(timed.state_hash(), plain.state_hash());
    timed.run(1_000).unwrap();
    plain.run(1_000).unwrap();
    assert_eq!(timed.state_hash(), plain.state_hash());
}

/// The pair phase and the wall contacts (floor, ring, funnel) evaluate touching contacts in
/// lanes, on AVX-512, AVX2 or SSE2, through the model's compiled law set or the slots'
/// enums, or one at a time: the same bits, through the pour's new contacts, ending
/// contacts, reorders and
/// rebuilds, with laws whose lane forms run their scalar forms (JKR, EPSD) and laws with
/// lane forms of their own (the settling bed's Hertz, Mindlin, CDT, SJKR), on 1 and 2
/// threads. (On a CPU without AVX-512 or AVX2, those paths fall back to the next one.)
#[test]
fn contacts_in_lanes_give_the_bits_of_one_at_a_time() {
    let paths = [
        (PairPath::Lanes, 2),
        (PairPath::LanesAvx2, 1),
        (PairPath::LanesBaseline, 2),
        (PairPath::LanesEnums, 1),
        (PairPath::OneByOne, 1),
    ];
    for (name, m) in [
        ("jkr", jkr_epsd as fn() -> ContactModel),
        ("sjkr", hertz_sjkr),
    ] {
        let mut runs: Vec<Simulation> = paths
            .iter()
            .map(|&(path, threads)| {
                let mut s = pile_with(m(), threads, 4e-4);
                s.set_pair_path(path);
                s
            })
            .collect();
        for _ in 0..8 {
            for s in &mut runs {
                s.run(2_000).unwrap();
            }
            for (s, (path, _)) in runs.iter().zip(&paths).skip(1) {
                assert_eq!(
                    s.state_hash(),
                    runs[0].state_hash(),
                    "{name}: {path:?} differs from {:?} at step {}",
                    paths[0].0,
                    s.step
                );
            }
        }
        // The pour reached the floor: contacts formed, ended and carried load.
        let (pairs, walls) = runs[0].contact_counts();
        assert!(
            pairs > 100 && walls > 10,
            "{name}: pairs {pairs}, wall contacts {walls}"
        );
    }
}

/// A shallow V-shaped trough of 5 mm triangles under the pile (z = 0.1 |x|, 60 mm square):
/// most particles near it list one triangle, those near a seam several, of which the nearer
/// shadow the others.
fn trough() -> Wall {
    let cells = 12;
    let h = 0.06 / cells as f64;
    let corner = |a: usize, b: usize| {
        let x = -0.03 + a as f64 * h;
        DVec3::new(x, -0.03 + b as f64 * h, 0.1 * x.abs())
    };
    let mut triangles = vec![];
    for a in 0..cells {
        for b in 0..cells {
            let (p, q, r, t) = (
                corner(a, b),
                corner(a + 1, b),
                corner(a + 1, b + 1),
                corner(a, b + 1),
            );
            triangles.push([p, q, r]);
            triangles.push([p, r, t]);
        }
    }
    Wall::new("trough", Box::new(Mesh::new(triangles)), 0, Motion::Fixed)
}

/// A pile on a triangle mesh: its contacts with one listed triangle go through the lanes,
/// those with several (shadowing) one at a time, in one chunk; the same bits as every
/// contact one at a time.
#[test]
fn wall_contacts_on_a_mesh_in_lanes_give_the_bits_of_one_at_a_time() {
    let mut runs: Vec<Simulation> = [(PairPath::Lanes, 2), (PairPath::OneByOne, 1)]
        .iter()
        .map(|&(path, threads)| {
            let mut s = pile_on(trough(), hertz_sjkr(), threads, 4e-4);
            s.set_pair_path(path);
            s
        })
        .collect();
    for _ in 0..6 {
        for s in &mut runs {
            s.run(2_000).unwrap();
        }
        assert_eq!(
            runs[1].state_hash(),
            runs[0].state_hash(),
            "lanes and one at a time differ at step {}",
            runs[0].step
        );
    }
    let (_, walls) = runs[0].contact_counts();
    assert!(walls > 10, "only {walls} wall contacts");
}
