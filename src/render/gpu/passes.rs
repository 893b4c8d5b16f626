//! The renderer's own passes (the sort, scan and ranges are GPU primitives in `crate::gpu`). Each type owns the
//! pipeline(s) of one WGSL file under `shaders/render/`.

use super::{shader_source, COMMON, SH};
use crate::gpu::Kernel;

/// `shaders/render/project.wgsl`.
pub struct Project {
    pub kernel: Kernel,
}

impl Project {
    pub fn new(device: &wgpu::Device) -> Project {
        let src = shader_source(&[
            COMMON,
            SH,
            include_str!("../../../shaders/render/project.wgsl"),
        ]);
        Project {
            kernel: Kernel::new(device, "project", &src, "main"),
        }
    }
}

/// `shaders/render/tile_keys.wgsl`: tile counts in depth order, their total, the pairs.
pub struct TileKeys {
    pub gather: Kernel,
    pub total: Kernel,
    pub emit: Kernel,
}

impl TileKeys {
    pub fn new(device: &wgpu::Device) -> TileKeys {
        let src = shader_source(&[
            COMMON,
            include_str!("../../../shaders/render/tile_keys.wgsl"),
        ]);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("tile_keys"),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        });
        TileKeys {
            gather: Kernel::from_module(
                device,
                "tile_keys gather_counts",
                &module,
                "gather_counts",
            ),
            total: Kernel::from_module(device, "tile_keys total", &module, "total"),
            emit: Kernel::from_module(device, "tile_keys emit", &module, "emit"),
        }
    }
}

/// `shaders/render/rasterize.wgsl`.
pub struct Rasterize {
    pub kernel: Kernel,
}

impl Rasterize {
    pub fn new(device: &wgpu::Device) -> Rasterize {
        let src = shader_source(&[
            COMMON,
            include_str!("../../../shaders/render/rasterize.wgsl"),
        ]);
        Rasterize {
            kernel: Kernel::new(device, "rasterize", &src, "main"),
        }
    }
}
