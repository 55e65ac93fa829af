//! The virtual laboratory: the reference study's tests as experiments.
//!
//! [`model`] maps test conditions to contact parameters; [`experiment`] reads an experiment
//! file and builds its scene and [`protocol`]; [`repose`], [`shear`], [`ucs`] and [`tilt`]
//! are the tests, whose scenes [`scene`] assembles from the scene file's typed sections.

pub mod discharge;
pub mod experiment;
pub mod model;
pub mod observe;
pub mod protocol;
pub mod repose;
pub mod scene;
pub mod settling_bed;
pub mod shear;
pub mod sizes;
pub mod specimen;
pub mod tilt;
pub mod ucs;
