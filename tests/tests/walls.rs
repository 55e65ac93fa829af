//! Walls: every shape bounces a sphere with the contact law's restitution, meshes count a
//! seam or edge once, servo walls hold their force, moving walls move, forces are recorded.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::Simulation;
use tilth_kernel::wall::{Motion, Wall, axisymmetric::Axisymmetric, mesh::Mesh, plane::Plane};

const E_REST: f64 = 0.45;

fn frictionless() -> tilth_kernel::contact::ContactModel {
    model(
        &spec("hertz", Some("restitution"), None, None),
        &[("restitution", E_REST)],
    )
}

fn one(x: DVec3, v: DVec3) -> Particles {
    let mut p = Particles::default();
    p.push(x, v, R, RHO, 0);
    p
}

fn bounce(wall: Wall, x: DVec3, v: DVec3) -> Simulation {
    let mut s = sim(frictionless(), one(x, v), vec![wall], 1e-7, DVec3::ZERO, 1);
    s.run(6_000).unwrap();
    s
}

#[test]
fn disc_rebounds_with_restitution() {
    let w = Wall::new(
        "disc",
        Box::new(Axisymmetric::disc(DVec3::ZERO, DVec3::Z, 0.01).unwrap()),
        0,
        Motion::Fixed,
    );
    let s = bounce(
        w,
        DVec3::new(0.003, 0.0, 1.02 * R),
        DVec3::new(0.0, 0.0, -0.5),
    );
    let v = s.particles.velocity[0];
    assert!(
        (v.z / 0.5 - E_REST).abs() < 1e-3 && v.x.abs() < 1e-12,
        "disc rebound {v:?}"
    );
}

#[test]
fn cylinder_confines_from_inside_and_deflects_from_outside() {
    let cyl = || {
        Box::new(Axisymmetric::cylinder(DVec3::new(0.0, 0.0, -0.01), DVec3::Z, 0.01, 0.02).unwrap())
    };
    // Inside, moving radially outward toward the wall at x = 0.01.
    let s = bounce(
        Wall::new("mould", cyl(), 0, Motion::Fixed),
        DVec3::new(0.01 - 1.02 * R, 0.0, 0.0),
        DVec3::new(0.5, 0.0, 0.0),
    );
    let v = s.particles.velocity[0];
    assert!((-v.x / 0.5 - E_REST).abs() < 1e-3, "inside rebound {v:?}");
    // Outside, moving radially inward.
    let s = bounce(
        Wall::new("post", cyl(), 0, Motion::Fixed),
        DVec3::new(0.01 + 1.02 * R, 0.0, 0.0),
        DVec3::new(-0.5, 0.0, 0.0),
    );
    let v = s.particles.velocity[0];
    assert!((v.x / 0.5 - E_REST).abs() < 1e-3, "outside rebound {v:?}");
}

#[test]
fn cone_frustum_reflects_about_its_surface_normal() {
    // Funnel: radius 10 mm at z = 0, 67.5 mm at z = 140 mm (the study's funnel proportions).
    let (r0, r1, h) = (0.01, 0.0675, 0.14);
    let cone = Axisymmetric::frustum(DVec3::ZERO, DVec3::Z, r0, r1, h).unwrap();
    let slope = (r1 - r0) / h;
    // Inward surface normal at azimuth 0: (-1, 0, slope) normalised.
    let n = DVec3::new(-1.0, 0.0, slope).normalize();
    let z = 0.05;
    let surface = DVec3::new(r0 + slope * z, 0.0, z);
    let x = surface + n * 1.02 * R;
    let v_in = -n * 0.5;
    let s = bounce(
        Wall::new("funnel", Box::new(cone), 0, Motion::Fixed),
        x,
        v_in,
    );
    let v = s.particles.velocity[0];
    assert!(
        (v.dot(n) / 0.5 - E_REST).abs() < 1e-3 && (v - n * v.dot(n)).length() < 1e-9,
        "cone rebound {v:?}"
    );
}

fn square_mesh() -> Mesh {
    // A 20 mm square at z = 0 as two triangles sharing the diagonal.
    let (a, b, c, d) = (
        DVec3::new(-0.01, -0.01, 0.0),
        DVec3::new(0.01, -0.01, 0.0),
        DVec3::new(0.01, 0.01, 0.0),
        DVec3::new(-0.01, 0.01, 0.0),
    );
    Mesh::new(vec![[a, b, c], [a, c, d]])
}

#[test]
fn mesh_seam_is_counted_once() {
    // Land exactly on the shared diagonal and next to it: each bounce must equal a plane's.
    for x in [
        DVec3::new(0.0, 0.0, 1.02 * R),
        DVec3::new(0.0004, 0.0, 1.02 * R),
    ] {
        let w = Wall::new("mesh", Box::new(square_mesh()), 0, Motion::Fixed);
        let s = bounce(w, x, DVec3::new(0.0, 0.0, -0.5));
        let v = s.particles.velocity[0];
        assert!(
            (v.z / 0.5 - E_REST).abs() < 1e-3 && v.x.abs() < 1e-9 && v.y.abs() < 1e-9,
            "seam rebound at {x:?}: {v:?}"
        );
    }
}

#[test]
fn stl_file_loads_and_concave_corner_pushes_on_both_faces() {
    // An ASCII STL of two faces meeting at a right angle (floor z = 0, wall x = 0), in mm.
    let dir = std::env::temp_dir().join(format!("tilth-stl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("corner.stl");
    let facet = |n: [f64; 3], v: [[f64; 3]; 3]| {
        let mut s = format!("facet normal {} {} {}\n outer loop\n", n[0], n[1], n[2]);
        for p in v {
            s += &format!("  vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s + " endloop\nendfacet\n"
    };
    let mut text = "solid corner\n".to_string();
    text += &facet(
        [0.0, 0.0, 1.0],
        [[0.0, -10.0, 0.0], [10.0, -10.0, 0.0], [10.0, 10.0, 0.0]],
    );
    text += &facet(
        [0.0, 0.0, 1.0],
        [[0.0, -10.0, 0.0], [10.0, 10.0, 0.0], [0.0, 10.0, 0.0]],
    );
    text += &facet(
        [1.0, 0.0, 0.0],
        [[0.0, -10.0, 0.0], [0.0, 10.0, 10.0], [0.0, -10.0, 10.0]],
    );
    text += &facet(
        [1.0, 0.0, 0.0],
        [[0.0, -10.0, 0.0], [0.0, 10.0, 0.0], [0.0, 10.0, 10.0]],
    );
    text += "endsolid corner\n";
    std::fs::write(&path, text).unwrap();
    let mesh = Mesh::from_stl(&path, 1e-3).unwrap();
    assert_eq!(mesh.triangles.len(), 4);
    // A sphere resting in the corner under gravity pointing into it: both faces carry load.
    let g = DVec3::new(-1.0, 0.0, -1.0).normalize() * 9.81;
    let mut s = sim(
        frictionless(),
        one(DVec3::new(R, 0.0, R), DVec3::ZERO),
        vec![Wall::new("corner", Box::new(mesh), 0, Motion::Fixed)],
        1e-6,
        g,
        1,
    );
    s.run(30_000).unwrap();
    let f = s.walls[0].force;
    let weight = s.particles.mass[0] * 9.81;
    // The wall carries the weight along g, split equally between the two faces.
    assert!(
        (f - g.normalize() * weight).length() < 1e-3 * weight,
        "corner force {f:?} vs weight {weight}"
    );
    assert!(
        Mesh::from_stl(&dir.join("missing.stl"), 1.0)
            .unwrap_err()
            .to_string()
            .contains("missing.stl")
    );
}

#[test]
fn servo_platen_holds_its_target_force() {
    // One sphere on a floor under a servo platen pressing down with 0.05 N: both contacts
    // carry the target, so the overlap at each is Hertz's (3F / (4 E* sqrt(R)))^(2/3).
    let target = 0.05;
    let floor = floor();
    let platen = Wall::new(
        "platen",
        Box::new(Plane::new(DVec3::new(0.0, 0.0, 2.0 * R + 1e-5), -DVec3::Z).unwrap()),
        0,
        Motion::Servo {
            axis: -DVec3::Z,
            target_force: target,
            gain: 2.0,
            max_speed: 0.01,
        },
    );
    let mut s = sim(
        frictionless(),
        one(DVec3::new(0.0, 0.0, R), DVec3::ZERO),
        vec![floor, platen],
        1e-6,
        DVec3::ZERO,
        1,
    );
    s.run(200_000).unwrap();
    let f = s.walls[1].force.z;
    assert!(
        (f - target).abs() / target < 1e-3,
        "platen force {f} vs target {target}"
    );
    let delta = (3.0 * target / (4.0 * e_eff() * R.sqrt())).powf(2.0 / 3.0);
    let gap = 2.0 * R + 1e-5 + s.walls[1].offset.z; // platen height
    assert!(
        (2.0 * R - gap - 2.0 * delta).abs() < 1e-3 * delta,
        "platen at {gap}, two Hertz overlaps {delta}"
    );
}

#[test]
fn prescribed_motion_moves_the_wall_and_records_force_and_torque() {
    let v = DVec3::new(0.0, 0.0, 0.01);
    let lift = Wall::new(
        "lift",
        Box::new(Plane::new(DVec3::new(0.0, 0.0, 0.0), DVec3::Z).unwrap()),
        0,
        Motion::Velocity(v),
    );
    let mut s = sim(
        frictionless(),
        one(DVec3::new(0.003, 0.0, R), DVec3::ZERO),
        vec![lift],
        1e-6,
        DVec3::new(0.0, 0.0, -9.81),
        1,
    );
    s.run(50_000).unwrap();
    assert!((s.walls[0].offset - v * s.time).length() < 1e-12);
    // The lift carries the sphere upward at its speed; its force is the weight, and the
    // torque about the plane's reference point (origin) is r x F at x = 3 mm.
    let w = s.particles.mass[0] * 9.81;
    assert!(
        (s.particles.velocity[0].z - 0.01).abs() < 1e-4,
        "{:?}",
        s.particles.velocity[0]
    );
    assert!(
        (s.walls[0].force.z + w).abs() < 1e-2 * w,
        "force {:?}",
        s.walls[0].force
    );
    assert!(
        (s.walls[0].torque.y - 0.003 * w).abs() < 1e-2 * 0.003 * w,
        "torque {:?}",
        s.walls[0].torque
    );
}

#[test]
fn a_deactivated_wall_lets_go_and_the_wall_below_catches() {
    // A sphere resting on a floor carries its weight; switched off, the floor lets it fall
    // freely (z(t) = z0 - g t^2 / 2) until the wall below catches it.
    let r = 1e-3;
    let g = 9.81;
    let mut s = sim(
        frictionless(),
        one(DVec3::new(0.0, 0.0, r), DVec3::ZERO),
        vec![floor(), {
            let mut w = floor();
            w.offset = DVec3::new(0.0, 0.0, -0.01);
            w.name = "lower".into();
            w
        }],
        1e-6,
        DVec3::new(0.0, 0.0, -g),
        1,
    );
    s.run(20_000).unwrap();
    let weight = s.particles.mass[0] * g;
    assert!(
        (s.walls[0].force.z + weight).abs() < 0.01 * weight,
        "{}",
        s.walls[0].force
    );
    let z0 = s.particles.position[0].z;
    s.set_wall_active(0, false);
    assert_eq!(s.walls[0].force, DVec3::ZERO);
    let n = 20_000;
    s.run(n).unwrap();
    let t = n as f64 * 1e-6;
    let z = s.particles.position[0].z;
    assert!(
        (z - (z0 - 0.5 * g * t * t)).abs() < 1e-3 * 0.5 * g * t * t,
        "z = {z}"
    );
    assert_eq!(s.walls[0].force, DVec3::ZERO);
    // The lower floor catches it.
    s.run(200_000).unwrap();
    assert!((s.particles.position[0].z - (-0.01 + r)).abs() < 1e-4);
    assert!((s.walls[1].force.z + weight).abs() < 0.02 * weight);
}
