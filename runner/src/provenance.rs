//! Where a result came from: the build of tilth that made it.

/// The git commit this binary was built from (`-dirty` with uncommitted changes).
pub const GIT_COMMIT: &str = env!("TILTH_GIT_COMMIT");
