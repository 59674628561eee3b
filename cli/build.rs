//! Link-time settings of the `physid` binary.

fn main() {
    // Relative relocations packed (DT_RELR, glibc ≥ 2.36): the binary's 214,000 relocation
    // entries (5 MB) are what the dynamic loader walks at every start.
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-link-arg-bins=-Wl,-z,pack-relative-relocs");
    }
}
