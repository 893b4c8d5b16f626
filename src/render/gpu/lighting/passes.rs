//! The lighting passes, one type per WGSL file under `shaders/render/`, each binding the
//! buffers of [`Lighting`] and of the frame by the names its WGSL declares:
//!
//! 1. [`ShadowSplat`] — every Gaussian's density splatted into the shadow volume's optical
//!    depth;
//! 2. [`ShadowMark`] — the (light, voxel) pairs the shade pass will read, listed, and the
//!    transmittance pass's dispatch size;
//! 3. [`ShadowTransmit`] — the transmittance along each listed voxel's ray to its light;
//! 4. [`Shade`] — Blinn-Phong of each visible Gaussian's projected colour.

use super::{Lighting, LIGHTING};
use crate::gpu::wgsl::Source;
use crate::gpu::Kernel;

/// What the lighting passes read of the frame and of the uploaded Gaussians.
pub(crate) struct FrameInputs<'a> {
    pub frame: &'a wgpu::Buffer,
    pub gaussians: &'a wgpu::Buffer,
    pub depth_keys: &'a wgpu::Buffer,
    pub projected: &'a wgpu::Buffer,
}

fn kernel(device: &wgpu::Device, label: &'static str, pass: &str) -> Kernel {
    Kernel::new(
        device,
        label,
        &Source::new().module(&LIGHTING).pass(pass),
        "main",
    )
}

/// `shaders/render/shadow_splat.wgsl`.
pub(crate) struct ShadowSplat(Kernel);

impl ShadowSplat {
    pub fn new(device: &wgpu::Device) -> ShadowSplat {
        ShadowSplat(kernel(
            device,
            "shadow_splat",
            include_str!("../../../../shaders/render/shadow_splat.wgsl"),
        ))
    }

    pub fn bind(&self, device: &wgpu::Device, l: &Lighting, f: &FrameInputs) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("lights", &l.lights),
                ("gaussians", f.gaussians),
                ("depth", &l.depth),
                ("count", &l.count),
            ],
        )
    }

    /// One invocation per Gaussian.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, gaussians: u32) {
        self.0.dispatch(c, bind, gaussians.div_ceil(256));
    }
}

/// `shaders/render/shadow_mark.wgsl`.
pub(crate) struct ShadowMark(Kernel);

impl ShadowMark {
    pub fn new(device: &wgpu::Device) -> ShadowMark {
        ShadowMark(kernel(
            device,
            "shadow_mark",
            include_str!("../../../../shaders/render/shadow_mark.wgsl"),
        ))
    }

    pub fn bind(&self, device: &wgpu::Device, l: &Lighting, f: &FrameInputs) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("frame", f.frame),
                ("lights", &l.lights),
                ("gaussians", f.gaussians),
                ("shading", &l.shading),
                ("depth_keys", f.depth_keys),
                ("asked", &l.asked),
                ("asked_list", &l.asked_list),
                ("transmit_args", &l.transmit_args),
            ],
        )
    }

    /// One invocation per Gaussian.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, gaussians: u32) {
        self.0.dispatch(c, bind, gaussians.div_ceil(256));
    }
}

/// `shaders/render/shadow_transmit.wgsl`.
pub(crate) struct ShadowTransmit(Kernel);

impl ShadowTransmit {
    pub fn new(device: &wgpu::Device) -> ShadowTransmit {
        ShadowTransmit(kernel(
            device,
            "shadow_transmit",
            include_str!("../../../../shaders/render/shadow_transmit.wgsl"),
        ))
    }

    pub fn bind(&self, device: &wgpu::Device, l: &Lighting) -> wgpu::BindGroup {
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
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, l: &Lighting) {
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

    pub fn bind(&self, device: &wgpu::Device, l: &Lighting, f: &FrameInputs) -> wgpu::BindGroup {
        self.0.bind_named(
            device,
            &[
                ("frame", f.frame),
                ("lights", &l.lights),
                ("gaussians", f.gaussians),
                ("shading", &l.shading),
                ("materials", &l.materials),
                ("transmittance", &l.transmittance),
                ("depth_keys", f.depth_keys),
                ("projected", f.projected),
            ],
        )
    }

    /// One invocation per Gaussian.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, gaussians: u32) {
        self.0.dispatch(c, bind, gaussians.div_ceil(256));
    }
}

/// The lighting passes' bind groups over the current buffers.
pub(crate) struct LightingBinds {
    pub splat: wgpu::BindGroup,
    pub mark: wgpu::BindGroup,
    pub transmit: wgpu::BindGroup,
    pub shade: wgpu::BindGroup,
}

impl Lighting {
    /// Bind the four passes over `f` (cheap; made per frame so that re-uploads and grown
    /// buffers need no bookkeeping).
    pub fn binds(&self, device: &wgpu::Device, f: &FrameInputs) -> LightingBinds {
        LightingBinds {
            splat: self.splat.bind(device, self, f),
            mark: self.mark.bind(device, self, f),
            transmit: self.transmit.bind(device, self),
            shade: self.shade.bind(device, self, f),
        }
    }
}
