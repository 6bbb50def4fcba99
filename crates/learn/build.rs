//! Lets the `naosoccer` binary and the tests under tests/ find libtorch at
//! run time without LD_LIBRARY_PATH. The lib dir comes from torch-sys (its
//! `links = "tch"` metadata reaches only direct dependents, hence the direct
//! optional dependency), and `rustc-link-arg` reaches only this package's own
//! targets, so crates/learn carries the same script for its tests.
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_TCH_LIBTORCH_LIB");
    if let Ok(lib) = std::env::var("DEP_TCH_LIBTORCH_LIB") {
        println!("cargo:rustc-link-arg=-Wl,-rpath={lib}");
        // rustc links with --as-needed; keep libtorch.so itself, which pulls
        // in the backends that register their operators at load time.
        println!("cargo:rustc-link-arg=-Wl,--no-as-needed");
        println!("cargo:rustc-link-arg=-ltorch");
    }
}
