//! tilth: the command-line front end of the tilth DEM workbench.
//!
//! Layers, lowest first (ARCHITECTURE.md): [`config`] turns a TOML scene file into a checked
//! kernel simulation; [`lab`] holds the virtual instruments; [`sweep`] expands plans into
//! runs and executes them, [`record`] writes their MCAP files; [`study`] compares, diagnoses,
//! fits and calibrates; [`cli`] parses the arguments, calls the library and prints.
//!
//! Exit codes: 0 success, 1 the run failed (the kernel stopped it: [`KernelError::BlowUp`]),
//! 2 bad input or usage. A closed stdout (broken pipe) is not an error.

// Range checks are written `!(x > 0.0)` on purpose: the negation also refuses NaN, which
// `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cli;
pub mod config;
pub mod lab;
pub mod memory;
pub mod progress;
pub mod provenance;
pub mod record;
pub mod study;
pub mod sweep;
pub mod text;

use tilth_kernel::KernelError;

pub use provenance::GIT_COMMIT;

/// Exit code for success.
pub const EXIT_OK: u8 = 0;
/// Exit code when the simulation itself failed.
pub const EXIT_RUN_FAILED: u8 = 1;
/// Exit code of a sweep stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report).
pub const EXIT_INTERRUPTED: u8 = 130;
/// Exit code for bad input (scene file, arguments).
pub const EXIT_BAD_INPUT: u8 = 2;

/// The exit code for an error: [`EXIT_RUN_FAILED`] when the kernel stopped a run,
/// [`EXIT_BAD_INPUT`] otherwise.
pub fn exit_code(err: &anyhow::Error) -> u8 {
    use sweep::execute::SweepEnd;
    match err.downcast_ref::<SweepEnd>() {
        Some(SweepEnd::Interrupted) => return EXIT_INTERRUPTED,
        Some(SweepEnd::Failed(_)) => return EXIT_RUN_FAILED,
        None => {}
    }
    let blew_up = err.chain().any(|e| {
        matches!(
            e.downcast_ref::<KernelError>(),
            Some(KernelError::BlowUp { .. })
        )
    });
    if blew_up {
        EXIT_RUN_FAILED
    } else {
        EXIT_BAD_INPUT
    }
}

/// Whether the error is only stdout closing under us (`tilth laws | head`).
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|e| {
        e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
