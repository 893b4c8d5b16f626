//! Bakes into the binary where the Slang library lies (an rpath, so `cargo run` needs no
//! LD_LIBRARY_PATH) and which versions of slosh3d and Slang it was built against.

use std::path::Path;

fn main() {
    println!("cargo:rerun-if-env-changed=SLANG_DIR");
    println!("cargo:rerun-if-changed=Cargo.lock");
    let mut slang = String::from("unknown");
    if let Ok(dir) = std::env::var("SLANG_DIR") {
        let dir = Path::new(&dir);
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
        println!("cargo:rustc-link-arg-bins=-Wl,-rpath,{}", dir.join("lib").display());
        let version = dir.join("VERSION");
        println!("cargo:rerun-if-changed={}", version.display());
        if let Ok(v) = std::fs::read_to_string(version) {
            slang = v.trim().to_string();
        }
    }
    println!("cargo:rustc-env=PEER_SLANG_VERSION={slang}");
    // The resolved slosh3d version, from the committed lock file.
    let lock = std::fs::read_to_string("Cargo.lock").unwrap_or_default();
    let slosh = lock
        .split("[[package]]")
        .find(|p| p.contains("name = \"slosh3d\""))
        .and_then(|p| p.lines().find_map(|l| l.strip_prefix("version = \"")))
        .map(|v| v.trim_end_matches('"').to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=PEER_SLOSH_VERSION={slosh}");
}
