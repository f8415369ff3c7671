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
/// analyses (docs/performance.md). The process is short and its memory small; the library,
/// also loaded into Python, leaves the allocator as it is.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before any thread starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20);
    }
}
