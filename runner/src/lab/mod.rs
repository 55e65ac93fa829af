//! The virtual laboratory: the reference study's three tests as experiments.
//!
//! [`model`] maps test conditions to contact parameters; [`experiment`] reads an experiment
//! file and builds its scene and [`protocol`]; [`repose`], [`shear`] and [`ucs`] are the tests,
//! whose scenes [`scene`] assembles from the scene file's typed sections.

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
pub mod ucs;
