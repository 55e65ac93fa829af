//! How the process asks memory of the C library.
//!
//! glibc serves a large block from its own heap once a block of that size has been freed
//! (its "dynamic mmap threshold" rises up to 32 MiB), and a block freed in the middle of that
//! heap stays resident. A simulation's neighbour list and force buffers are tens of MiB that
//! grow a little at each rebuild, so their freed generations piled up: at 100,000 particles
//! the peak resident memory was 1.14 KiB per particle with 0.75 KiB live. With a fixed
//! threshold every block from 256 KiB up is its own mapping, returned to the system when
//! freed, and the peak fell to 0.86 KiB per particle (today's numbers: BENCHMARKS.md, "Memory at
//! 100,000 particles").

/// Serves blocks of 256 KiB and more from their own mappings (glibc `M_MMAP_THRESHOLD`). A
/// user's `MALLOC_MMAP_THRESHOLD_` in the environment wins. Elsewhere, nothing to do.
pub fn return_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() {
        // SAFETY: mallopt only sets an allocator parameter; called before any threads exist.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 256 * 1024);
        }
    }
}
