//! Rendering: the camera, the render input, the GPU tile rasteriser and its CPU reference.

pub mod camera;
pub mod cpu;
pub mod gpu;
pub mod splats;

pub use camera::Camera;
pub use gpu::{GpuRenderer, PassImages, PassSet, RenderedImage};
pub use splats::Splats;
