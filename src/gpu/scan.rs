//! Exclusive prefix sum on the GPU (`shaders/gpu/scan.wgsl`), in blocks of 1024 with
//! recursive scans of the block sums.

use wgpu::util::DeviceExt;

use bytemuck::{Pod, Zeroable};

use super::{Kernel, Shader};

/// `ScanParams` of `shaders/gpu/scan.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ScanParams {
    pub n: u32,
    pub _pad: [u32; 3],
}

pub const BLOCK: u32 = 1024;

pub struct Scan {
    scan_blocks: Kernel,
    add_offsets: Kernel,
}

struct Level {
    blocks: u32,
    scan_bind: wgpu::BindGroup,
    add_bind: wgpu::BindGroup,
}

/// The buffers and bind groups to scan one buffer of a fixed length.
pub struct ScanPlan {
    levels: Vec<Level>,
    _buffers: Vec<wgpu::Buffer>,
}

impl Scan {
    pub fn new(device: &wgpu::Device) -> Scan {
        let shader = Shader::new(device, "scan", include_str!("../../shaders/gpu/scan.wgsl"));
        Scan {
            scan_blocks: shader.kernel(device, "scan_blocks", "scan_blocks"),
            add_offsets: shader.kernel(device, "add_block_offsets", "add_block_offsets"),
        }
    }

    /// Plan an in-place exclusive scan of the first `n` u32 of `data`.
    pub fn plan(&self, device: &wgpu::Device, data: &wgpu::Buffer, n: u32) -> ScanPlan {
        let mut levels = Vec::new();
        let mut buffers: Vec<wgpu::Buffer> = Vec::new();
        let mut len = n.max(1);
        let mut current: Option<usize> = None; // index into `buffers`; None = `data`
        loop {
            let blocks = len.div_ceil(BLOCK);
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scan params"),
                contents: bytemuck::bytes_of(&ScanParams {
                    n: len,
                    _pad: [0; 3],
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let sums = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scan block sums"),
                size: u64::from(blocks.max(1)) * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            buffers.push(params);
            buffers.push(sums);
            let params = &buffers[buffers.len() - 2];
            let sums = &buffers[buffers.len() - 1];
            let level_data = current.map_or(data, |i| &buffers[i]);
            let named = [
                ("params", params),
                ("data", level_data),
                ("block_sums", sums),
            ];
            levels.push(Level {
                blocks,
                scan_bind: self.scan_blocks.bind_named(device, &named),
                add_bind: self.add_offsets.bind_named(device, &named),
            });
            if blocks == 1 {
                break;
            }
            current = Some(buffers.len() - 1);
            len = blocks;
        }
        ScanPlan {
            levels,
            _buffers: buffers,
        }
    }

    pub fn record(&self, cpass: &mut wgpu::ComputePass, plan: &ScanPlan) {
        for level in &plan.levels {
            self.scan_blocks
                .dispatch(cpass, &level.scan_bind, level.blocks);
        }
        for level in plan.levels.iter().rev().filter(|l| l.blocks > 1) {
            self.add_offsets
                .dispatch(cpass, &level.add_bind, level.blocks);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn params_match_wgsl() {
        let src = include_str!("../../shaders/gpu/scan.wgsl");
        assert_layout!(src, ScanParams, "ScanParams", [n]);
    }
}
