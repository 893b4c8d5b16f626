//! Relighting on the GPU (docs/method.md §8, docs/relighting.md): the state of the
//! shadow volume (the transmittance only of the voxels the shade pass will read) and of
//! the Blinn-Phong shade pass; the passes are in [`passes`] (`lighting/passes.rs`), all
//! sharing `shaders/render/lighting.wgsl`. The renderer runs the shadow passes and the
//! shade pass right after projecting (which culls), so the rasteriser composites shaded
//! colours. CPU twins: [`crate::relight`].

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wgpu::util::DeviceExt;

mod passes;

use super::COMMON;
use crate::gpu::wgsl::Module;
use crate::gpu::{GpuContext, GpuError};
use crate::relight::shadow::VolumeGrid;
use crate::relight::{PointLight, ShadingParams, MAX_LIGHTS};
pub(crate) use passes::{Shade, Shadows};

pub(crate) static LIGHTING: Module = Module {
    name: "render/lighting",
    text: include_str!("../../../shaders/render/lighting.wgsl"),
    needs: &[&COMMON],
};

/// `Lights` of `lighting.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightsGpu {
    pub ambient: [f32; 4],
    pub count: u32,
    pub shadows: u32,
    pub _pad: [u32; 2],
    pub position: [[f32; 4]; MAX_LIGHTS],
    pub radiance: [[f32; 4]; MAX_LIGHTS],
    pub volume_lo_h: [f32; 4],
    pub volume_res: [u32; 4],
}

/// `ShadeMaterial` of `lighting.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadeMaterialGpu {
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
}

/// What the renderer needs to relight a set of Gaussians (fixed for a run; the lights move
/// per frame through [`super::GpuRenderer::set_lights`]).
#[derive(Clone, Debug)]
pub struct LightingSetup {
    /// Ambient light I_a.
    pub ambient: Vec3,
    /// Shading weights, indexed by `shading[i][1]`.
    pub materials: Vec<ShadingParams>,
    /// Per Gaussian: packed normal ([`crate::relight::oct_encode`]) and material index.
    pub shading: Vec<[u32; 2]>,
    /// The shadow volume, or None for no shadows.
    pub shadows: Option<VolumeGrid>,
    /// The most lights any frame will have (sizes the transmittance volume).
    pub max_lights: usize,
}

/// The GPU state of relighting.
pub(crate) struct Lighting {
    pub shadows: Shadows,
    pub shade: Shade,
    pub lights: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    /// Per Gaussian `vec2<u32>`: packed normal, material.
    pub shading: wgpu::Buffer,
    pub depth: wgpu::Buffer,
    pub transmittance: wgpu::Buffer,
    /// Per light and voxel, whether the shade pass reads it this frame (`shadow_mark.wgsl`).
    pub asked: wgpu::Buffer,
    /// The asked (light, voxel) pairs as transmittance indices.
    pub asked_list: wgpu::Buffer,
    /// Indirect dispatch of the transmittance pass over `asked_list`, and its length.
    pub transmit_args: wgpu::Buffer,
    pub count: wgpu::Buffer,
    pub grid: Option<VolumeGrid>,
    pub ambient: Vec3,
    pub frame_lights: Vec<PointLight>,
    pub max_lights: usize,
    /// The shading records as uploaded (rest normals of simulated Gaussians for derive).
    pub rest_shading: Vec<[u32; 2]>,
}

impl Lighting {
    pub fn new(gpu: &GpuContext, setup: &LightingSetup) -> Result<Lighting, GpuError> {
        let device = &gpu.device;
        if setup.materials.is_empty() && !setup.shading.is_empty() {
            return Err(GpuError::Failed(
                "lighting: no shading materials".to_string(),
            ));
        }
        let max_lights = setup.max_lights.clamp(1, MAX_LIGHTS);
        let voxels = setup.shadows.map_or(1, |g| g.voxels()) as u64;
        let transmittance_bytes = voxels * max_lights as u64 * 4;
        if transmittance_bytes > gpu.max_binding() {
            return Err(GpuError::Failed(format!(
                "the shadow volume ({voxels} voxels × {max_lights} lights) needs {} MiB, more than this adapter's {} MiB per buffer; lower lighting.shadows.resolution",
                transmittance_bytes >> 20,
                gpu.max_binding() >> 20
            )));
        }
        let materials: Vec<ShadeMaterialGpu> = setup
            .materials
            .iter()
            .map(|m| ShadeMaterialGpu {
                ambient: m.ambient,
                diffuse: m.diffuse,
                specular: m.specular,
                shininess: m.shininess,
            })
            .chain(std::iter::once(ShadeMaterialGpu::zeroed()))
            .collect();
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
            })
        };
        let mut shading_bytes = bytemuck::cast_slice::<[u32; 2], u8>(&setup.shading).to_vec();
        shading_bytes.resize(shading_bytes.len().max(8), 0);
        let count = setup.shading.len() as u32;
        let zeroed = |label: &str, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        Ok(Lighting {
            shadows: Shadows::new(device),
            shade: Shade::new(device),
            lights: zeroed("lights", std::mem::size_of::<LightsGpu>() as u64),
            materials: init("shade materials", bytemuck::cast_slice(&materials)),
            shading: init("shading", &shading_bytes),
            depth: zeroed("shadow optical depth", voxels * 4),
            transmittance: zeroed("shadow transmittance", transmittance_bytes),
            asked: zeroed("shadow voxels asked", transmittance_bytes),
            asked_list: zeroed("shadow voxels asked, listed", transmittance_bytes),
            transmit_args: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow transmittance dispatch"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::INDIRECT
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            count: init("lighting count", bytemuck::bytes_of(&[count, 0, 0, 0])),
            grid: setup.shadows,
            ambient: setup.ambient,
            frame_lights: Vec::new(),
            max_lights,
            rest_shading: setup.shading.clone(),
        })
    }

    /// The per-frame constants for the current lights.
    pub fn uniforms(&self) -> LightsGpu {
        let mut u = LightsGpu::zeroed();
        u.ambient = self.ambient.extend(0.0).to_array();
        let n = self.frame_lights.len().min(self.max_lights);
        u.count = n as u32;
        for (i, l) in self.frame_lights.iter().take(n).enumerate() {
            u.position[i] = l.position.extend(1.0).to_array();
            u.radiance[i] = l.radiance.extend(0.0).to_array();
        }
        if let Some(g) = self.grid {
            u.shadows = 1;
            u.volume_lo_h = g.lo.extend(g.h).to_array();
            u.volume_res = g.res.extend(0).to_array();
        }
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    /// The renderer's shared modules say in their `// Needs:` lines what their Rust
    /// `Module`s include before them.
    #[test]
    fn render_modules_declare_what_they_need() {
        use crate::gpu::wgsl::declared_needs;
        for m in [&COMMON, &super::super::SH, &LIGHTING] {
            let listed: Vec<&str> = m.needs.iter().map(|n| n.name).collect();
            assert_eq!(declared_needs(m.text), listed, "{}", m.name);
        }
    }

    #[test]
    fn layouts_match_wgsl() {
        let src = crate::gpu::wgsl::Source::new().module(&LIGHTING).pass("");
        assert_layout!(
            &src,
            LightsGpu,
            "Lights",
            [
                ambient,
                count,
                shadows,
                position,
                radiance,
                volume_lo_h,
                volume_res
            ]
        );
        assert_layout!(
            &src,
            ShadeMaterialGpu,
            "ShadeMaterial",
            [ambient, diffuse, specular, shininess]
        );
    }
}
