//! Sizes checked against the adapter's buffer limits before anything is allocated on the
//! GPU, so that a scene too large for the adapter stops with one message saying what to
//! reduce, instead of a validation error (or an out-of-memory abort) midway.
//!
//! The byte counts here mirror the allocations of [`GpuRenderer`](crate::render::GpuRenderer)
//! and of the derive pass; the simulation's are `sim::gpu::plan::sim_needs`, next to the
//! path choice they depend on. An array that its passes read in pages
//! ([`crate::gpu::pages`]) must fit one buffer (`max_buffer_size`); any other must fit one
//! storage binding ([`GpuContext::max_binding`](crate::gpu::GpuContext::max_binding)).

pub use crate::gpu::limits::{check, check_gpu, Fit, LimitError, Need};

const FEWER_GAUSSIANS: &str = "render fewer Gaussians (a larger procedural spacing, a smaller or pruned PLY, fewer objects) or use a GPU with larger buffers";
const FEWER_SIMULATED: &str = "simulate fewer Gaussians (a larger procedural spacing, physics.select or min_opacity to leave some static) or use a GPU with larger buffers";
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
            advice: crate::sim::gpu::plan::FEWER_PARTICLES,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::gpu::plan::sim_needs;
    use glam::UVec3;

    fn grid(cells: u32) -> UVec3 {
        UVec3::splat(cells)
    }

    #[test]
    // Over 80 lines on purpose: one table of cases against the same two limits.
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
