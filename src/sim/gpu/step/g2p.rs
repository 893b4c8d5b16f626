//! `shaders/sim/step/g2p.wgsl`: per particle: velocity, C, F and position from the grid,
//! then the material's plasticity (G2P); then what [`super::Prepare`] would compute for
//! the next step (the affine term, and on the gather path the sort key), so that only the
//! first step of a submission prepares.

use crate::gpu::Kernel;
use crate::sim::model::ModelsUsed;

use super::{pages, per_page, BindAt, Bound, Extent, Pass, Step, StepBuffers, MAT3, SCALAR, VEC4};

pub(crate) struct G2p {
    kernel: Kernel,
}

impl G2p {
    /// With `next_keys` (the gather path), G2P also writes the next step's sort keys;
    /// with `separation`, each particle reads its own field (two-field separation compiled
    /// in); with `actions`, the timed actions act on their particles.
    pub fn new(
        device: &wgpu::Device,
        (next_keys, separation, actions): (bool, bool, bool),
        used: &ModelsUsed,
    ) -> Self {
        let src = super::step_source(used)
            .define("NEXT_KEYS", next_keys)
            .define("SEPARATION", separation)
            .define("ACTIONS", actions)
            .pass(include_str!("../../../../shaders/sim/step/g2p.wgsl"));
        G2p {
            kernel: Kernel::new(device, "sim g2p", &src, "main"),
        }
    }

    /// Bind page `i` of the particles (`gpu::pages`): windows of the particle arrays.
    fn bind_page(&self, device: &wgpu::Device, b: &StepBuffers, i: u32) -> wgpu::BindGroup {
        use wgpu::BindingResource::Buffer;
        self.kernel.bind_named_resources(
            device,
            &[
                ("step", b.step.as_entire_binding()),
                ("page", Buffer(b.pages.entry(i))),
                ("x_mass", Buffer(b.window(&b.x_mass, i, VEC4))),
                ("v_volume", Buffer(b.window(&b.v_volume, i, VEC4))),
                ("deformation", Buffer(b.window(&b.deformation, i, MAT3))),
                (
                    "affine_velocity",
                    Buffer(b.window(&b.affine_velocity, i, MAT3)),
                ),
                ("alpha", Buffer(b.window(&b.alpha, i, SCALAR))),
                ("material", Buffer(b.window(&b.material, i, SCALAR))),
                ("grid_velocity", b.grid_velocity.binding()),
                ("grid_velocity_change", b.grid_velocity_change.binding()),
                ("flags", b.flags.as_entire_binding()),
                ("block_slot", b.block_slot.as_entire_binding()),
                ("affine", Buffer(b.window(&b.affine, i, MAT3))),
                ("cell_keys", Buffer(b.window(&b.keys, i, SCALAR))),
                ("cell_values", Buffer(b.window(&b.values, i, SCALAR))),
                // Two-field separation runs on one page: whole buffers (one element
                // each, unread, without it).
                ("damage_gradient", b.damage_gradient.as_entire_binding()),
                ("ridge", b.ridge.as_entire_binding()),
                ("far_field", b.far_field.as_entire_binding()),
            ],
        )
    }
}

impl Pass<Step> for G2p {
    fn name(&self) -> &'static str {
        "g2p"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        per_page(at.b, |i| self.bind_page(device, at.b, i))
    }

    /// One invocation per particle of the page.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        for (bind, n) in pages(bound, at) {
            self.kernel.dispatch(c, bind, n.div_ceil(256));
        }
    }
}
