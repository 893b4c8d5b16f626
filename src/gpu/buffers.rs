//! Buffer helpers every GPU pass uses.

use super::{GpuContext, GpuError};

/// A storage buffer of at least `bytes` (256 minimum, so that empty scenes still bind),
/// copyable both ways, with `extra` usages.
pub fn storage(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(256),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC
            | extra,
        mapped_at_creation: false,
    })
}

/// Map a MAP_READ buffer, copy its contents out, unmap.
pub fn read_buffer(gpu: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv().expect("map callback runs during poll")?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| GpuError::MapRange(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(data)
}

/// Copy a COPY_SRC buffer to a mappable one and read it.
pub fn copy_out(gpu: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, None);
    gpu.queue.submit([enc.finish()]);
    read_buffer(gpu, &staging)
}
