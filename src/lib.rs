//! splatter: a headless simulator and renderer for 3D Gaussian Splatting scenes.
//!
//! The pipeline (see `docs/architecture.md`): **build** (scene file → Gaussians, CPU) →
//! **simulate** (MPM, GPU) → **derive** (deformed Gaussians) → **render**
//! (tile-based splatting, GPU) → PNG frames (writer thread).

pub mod bench;
pub mod checkpoint;
pub mod farm;
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
pub mod study;
