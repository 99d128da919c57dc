//! Links the `clayloft` executables at a fixed address (not position-independent). The binary
//! holds the whole editor (Bevy) as well as the command line; as a position-independent
//! executable the dynamic loader first patches about half a million addresses in it (12 MB of
//! relocation records, a few thousand pages made private) before `main` runs: measured 10 ms of
//! a 0.12 s `clayloft gcode` run (`perf record`, `LD_DEBUG=statistics`). Linked at a fixed
//! address there is nothing to patch. Only the link step of this package's binaries changes;
//! every library stays as it was built.
fn main() {
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-link-arg-bins=-no-pie");
    }
}
