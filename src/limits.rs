//! Sizes checked against the adapter's buffer limits before anything is allocated on the
//! GPU, so that a scene too large for the adapter stops with one message saying what to
//! reduce, instead of a validation error (or an out-of-memory abort) midway.
//!
//! The byte counts mirror the allocations of [`GpuSim`](crate::sim::gpu::GpuSim) and
//! [`GpuRenderer`](crate::render::GpuRenderer). An array that its passes read in pages
//! ([`crate::gpu::pages`]) must fit one buffer (`max_buffer_size`); any other must fit one
//! storage binding ([`GpuContext::max_binding`]).

use crate::gpu::GpuContext;
use glam::UVec3;

/// What a buffer must fit in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    /// One storage binding: its passes bind it whole.
    Binding,
    /// One buffer: its passes bind it in pages.
    Buffer,
}

impl Fit {
    fn place(self) -> &'static str {
        match self {
            Fit::Binding => "one GPU storage binding",
            Fit::Buffer => "one GPU buffer",
        }
    }
}

/// One buffer a run will allocate.
#[derive(Clone, Debug, PartialEq)]
pub struct Need {
    pub what: String,
    pub bytes: u64,
    pub advice: &'static str,
    pub fit: Fit,
}

#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{what} needs {bytes} bytes ({mib:.1} MiB) in {place}, but {adapter} allows at most {limit} bytes ({limit_mib:.1} MiB); {advice}", mib = *bytes as f64 / 1048576.0, limit_mib = *limit as f64 / 1048576.0)]
pub struct LimitError {
    pub what: String,
    pub place: &'static str,
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
            fit: Fit::Buffer,
        },
        Need {
            what: format!("the SH coefficients of {n} Gaussians"),
            bytes: n * sh_bytes,
            advice: FEWER_GAUSSIANS,
            fit: Fit::Buffer,
        },
        Need {
            what: format!("the projected Gaussians of {n} Gaussians"),
            bytes: n * 48,
            advice: FEWER_GAUSSIANS,
            fit: Fit::Buffer,
        },
        Need {
            what: format!("a {width}×{height} image"),
            bytes: u64::from(width) * u64::from(height) * 4,
            advice: SMALLER_IMAGE,
            fit: Fit::Binding,
        },
    ]
}

/// The simulation's largest buffers for `particles` particles on a grid of `cells` cells
/// per axis ([`Grid::cells`](crate::sim::Grid)), on the gather P2G path when `gather`. The
/// grid's nodes live in a pool of the blocks the particles reach (`GpuSim`), grown as they
/// move and capped where it stops fitting (`GpuSim::max_pool_blocks`), so the whole grid
/// needs only its block tables, 4 bytes a block of 4³ nodes; the gather path also indexes
/// every cell (its runs of sorted particles) and binds the particle arrays whole; a
/// captured surface collider (`surface`) samples its distance at every node.
pub fn sim_needs(particles: usize, cells: UVec3, gather: bool, surface: bool) -> Vec<Need> {
    let n = particles as u64;
    let nodes = cells.to_array().map(|c| u64::from(c) + 1);
    let blocks: u64 = nodes.iter().map(|n| n.div_ceil(4)).product();
    let node_count: u64 = nodes.iter().product();
    let mut needs = vec![
        Need {
            what: if gather {
                format!("the stress-affine terms of {n} particles, which the gather P2G path (two-field separation) binds whole")
            } else {
                format!("the deformation gradients of {n} particles")
            },
            bytes: n * 48,
            advice: FEWER_PARTICLES,
            fit: if gather { Fit::Binding } else { Fit::Buffer },
        },
        Need {
            what: format!(
                "the block table of a grid of {}×{}×{} nodes",
                cells.x + 1,
                cells.y + 1,
                cells.z + 1
            ),
            bytes: blocks * 4,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        },
    ];
    if surface {
        needs.push(Need {
            what: format!("the captured surface's distance at {node_count} grid nodes"),
            bytes: node_count * 4,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        });
    }
    if gather {
        needs.push(Need {
            what: format!(
                "the cell ranges of {} grid cells (gather P2G path)",
                crate::sim::gpu::gather_range_entries(cells) - 1
            ),
            bytes: crate::sim::gpu::gather_range_entries(cells) * 8,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        });
    }
    needs
}

/// The derive pass's buffers, which it binds whole: the rest records
/// ([`RestGaussian`](crate::derive::RestGaussian): rest look and binding) of `gaussians`
/// simulated Gaussians, the state of the `particles` they are bound to, and the records of
/// the `rendered` Gaussians it writes into.
pub fn derive_needs(gaussians: usize, particles: usize, rendered: usize) -> Vec<Need> {
    if gaussians == 0 {
        return Vec::new(); // nothing to derive
    }
    let record = std::mem::size_of::<crate::derive::RestGaussian>() as u64;
    let out = std::mem::size_of::<crate::render::gpu::layout::GaussianIn>() as u64;
    vec![
        Need {
            what: format!("the rest records of {gaussians} simulated Gaussians"),
            bytes: gaussians as u64 * record,
            advice: FEWER_SIMULATED,
            fit: Fit::Binding,
        },
        Need {
            what: format!(
                "the deformation gradients of {particles} particles, which the derive pass reads"
            ),
            bytes: particles as u64 * 48,
            advice: FEWER_PARTICLES,
            fit: Fit::Binding,
        },
        Need {
            what: format!("the records of {rendered} Gaussians, which the derive pass writes"),
            bytes: rendered as u64 * out,
            advice: FEWER_GAUSSIANS,
            fit: Fit::Binding,
        },
    ]
}

/// The first need above its limit (`binding` or `buffer` bytes), as an error naming
/// `adapter`.
pub fn check(needs: &[Need], binding: u64, buffer: u64, adapter: &str) -> Result<(), LimitError> {
    for need in needs {
        let limit = match need.fit {
            Fit::Binding => binding.min(buffer),
            Fit::Buffer => buffer,
        };
        if need.bytes > limit {
            return Err(LimitError {
                what: need.what.clone(),
                place: need.fit.place(),
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
    check(
        needs,
        gpu.max_binding(),
        gpu.limits.max_buffer_size,
        &gpu.describe(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(cells: u32) -> UVec3 {
        UVec3::splat(cells)
    }

    #[test]
    fn sizes_under_the_limit_pass_and_over_it_name_what_to_reduce() {
        // lavapipe's limits: bindings of 128 MiB in buffers of 2 GiB.
        let (binding, buffer) = (128 << 20, 2047 << 20);
        check(
            &render_needs(1_000_000, 1920, 1080),
            binding,
            buffer,
            "test",
        )
        .unwrap();
        check(
            &sim_needs(1_000_000, grid(128), true, true),
            binding,
            buffer,
            "test",
        )
        .unwrap();
        // Paged arrays: past one binding, within one buffer.
        check(
            &render_needs(6_000_000, 1920, 1080),
            binding,
            buffer,
            "test",
        )
        .unwrap();
        check(
            &sim_needs(27_000_000, grid(192), false, false),
            binding,
            buffer,
            "test",
        )
        .unwrap();

        let e = check(
            &render_needs(30_000_000, 64, 64),
            binding,
            buffer,
            "lavapipe",
        )
        .unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("30000000 Gaussians") && msg.contains("lavapipe"),
            "{msg}"
        );
        assert!(
            msg.contains("fewer Gaussians") && msg.contains("one GPU buffer"),
            "{msg}"
        );

        let e = check(&render_needs(10, 16384, 16384), binding, buffer, "x").unwrap_err();
        assert!(e.to_string().contains("16384×16384 image"), "{e}");
        assert!(e.to_string().contains("--width"), "{e}");
        assert!(e.to_string().contains("storage binding"), "{e}");

        // A grid of 401³ nodes: the scatter paths hold only its 1M-entry block table; the
        // gather path indexes its 64M cells.
        check(
            &sim_needs(10, grid(400), false, false),
            binding,
            buffer,
            "x",
        )
        .unwrap();
        let e = check(&sim_needs(10, grid(400), true, false), binding, buffer, "x").unwrap_err();
        assert!(e.to_string().contains("63521199 grid cells"), "{e}");
        // The gather path's ranges are per base cell: 363³ cells (362³ + 1 ranges, 379 MB
        // in a 380 MB binding) fit exactly where 363³ + 1 would not.
        let fits = 8 * (362u64.pow(3) + 1);
        check(&sim_needs(10, grid(363), true, false), fits, buffer, "x").unwrap();
        check(&sim_needs(10, grid(364), true, false), fits, buffer, "x").unwrap_err();
        assert!(e.to_string().contains("simulation.dx"), "{e}");
        let e = check(
            &sim_needs(10, grid(5000), false, false),
            binding,
            buffer,
            "x",
        )
        .unwrap_err();
        assert!(e.to_string().contains("block table"), "{e}");
        let e = check(&sim_needs(10, grid(400), false, true), binding, buffer, "x").unwrap_err();
        assert!(e.to_string().contains("surface's distance"), "{e}");

        let e = check(
            &sim_needs(50_000_000, grid(16), false, false),
            binding,
            buffer,
            "x",
        )
        .unwrap_err();
        assert!(e.to_string().contains("50000000 particles"), "{e}");
        // The gather path binds them whole: 3M particles' F is past one binding.
        let e = check(
            &sim_needs(3_000_000, grid(16), true, false),
            binding,
            buffer,
            "x",
        )
        .unwrap_err();
        assert!(e.to_string().contains("binds whole"), "{e}");

        // The derive pass binds its arrays whole.
        let e = check(&derive_needs(1000, 4_000_000, 1000), binding, buffer, "x").unwrap_err();
        assert!(
            e.to_string()
                .contains("4000000 particles, which the derive pass reads"),
            "{e}"
        );
        let e = check(&derive_needs(1000, 1000, 3_000_000), binding, buffer, "x").unwrap_err();
        assert!(
            e.to_string()
                .contains("3000000 Gaussians, which the derive pass writes"),
            "{e}"
        );
    }
}
