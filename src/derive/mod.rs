//! The derive stage: the simulation's state turned into the renderer's Gaussians, on the
//! GPU and without a readback. Deforming the Gaussians (docs/method.md §6):
//! `shaders/sim/derive.wgsl` writes each simulated Gaussian — moved by the particle it is
//! bound to ([`binding`]): mean x_p + F (X_g − X_p), covariance F A Fᵀ, rest frame rotated
//! by polar(F) — into the renderer's Gaussian buffer, so a frame goes from simulation to
//! image without a CPU round trip. [`derive_gaussian`] is the f64 twin the pass is tested
//! against. Kinematic objects move rigidly ([`RigidDerive`]); simulated objects' normals are
//! refitted in the deformed configuration by [`normals`].

pub mod binding;
pub mod normals;

pub use binding::Binding;

use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DQuat, DVec3};
use wgpu::util::DeviceExt;

use crate::gpu::pass::{Bound, Family, Pass};
use crate::gpu::{GpuContext, GpuError, Kernel};
use crate::render::{GpuRenderer, Splats};
use crate::sim::gpu::GpuSim;
use crate::sim::svd::polar;
use crate::splat::{mat3_from_sym3, Sym3};

/// `DeriveParams` of the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct DeriveParams {
    pub offset: u32,
    pub count: u32,
    /// 1: write the transported normals into the renderer's shading records.
    pub normals: u32,
    pub _pad: u32,
}

/// `RestGaussian` of the shader: a simulated Gaussian at rest (world space) and its binding.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RestGaussian {
    pub cov_a: [f32; 4],
    pub cov_b: [f32; 4],
    pub rotation: [f32; 4],
    /// X_g − X_p, and the particle's index as bits.
    pub anchor: [f32; 4],
}

/// The deformed Gaussian of a particle at `x` with deformation gradient `f`, whose rest
/// covariance is `a` and rest-frame rotation `r0` (docs/method.md §6).
pub fn derive_gaussian(x: DVec3, f: DMat3, a: DMat3, r0: DQuat) -> (DVec3, DMat3, DQuat) {
    let (r, _) = polar(f);
    (
        x,
        f * a * f.transpose(),
        (DQuat::from_mat3(&r) * r0).normalize(),
    )
}

/// The deformed normal of a Gaussian with rest normal `n0` (docs/method.md §8): n = F⁻ᵀ n₀,
/// normalised (the twin of the normal transport in `shaders/sim/derive.wgsl`).
pub fn derive_normal(f: DMat3, n0: DVec3) -> DVec3 {
    (f.inverse().transpose() * n0).normalize()
}

/// The derive pass for one simulation whose Gaussians are `offset .. offset +
/// binding.len()` of the renderer's buffer, each moved by the particle `binding` names.
pub struct Derive {
    pass: DerivePass,
    bound: Bound,
    count: u32,
    _buffers: [wgpu::Buffer; 3],
}

/// The derive pass's family (`gpu::pass`, the shape of every pass): it binds over the
/// particles' state, its rest Gaussians and the renderer's buffers, and dispatches over its
/// Gaussians.
pub(crate) struct Deriving;

impl Family for Deriving {
    type Inputs<'a> = DeriveInputs<'a>;
    type Extent<'a> = u32;
}

/// What the derive pass binds over.
pub(crate) struct DeriveInputs<'a> {
    params: &'a wgpu::Buffer,
    x_mass: &'a wgpu::Buffer,
    deformation: &'a wgpu::Buffer,
    rest: &'a wgpu::Buffer,
    gaussians: &'a wgpu::Buffer,
    shading: &'a wgpu::Buffer,
}

/// `shaders/sim/derive.wgsl`.
struct DerivePass(Kernel);

impl Pass<Deriving> for DerivePass {
    fn name(&self) -> &'static str {
        "derive"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut DeriveInputs) -> Bound {
        Bound::Whole(self.0.bind_named(
            device,
            &[
                ("params", at.params),
                ("x_mass", at.x_mass),
                ("deformation", at.deformation),
                ("rest", at.rest),
                ("gaussians", at.gaussians),
                ("shading", at.shading),
            ],
        ))
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, gaussians: &u32) {
        self.0.dispatch(c, bound.whole(), gaussians.div_ceil(256));
    }
}

impl Derive {
    /// `splats` are all the renderer's Gaussians (as uploaded); the simulated ones start at
    /// `offset`, and `binding` says which of `sim`'s particles moves each of them.
    pub fn new(
        gpu: &GpuContext,
        sim: &GpuSim,
        renderer: &GpuRenderer,
        splats: &Splats,
        offset: u32,
        binding: &Binding,
    ) -> Result<Derive, GpuError> {
        if let Some(&p) = binding.particle.iter().find(|&&p| p >= sim.len()) {
            return Err(GpuError::Failed(format!(
                "derive: a Gaussian is bound to particle {p} of a simulation of {}",
                sim.len()
            )));
        }
        let (x_mass, deformation) = sim.state_buffers();
        Self::over(
            gpu,
            (x_mass, deformation),
            binding,
            renderer,
            splats,
            offset,
        )
    }

    /// As [`new`](Self::new) for particles whose positions (`vec4`, xyz) and deformation
    /// gradients (`mat3x3`) are in `state`.
    fn over(
        gpu: &GpuContext,
        state: (&wgpu::Buffer, &wgpu::Buffer),
        binding: &Binding,
        renderer: &GpuRenderer,
        splats: &Splats,
        offset: u32,
    ) -> Result<Derive, GpuError> {
        let count = binding.len() as u32;
        let end = offset as usize + count as usize;
        let target = renderer
            .gaussian_buffer()
            .filter(|_| end <= splats.len())
            .ok_or_else(|| {
                GpuError::Failed(format!(
                    "derive: Gaussians {offset}..{end} are not all uploaded to the renderer"
                ))
            })?;
        // With relighting on, the rest normals ride in cov_b.w (as bits).
        let rest_shading = renderer.rest_shading();
        let rest: Vec<RestGaussian> = (offset as usize..end)
            .map(|i| {
                let normal = rest_shading.map_or(0, |s| s[i][0]);
                let c: Sym3 = splats.covariances[i];
                let q = splats.rotations[i];
                let k = i - offset as usize;
                let d = binding.offset[k];
                RestGaussian {
                    cov_a: [c[0], c[1], c[2], c[3]],
                    cov_b: [c[4], c[5], splats.opacities[i], f32::from_bits(normal)],
                    rotation: [q.x, q.y, q.z, q.w],
                    anchor: [d.x, d.y, d.z, f32::from_bits(binding.particle[k])],
                }
            })
            .collect();
        let device = &gpu.device;
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("derive params"),
            contents: bytemuck::bytes_of(&DeriveParams {
                offset,
                count,
                normals: u32::from(rest_shading.is_some()),
                _pad: 0,
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut rest_bytes = bytemuck::cast_slice::<RestGaussian, u8>(&rest).to_vec();
        rest_bytes.resize(rest_bytes.len().max(256), 0);
        let rest = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("derive rest Gaussians"),
            contents: &rest_bytes,
            usage: wgpu::BufferUsages::STORAGE,
        });
        let pass = DerivePass(Kernel::new(device, "derive", &source(), "main"));
        let (x_mass, deformation) = state;
        let stand_in = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("derive no shading"),
            size: 256,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let shading = renderer.shading_buffer().unwrap_or(&stand_in);
        let mut inputs = DeriveInputs {
            params: &params,
            x_mass,
            deformation,
            rest: &rest,
            gaussians: target,
            shading,
        };
        let bound = pass.bind(device, &mut inputs);
        Ok(Derive {
            pass,
            bound,
            count,
            _buffers: [params, rest, stand_in],
        })
    }

    /// Record the pass.
    pub fn record(&self, cpass: &mut wgpu::ComputePass) {
        self.pass.record(cpass, &self.bound, &self.count);
    }

    /// Record and submit the pass on its own.
    pub fn run(&self, gpu: &GpuContext) -> Result<(), GpuError> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.record(&mut enc.begin_compute_pass(&Default::default()));
        gpu.queue.submit([enc.finish()]);
        gpu.check()
    }
}

/// Gaussians moved rigidly (a kinematic object, `scene::kinematic`): the derive pass with
/// F = A and x = A x₀ + b per Gaussian, so covariances, SH frames and normals turn exactly
/// as a simulated particle's would. The positions are written from the CPU per frame (one
/// `vec4` and one `mat3x3` per Gaussian: small next to a frame's render).
pub struct RigidDerive {
    derive: Derive,
    rest: Vec<DVec3>,
    x: wgpu::Buffer,
    f: wgpu::Buffer,
}

impl RigidDerive {
    /// The Gaussians `offset .. offset + count` of `splats` (all the renderer's Gaussians,
    /// as uploaded).
    pub fn new(
        gpu: &GpuContext,
        renderer: &GpuRenderer,
        splats: &Splats,
        offset: u32,
        count: u32,
    ) -> Result<RigidDerive, GpuError> {
        let range = offset as usize..(offset + count) as usize;
        let rest: Vec<DVec3> = splats.means[range.clone()]
            .iter()
            .map(|m| m.as_dvec3())
            .collect();
        let buffer = |label, bytes: u64| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(256),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let x = buffer("rigid positions", u64::from(count) * 16);
        let f = buffer("rigid rotations", u64::from(count) * 48);
        let binding = Binding::identity(0, count as usize);
        let derive = Derive::over(gpu, (&x, &f), &binding, renderer, splats, offset)?;
        Ok(RigidDerive { derive, rest, x, f })
    }

    /// Write the Gaussians moved by x ↦ `a` x + `b` (a rotation) into the renderer's buffer.
    pub fn run(&self, gpu: &GpuContext, a: DMat3, b: DVec3) -> Result<(), GpuError> {
        let x: Vec<[f32; 4]> = self
            .rest
            .iter()
            .map(|p| (a * *p + b).as_vec3().extend(0.0).to_array())
            .collect();
        let m = a.as_mat3();
        let col = |v: glam::Vec3| v.extend(0.0).to_array();
        let f = vec![[col(m.x_axis), col(m.y_axis), col(m.z_axis)]; self.rest.len()];
        if !x.is_empty() {
            gpu.queue.write_buffer(&self.x, 0, bytemuck::cast_slice(&x));
            gpu.queue.write_buffer(&self.f, 0, bytemuck::cast_slice(&f));
        }
        self.derive.run(gpu)
    }
}

fn source() -> String {
    crate::sim::gpu::wgsl::library_source()
        .module(&crate::render::gpu::lighting::LIGHTING)
        .pass(include_str!("../../shaders/sim/derive.wgsl"))
}

/// The rest covariance of Gaussian `i` of `splats` as a matrix (for the CPU twin).
pub fn rest_covariance(splats: &Splats, i: usize) -> DMat3 {
    mat3_from_sym3(splats.covariances[i]).as_dmat3()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn layouts_match_wgsl() {
        let src = source();
        assert_layout!(&src, DeriveParams, "DeriveParams", [offset, count]);
        assert_layout!(
            &src,
            RestGaussian,
            "RestGaussian",
            [cov_a, cov_b, rotation, anchor]
        );
    }
}
