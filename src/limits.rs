//! Sizes checked against the adapter's buffer limits before anything is allocated on the
//! GPU, so that a scene too large for the adapter stops with one message saying what to
//! reduce, instead of a validation error (or an out-of-memory abort) midway.
//!
//! The byte counts mirror the allocations of [`GpuSim`](crate::sim::gpu::GpuSim) and
//! [`GpuRenderer`](crate::render::GpuRenderer); each buffer must fit one storage binding
//! ([`GpuContext::max_binding`]: `max_storage_buffer_binding_size` and `max_buffer_size`).

use crate::gpu::GpuContext;
use glam::UVec3;

/// One buffer a run will allocate.
#[derive(Clone, Debug, PartialEq)]
pub struct Need {
    pub what: String,
    pub bytes: u64,
    pub advice: &'static str,
}

#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{what} needs {bytes} bytes ({mib:.1} MiB) in one GPU buffer, but {adapter} allows at most {limit} bytes ({limit_mib:.1} MiB); {advice}", mib = *bytes as f64 / 1048576.0, limit_mib = *limit as f64 / 1048576.0)]
pub struct LimitError {
    pub what: String,
    pub bytes: u64,
    pub limit: u64,
    pub adapter: String,
    pub advice: &'static str,
}

const FEWER_GAUSSIANS: &str = "render fewer Gaussians (a larger procedural spacing, a smaller or pruned PLY, fewer objects) or use a GPU with larger buffers";
const FEWER_PARTICLES: &str = "simulate fewer particles (a larger physics.particles spacing, smaller or fewer objects with physics) or use a GPU with larger buffers";
const FEWER_SIMULATED: &str = "simulate fewer Gaussians (a larger procedural spacing, physics.select or min_opacity to leave some static) or use a GPU with larger buffers";
const SMALLER_GRID: &str =
    "use a coarser or smaller grid (a larger simulation.dx, or a smaller simulation.domain)";
const SMALLER_IMAGE: &str = "render a smaller image (--width/--height or output.width/height)";

/// The renderer's largest buffers for `gaussians` Gaussians and a `width`×`height` image.
pub fn render_needs(gaussians: usize, width: u32, height: u32) -> Vec<Need> {
    let n = gaussians as u64;
    let sh_bytes = crate::render::gpu::layout::SH_WORDS as u64 * 4;
    let record = std::mem::size_of::<crate::render::gpu::layout::GaussianIn>() as u64;
    vec![
        Need {
            what: format!("the Gaussian records of {n} Gaussians"),
            bytes: n * record,
            advice: FEWER_GAUSSIANS,
        },
        Need {
            what: format!("the SH coefficients of {n} Gaussians"),
            bytes: n * sh_bytes,
            advice: FEWER_GAUSSIANS,
        },
        Need {
            what: format!("the projected Gaussians of {n} Gaussians"),
            bytes: n * 48,
            advice: FEWER_GAUSSIANS,
        },
        Need {
            what: format!("a {width}×{height} image"),
            bytes: u64::from(width) * u64::from(height) * 4,
            advice: SMALLER_IMAGE,
        },
    ]
}

/// The simulation's largest buffers for `particles` particles on a grid of `cells` cells
/// per axis ([`Grid::cells`](crate::sim::Grid)).
pub fn sim_needs(particles: usize, cells: UVec3) -> Vec<Need> {
    let n = particles as u64;
    let nodes: u64 = cells.to_array().iter().map(|c| u64::from(*c) + 1).product();
    let cell_count: u64 = cells.to_array().iter().map(|c| u64::from(*c)).product();
    vec![
        Need {
            what: format!("the deformation gradients of {n} particles"),
            bytes: n * 48,
            advice: FEWER_PARTICLES,
        },
        Need {
            what: format!(
                "the grid of {}×{}×{} nodes",
                cells.x + 1,
                cells.y + 1,
                cells.z + 1
            ),
            bytes: nodes * 16,
            advice: SMALLER_GRID,
        },
        Need {
            what: format!("the cell ranges of {cell_count} grid cells"),
            bytes: (cell_count + 1) * 8,
            advice: SMALLER_GRID,
        },
    ]
}

/// The derive pass's rest records ([`RestGaussian`](crate::derive::RestGaussian): rest
/// look and binding) of `gaussians` simulated Gaussians.
pub fn derive_needs(gaussians: usize) -> Vec<Need> {
    let record = std::mem::size_of::<crate::derive::RestGaussian>() as u64;
    vec![Need {
        what: format!("the rest records of {gaussians} simulated Gaussians"),
        bytes: gaussians as u64 * record,
        advice: FEWER_SIMULATED,
    }]
}

/// The first need above `limit`, as an error naming `adapter`.
pub fn check(needs: &[Need], limit: u64, adapter: &str) -> Result<(), LimitError> {
    for need in needs {
        if need.bytes > limit {
            return Err(LimitError {
                what: need.what.clone(),
                bytes: need.bytes,
                limit,
                adapter: adapter.to_owned(),
                advice: need.advice,
            });
        }
    }
    Ok(())
}

/// [`check`] against `gpu`'s limits.
pub fn check_gpu(gpu: &GpuContext, needs: &[Need]) -> Result<(), LimitError> {
    check(needs, gpu.max_binding(), &gpu.describe())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(cells: u32) -> UVec3 {
        UVec3::splat(cells)
    }

    #[test]
    fn sizes_under_the_limit_pass_and_over_it_name_what_to_reduce() {
        let limit = 128 << 20;
        check(&render_needs(1_000_000, 1920, 1080), limit, "test").unwrap();
        check(&sim_needs(1_000_000, grid(128)), limit, "test").unwrap();

        let e = check(&render_needs(3_000_000, 64, 64), limit, "lavapipe").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("3000000 Gaussians") && msg.contains("lavapipe"),
            "{msg}"
        );
        assert!(msg.contains("fewer Gaussians"), "{msg}");

        let e = check(&render_needs(10, 16384, 16384), limit, "x").unwrap_err();
        assert!(e.to_string().contains("16384×16384 image"), "{e}");
        assert!(e.to_string().contains("--width"), "{e}");

        let e = check(&sim_needs(10, grid(400)), limit, "x").unwrap_err();
        assert!(e.to_string().contains("401×401×401 nodes"), "{e}");
        assert!(e.to_string().contains("simulation.dx"), "{e}");

        let e = check(&sim_needs(4_000_000, grid(16)), limit, "x").unwrap_err();
        assert!(e.to_string().contains("4000000 particles"), "{e}");
    }
}
