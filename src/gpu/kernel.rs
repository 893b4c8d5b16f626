//! A compute kernel: one WGSL entry point with a bind-group layout derived from the shader.

use std::borrow::Cow;

/// A compiled WGSL module and the names of its group-0 bindings, for kernels that share
/// one module (several entry points of one file).
pub struct Shader {
    module: wgpu::ShaderModule,
    bindings: Vec<(String, u32)>,
}

impl Shader {
    /// Compile `source` (already assembled from its WGSL parts).
    pub fn new(device: &wgpu::Device, label: &'static str, source: &str) -> Shader {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(Cow::Owned(source.to_owned())),
        });
        Shader {
            module,
            bindings: group0_bindings(label, source),
        }
    }

    /// The kernel of entry point `entry`, labelled `label`.
    pub fn kernel(&self, device: &wgpu::Device, label: &'static str, entry: &str) -> Kernel {
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: None,
            module: &self.module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let layout = pipeline.get_bind_group_layout(0);
        Kernel {
            pipeline,
            layout,
            label,
            bindings: self.bindings.clone(),
        }
    }
}

/// A compute pipeline whose bind group 0 takes resources by the names the WGSL declares
/// them with ([`Kernel::bind_named`]): no caller knows a binding number.
pub struct Kernel {
    pub pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    label: &'static str,
    /// `var` name → binding number of group 0, read from the source.
    bindings: Vec<(String, u32)>,
}

/// The `@group(0) @binding(n) var … name` declarations of a WGSL source.
fn group0_bindings(label: &str, source: &str) -> Vec<(String, u32)> {
    let module = wgpu::naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{label}: WGSL does not parse: {}", e.emit_to_string(source)));
    module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            (b.group == 0).then(|| (g.name.clone().unwrap_or_default(), b.binding))
        })
        .collect()
}

impl Kernel {
    /// Compile `source` (already assembled from its WGSL parts) and take `entry`.
    pub fn new(device: &wgpu::Device, label: &'static str, source: &str, entry: &str) -> Kernel {
        Shader::new(device, label, source).kernel(device, label, entry)
    }

    /// Bind each buffer to the binding its WGSL `var` is declared at. A name the source
    /// does not declare is a programming error and panics, naming the kernel; a binding
    /// the entry point uses but `buffers` leaves out is reported by wgpu's validation.
    pub fn bind_named(
        &self,
        device: &wgpu::Device,
        buffers: &[(&str, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let parts: Vec<(&str, wgpu::BufferBinding)> = buffers
            .iter()
            .map(|(name, b)| (*name, b.as_entire_buffer_binding()))
            .collect();
        self.bind_named_parts(device, &parts)
    }

    /// As [`bind_named`](Self::bind_named), with a part of a buffer per name (a page's
    /// window, [`crate::gpu::pages`]).
    pub fn bind_named_parts(
        &self,
        device: &wgpu::Device,
        parts: &[(&str, wgpu::BufferBinding)],
    ) -> wgpu::BindGroup {
        let resources: Vec<(&str, wgpu::BindingResource)> = parts
            .iter()
            .map(|(name, part)| (*name, wgpu::BindingResource::Buffer(part.clone())))
            .collect();
        self.bind_named_resources(device, &resources)
    }

    /// As [`bind_named`](Self::bind_named), with any resource per name (buffers and
    /// texture views).
    pub fn bind_named_resources(
        &self,
        device: &wgpu::Device,
        resources: &[(&str, wgpu::BindingResource)],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .iter()
            .map(|(name, resource)| wgpu::BindGroupEntry {
                binding: self.binding_of(name),
                resource: resource.clone(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }

    fn binding_of(&self, name: &str) -> u32 {
        self.bindings
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, i)| *i)
            .unwrap_or_else(|| {
                panic!(
                    "kernel {}: no `var {name}` at group 0 (declared: {:?})",
                    self.label, self.bindings
                )
            })
    }

    /// Record one dispatch of `groups` workgroups (split over x and y, see [`dispatch_1d`]).
    /// Dispatches recorded in one compute pass still see each other's writes in order:
    /// every dispatch is its own synchronisation scope.
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, groups: u32) {
        let (x, y) = dispatch_1d(groups);
        self.dispatch_2d(cpass, bind, x, y);
    }

    /// Record a dispatch of an explicit 2D grid of workgroups.
    pub fn dispatch_2d(
        &self,
        cpass: &mut wgpu::ComputePass,
        bind: &wgpu::BindGroup,
        x: u32,
        y: u32,
    ) {
        cpass.set_pipeline(&self.pipeline);
        cpass.set_bind_group(0, bind, &[]);
        cpass.dispatch_workgroups(x, y, 1);
    }

    /// Record a dispatch whose workgroup counts the GPU wrote into `args` at `offset`
    /// (three u32: x, y, z; the buffer needs `BufferUsages::INDIRECT`).
    pub fn dispatch_indirect(
        &self,
        cpass: &mut wgpu::ComputePass,
        bind: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        cpass.set_pipeline(&self.pipeline);
        cpass.set_bind_group(0, bind, &[]);
        cpass.dispatch_workgroups_indirect(args, offset);
    }
}

/// Split `groups` workgroups into an (x, y) grid with x ≤ 65535 (the portable limit per
/// dimension). Kernels flatten it as `wid.x + wid.y * num_workgroups.x` and bounds-check,
/// since x · y may exceed `groups`.
pub fn dispatch_1d(groups: u32) -> (u32, u32) {
    const MAX: u32 = 65535;
    if groups <= MAX {
        (groups.max(1), 1)
    } else {
        let y = groups.div_ceil(MAX);
        (groups.div_ceil(y), y)
    }
}

#[cfg(test)]
mod tests {
    use super::dispatch_1d;

    #[test]
    fn dispatch_covers_every_group() {
        for g in [1u32, 255, 65535, 65536, 200_000, 4_000_000] {
            let (x, y) = dispatch_1d(g);
            assert!(
                x <= 65535 && x as u64 * y as u64 >= g as u64,
                "{g}: {x}×{y}"
            );
        }
    }
}
