//! `shaders/sim/step/prepare.wgsl`: per particle: the base-cell sort key and the affine
//! term m C − Δt V⁰ (4/Δx²) τ(F) (P2G, part 1).

use crate::gpu::Kernel;
use crate::sim::model::ModelsUsed;

use super::{
    material_kernel, pages, per_page, BindAt, Bound, Extent, Pass, Step, StepBuffers, MAT3, SCALAR,
    VEC4,
};

/// Runs at the first step of a submission only: G2P leaves the next step's affine term
/// and sort keys ([`super::G2p`]).
pub(crate) struct Prepare {
    kernel: Kernel,
}

impl Prepare {
    pub fn new(device: &wgpu::Device, used: &ModelsUsed) -> Self {
        let src = include_str!("../../../../shaders/sim/step/prepare.wgsl");
        Prepare {
            kernel: material_kernel(device, "sim prepare", src, used),
        }
    }

    /// Bind page `i` of the particles (`gpu::pages`): windows of the particle arrays.
    fn bind_page(&self, device: &wgpu::Device, b: &StepBuffers, i: u32) -> wgpu::BindGroup {
        self.kernel.bind_named_parts(
            device,
            &[
                ("step", b.step.as_entire_buffer_binding()),
                ("page", b.pages.entry(i)),
                ("x_mass", b.window(&b.x_mass, i, VEC4)),
                ("v_volume", b.window(&b.v_volume, i, VEC4)),
                ("deformation", b.window(&b.deformation, i, MAT3)),
                ("affine_velocity", b.window(&b.affine_velocity, i, MAT3)),
                ("material", b.window(&b.material, i, SCALAR)),
                ("cell_keys", b.window(&b.keys, i, SCALAR)),
                ("cell_values", b.window(&b.values, i, SCALAR)),
                ("affine", b.window(&b.affine, i, MAT3)),
                ("alpha", b.window(&b.alpha, i, SCALAR)),
            ],
        )
    }
}

impl Pass<Step> for Prepare {
    fn name(&self) -> &'static str {
        "prepare"
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

    fn runs(&self, at: &Extent) -> bool {
        at.first
    }
}
