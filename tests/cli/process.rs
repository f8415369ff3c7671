//! The `mtsim` process as built: on Linux with glibc the binary is linked at a fixed address
//! (build.rs), so that the dynamic loader applies no relocations to it at each start.

/// The ELF header's file type (`e_type`, the two bytes at offset 16, in the byte order
/// `e_ident[5]` names: 1 little-endian, 2 big-endian): 2 an executable at a fixed address
/// (`ET_EXEC`), 3 a position-independent one (`ET_DYN`).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn the_binary_is_linked_at_a_fixed_address() {
    use std::io::Read;
    let mut header = [0u8; 18];
    std::fs::File::open(env!("CARGO_BIN_EXE_mtsim"))
        .unwrap()
        .read_exact(&mut header)
        .unwrap();
    assert_eq!(&header[..4], b"\x7fELF");
    let e_type = match header[5] {
        1 => u16::from_le_bytes([header[16], header[17]]),
        _ => u16::from_be_bytes([header[16], header[17]]),
    };
    assert_eq!(
        e_type, 2,
        "ELF type {e_type}: 2 (ET_EXEC) expected; 3 is a PIE"
    );
}
