//! The allocator policy of the command-line tools while a model runs: freed memory stays in
//! the process.
//!
//! glibc hands every freed block above its mmap threshold (at most 32 MB) straight back to
//! the kernel with `munmap`, and in a multi-threaded process every `munmap` interrupts each
//! core to flush its TLB. The models allocate and free tensors of hundreds of MB per layer:
//! on a 200k-face mesh the neural mesh simplifier spent about a third of its time in the
//! kernel doing that (perf: `native_write_msr`, `smp_call_function_many_cond`, page faults).
//! With the mmap and trim thresholds raised, freed blocks are reused instead: 3.3-4.1 s →
//! 2.4-2.5 s there, peak memory +16-20 % (docs/mesh_simplifier_model.md, "Time"). The tools
//! set it only for the learned methods: the Laplacian eigen-solver of `meshsimplify eval`
//! ran 3 % slower with it, and QEM gained nothing but 2 MB of peak memory.

/// Keeps freed memory in the process for reuse from now on (module docs): for the
/// command-line tools, before a model runs; a library should leave the allocator alone. A
/// no-op where the C library is not glibc.
pub fn reuse_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    glibc::raise_thresholds();
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
mod glibc {
    /// `mallopt` parameters of glibc's `malloc.h`.
    const M_TRIM_THRESHOLD: i32 = -1;
    const M_MMAP_THRESHOLD: i32 = -3;

    unsafe extern "C" {
        fn mallopt(param: i32, value: i32) -> i32;
    }

    pub(super) fn raise_thresholds() {
        // SAFETY: `mallopt` takes two integers and only retunes the allocator; it locks the
        // main arena, so any thread may call it; a value it refuses leaves the default.
        unsafe {
            mallopt(M_MMAP_THRESHOLD, i32::MAX);
            mallopt(M_TRIM_THRESHOLD, i32::MAX);
        }
    }
}
