//! Links the `mtsim` binary at a fixed address on Linux with glibc (`-no-pie`): a
//! position-independent executable has about 30,000 relocations for the dynamic loader to
//! apply at every start, and 90 pages of `.data.rel.ro` each copied on write
//! (docs/performance.md). The code is compiled position-independent as before; only the
//! link differs, and only for the binary (the library, loaded into Python as part of a
//! shared object, is untouched). The cost: the executable's own address is not randomised
//! (ASLR still places the stack, the heap and the shared libraries).

fn main() {
    let target = |key: &str| std::env::var(key).unwrap_or_default();
    if target("CARGO_CFG_TARGET_OS") == "linux" && target("CARGO_CFG_TARGET_ENV") == "gnu" {
        println!("cargo:rustc-link-arg-bins=-no-pie");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
