//! The lighting passes, one type per WGSL file under `shaders/render/`, each binding the
//! buffers of [`Lighting`] and of the frame by the names its WGSL declares:
//!
//! 1. [`ShadowSplat`] — every Gaussian's density splatted into the shadow volume's optical
//!    depth;
//! 2. [`ShadowMark`] — the (light, voxel) pairs the shade pass will read, listed, and the
//!    transmittance pass's dispatch size;
//! 3. [`ShadowTransmit`] — the transmittance along each listed voxel's ray to its light;
//! 4. [`Shade`] — Blinn-Phong of each visible Gaussian's projected colour.
//!
//! In a frame, 1–3 are the one [`Shadows`] pass of the [`Render`] family (with shadows
//! on), and [`Shade`] the next.

use super::{Lighting, LIGHTING};
use crate::gpu::pass::{Bound, Pass};
use crate::gpu::wgsl::Source;
use crate::gpu::Kernel;
use crate::render::gpu::{FrameExtent, FrameInputs, Render};

fn kernel(device: &wgpu::Device, label: &'static str, pass: &str) -> Kernel {
    Kernel::new(
        device,
        label,
        &Source::new().module(&LIGHTING).pass(pass),
        "main",
    )
}

/// `shaders/render/shadow_splat.wgsl`.
struct ShadowSplat(Kernel);

impl ShadowSplat {
    fn new(device: &wgpu::Device) -> ShadowSplat {
        ShadowSplat(kernel(
            device,
            "shadow_splat",
            include_str!("../../../../shaders/render/shadow_splat.wgsl"),
        ))
    }

    fn bind(&self, device: &wgpu::Device, l: &Lighting, f: &FrameInputs) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("lights", &l.lights),
                ("gaussians", &f.s.gaussians),
                ("depth", &l.depth),
                ("count", &l.count),
            ],
        )
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, gaussians: u32) {
        self.0.dispatch(c, bind, gaussians.div_ceil(256));
    }
}

/// `shaders/render/shadow_mark.wgsl`.
struct ShadowMark(Kernel);

impl ShadowMark {
    fn new(device: &wgpu::Device) -> ShadowMark {
        ShadowMark(kernel(
            device,
            "shadow_mark",
            include_str!("../../../../shaders/render/shadow_mark.wgsl"),
        ))
    }

    fn bind(&self, device: &wgpu::Device, l: &Lighting, f: &FrameInputs) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("frame", f.frame),
                ("lights", &l.lights),
                ("gaussians", &f.s.gaussians),
                ("shading", &l.shading),
                ("depth_keys", &f.s.depth_keys),
                ("asked", &l.asked),
                ("asked_list", &l.asked_list),
                ("transmit_args", &l.transmit_args),
            ],
        )
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, gaussians: u32) {
        self.0.dispatch(c, bind, gaussians.div_ceil(256));
    }
}

/// `shaders/render/shadow_transmit.wgsl`.
struct ShadowTransmit(Kernel);

impl ShadowTransmit {
    fn new(device: &wgpu::Device) -> ShadowTransmit {
        ShadowTransmit(kernel(
            device,
            "shadow_transmit",
            include_str!("../../../../shaders/render/shadow_transmit.wgsl"),
        ))
    }

    fn bind(&self, device: &wgpu::Device, l: &Lighting) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("lights", &l.lights),
                ("depth", &l.depth),
                ("transmittance", &l.transmittance),
                ("asked_list", &l.asked_list),
                ("transmit_args", &l.transmit_args),
            ],
        )
    }

    /// As many workgroups as [`ShadowMark`] wrote into `transmit_args`.
    fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, l: &Lighting) {
        self.0.dispatch_indirect(c, bind, &l.transmit_args, 0);
    }
}

/// `shaders/render/shade.wgsl`.
pub(crate) struct Shade(Kernel);

impl Shade {
    pub fn new(device: &wgpu::Device) -> Shade {
        Shade(kernel(
            device,
            "shade",
            include_str!("../../../../shaders/render/shade.wgsl"),
        ))
    }
}

/// The shadow volume of a frame: [`ShadowSplat`], [`ShadowMark`], [`ShadowTransmit`].
pub(crate) struct Shadows {
    splat: ShadowSplat,
    mark: ShadowMark,
    transmit: ShadowTransmit,
}

impl Shadows {
    pub fn new(device: &wgpu::Device) -> Shadows {
        Shadows {
            splat: ShadowSplat::new(device),
            mark: ShadowMark::new(device),
            transmit: ShadowTransmit::new(device),
        }
    }
}

impl Pass<Render> for Shadows {
    fn name(&self) -> &'static str {
        "shadows"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let l = at.lighting();
        Bound::Parts(vec![
            Bound::Whole(self.splat.bind(device, l, at)),
            Bound::Whole(self.mark.bind(device, l, at)),
            Bound::Whole(self.transmit.bind(device, l)),
        ])
    }

    /// The optical depth it splats into, the voxels asked for and their count.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &FrameExtent) {
        let l = at.lighting();
        enc.clear_buffer(&l.depth, 0, None);
        enc.clear_buffer(&l.asked, 0, None);
        enc.clear_buffer(&l.transmit_args, 0, None);
    }

    /// After the projection, which culls: only what is shaded asks for shadows.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &FrameExtent) {
        let [splat, mark, transmit] = bound.parts() else {
            unreachable!("shadows bound otherwise")
        };
        self.splat.record(c, splat.whole(), at.count);
        self.mark.record(c, mark.whole(), at.count);
        self.transmit.record(c, transmit.whole(), at.lighting());
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

impl Pass<Render> for Shade {
    fn name(&self) -> &'static str {
        "shade"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let (l, s) = (at.lighting(), at.s);
        Bound::Whole(self.0.bind_named(
            device,
            &[
                ("frame", at.frame),
                ("lights", &l.lights),
                ("gaussians", &s.gaussians),
                ("shading", &l.shading),
                ("materials", &l.materials),
                ("transmittance", &l.transmittance),
                ("depth_keys", &s.depth_keys),
                ("projected", &s.projected),
            ],
        ))
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &FrameExtent) {
        self.0.dispatch(c, bound.whole(), at.count.div_ceil(256));
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}
