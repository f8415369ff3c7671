//! `mtsim`: the command line. All the work is in the library; see `mtsim::cli`.

fn main() {
    keep_freed_memory();
    std::process::exit(mtsim::cli::main());
}

/// glibc's allocator, told to serve every allocation below 32 MB from its heap and to keep
/// what is freed (up to 64 MB at the heap's top) for the allocations after it. By default a
/// block of 128 kB or more is a mapping of its own, returned to the kernel when freed, so
/// that the next one touches fresh pages again: a page fault and a zeroed page each. A
/// `simulate` run frees and allocates such blocks between its two directions and its
/// analyses (docs/performance.md). In `study` and `sweep`, whose rayon threads allocate in
/// arenas of their own, each arena likewise keeps up to 64 MB freed at its top for its
/// thread's next runs instead of returning it. The library, also loaded into Python, leaves
/// the allocator as it is.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; called before any thread starts.
        let (mmap, trim) = unsafe {
            (
                libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20),
                libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20),
            )
        };
        // 1 is accepted; 0 a rejected value (e.g. a threshold above glibc's maximum).
        debug_assert_eq!((mmap, trim), (1, 1), "mallopt rejected a threshold");
    }
}
