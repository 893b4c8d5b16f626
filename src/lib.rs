//! splatter: a headless simulator and renderer for 3D Gaussian Splatting scenes.
//!
//! The pipeline (see `docs/architecture.md`): **build** (scene file → Gaussians, CPU) →
//! **simulate** (MPM, GPU) → **derive** (deformed Gaussians) → **render**
//! (tile-based splatting, GPU) → PNG frames (writer thread).

// The modules' documentation is written for the engineers who read the code: it names the
// private pass types in the order they run, and those links resolve in
// `cargo doc --document-private-items`.
#![allow(rustdoc::private_intra_doc_links)]

/// This program's version, as written into checkpoints and manifests.
pub const PROGRAM_VERSION: &str = env!("CARGO_PKG_VERSION");

pub mod bench;
pub mod checkpoint;
pub mod derive;
pub mod farm;
pub mod files;
pub mod fragments;
pub mod frames;
pub mod gpu;
pub mod limits;
pub mod output;
pub mod relight;
pub mod render;
pub mod rng;
pub mod run;
pub mod scene;
pub mod sim;
pub mod splat;
pub mod spline;
