//! # tilth-kernel
//!
//! A deterministic discrete element (DEM) engine for spherical particles.
//! Physics only: no command line, no file formats beyond what a law or a wall needs
//! (STL meshes). Every physical effect is a contact law in one file of
//! [`contact::laws`]; the registry there is the only other place that names it.
//!
//! Units are SI throughout (m, kg, s, N, Pa, J/m^2).
//!
//! The pieces, in the order a step uses them:
//! - [`particles::Particles`]: struct-of-arrays particle state.
//! - [`neighbor`]: linked cells + Verlet pair list with a skin; contact history lives
//!   in the pair list and survives every rebuild.
//! - [`contact`]: the contact geometry and the slot pipeline
//!   (normal -> damping -> tangential -> rolling -> extras).
//! - [`wall`]: planes, discs, cylinders, cone frusta and STL meshes, static, moving or servo-driven.
//! - [`factory`]: dynamic particle generation at a rate.
//! - [`sim::Simulation`]: velocity-Verlet stepping, failure detection, determinism.
//! - [`timestep`], [`step_check`]: the step a scene may take, before a run and from its
//!   contacts during one.
//! - [`timing`]: where a run's time goes, part by part of the step.

// Range checks are written `!(x > 0.0)` on purpose: the negation also refuses NaN, which
// `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod contact;
pub mod error;
pub mod factory;
pub mod material;
pub mod neighbor;
pub mod param;
pub mod particles;
pub mod sim;
pub mod step_check;
pub mod timestep;
pub mod timing;
pub mod wall;

pub use error::KernelError;
pub use glam::DVec3;
