//! PCA normals on the GPU, in the deformed configuration (`lighting.simulated_normals =
//! "recompute"`): the simulated Gaussians are hashed into a uniform grid
//! (`shaders/relight/normals_keys.wgsl`), sorted by cell (the GPU primitive [`RadixSort`]),
//! the cells' runs found ([`Ranges`]), the centres copied into cell order
//! (`normals_points.wgsl`), and each Gaussian's normal refitted from the same object's
//! centres within a radius (`normals_pca.wgsl`) — written straight into the
//! renderer's shading records, with no readback. The CPU twin is
//! [`crate::relight::normals::pca_normals`] (k nearest instead of a radius).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::ops::Range;
use wgpu::util::DeviceExt;

use crate::gpu::ranges::Ranges;
use crate::gpu::scan::Scan;
use crate::gpu::sort::{RadixSort, SortBuffers, SortPlan};
use crate::gpu::wgsl::Source;
use crate::gpu::{GpuContext, GpuError, Kernel};
use crate::render::gpu::lighting::LIGHTING;
use crate::render::GpuRenderer;
use crate::sim::gpu::wgsl;

/// `NormalsParams` of `shaders/relight/normals_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct NormalsParams {
    pub lo_h: [f32; 4],
    pub dims_count: [u32; 4],
    pub offset: u32,
    pub reach: u32,
    pub _pad: [u32; 2],
}

/// `NormalObject` of `shaders/relight/normals_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct NormalObject {
    pub radius: f32,
    pub layer: f32,
    pub _pad: [f32; 2],
}

/// Neighbourhood radius in units of an object's Gaussian spacing: about the 30 nearest
/// centres of a filled lattice on its surface (the CPU default k = 30) and the surface
/// layer of its refit.
pub const RADIUS_PER_SPACING: f32 = 2.6;

/// Hash-grid cells per neighbourhood radius: cells of half a radius make the searched cells
/// (those whose box comes within the radius) hug its sphere, about a third of the
/// candidates of radius-wide cells.
const CELLS_PER_RADIUS: f32 = 2.0;

/// The most hash-grid cells (the cell ranges take 8 bytes each).
const MAX_CELLS: f32 = 8.0e6;

fn source(pass: &str) -> String {
    Source::new()
        .module(&LIGHTING)
        .module(&wgsl::SVD)
        .generated(include_str!("../../shaders/relight/normals_common.wgsl").to_string())
        .pass(pass)
}

/// One recomputed object: its Gaussians (indices into the renderer's buffers) and the
/// spacing of its Gaussians at rest.
#[derive(Clone, Debug)]
pub struct RecomputedObject {
    pub range: Range<usize>,
    pub spacing: f32,
}

/// The GPU normal pass over some objects of a renderer's Gaussians.
pub struct GpuNormals {
    keys: Kernel,
    points: Kernel,
    pca: Kernel,
    tile_ranges: Ranges,
    sort: RadixSort,
    scan: Scan,
    plan: SortPlan,
    keys_bind: wgpu::BindGroup,
    ranges_bind: wgpu::BindGroup,
    points_bind: wgpu::BindGroup,
    pca_bind: wgpu::BindGroup,
    cell_ranges: wgpu::Buffer,
    count: u32,
    _buffers: Vec<wgpu::Buffer>,
}

fn storage(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    crate::gpu::buffers::storage(device, label, bytes, wgpu::BufferUsages::empty())
}

impl GpuNormals {
    /// Normals for `objects` (contiguous, increasing ranges) of `renderer`'s Gaussians,
    /// which must stay inside the box `lo..hi` (the simulation domain; Gaussians outside
    /// are hashed into the border cells). The renderer needs lighting set.
    // Over 80 lines on purpose: the hash grid's buffers and passes are made in their binding
    // order, each buffer next to the pass that binds it.
    pub fn new(
        gpu: &GpuContext,
        renderer: &GpuRenderer,
        objects: &[RecomputedObject],
        lo: Vec3,
        hi: Vec3,
    ) -> Result<GpuNormals, GpuError> {
        let device = &gpu.device;
        let (Some(gaussians), Some(shading)) =
            (renderer.gaussian_buffer(), renderer.shading_buffer())
        else {
            return Err(GpuError::Failed(
                "GPU normals need uploaded Gaussians and lighting".to_string(),
            ));
        };
        let offset = objects.first().map_or(0, |o| o.range.start);
        let end = objects.last().map_or(0, |o| o.range.end);
        let count = (end - offset) as u32;
        let mut object_of = vec![u32::MAX; count as usize];
        let mut table = Vec::new();
        let mut h = 0.0f32;
        for (k, o) in objects.iter().enumerate() {
            for i in o.range.clone() {
                object_of[i - offset] = k as u32;
            }
            let radius = RADIUS_PER_SPACING * o.spacing;
            h = h.max(radius);
            table.push(NormalObject {
                radius,
                layer: 0.5 * o.spacing,
                _pad: [0.0; 2],
            });
        }
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let radius = h;
        let h = (radius / CELLS_PER_RADIUS)
            .max(1e-6)
            .max((size.x * size.y * size.z / MAX_CELLS).cbrt());
        let reach = (radius / h).ceil().max(1.0) as u32;
        let dims = (size / h).ceil().as_uvec3().max(glam::UVec3::ONE);
        let cells = dims.x * dims.y * dims.z;
        let params = NormalsParams {
            lo_h: lo.extend(h).to_array(),
            dims_count: dims.extend(count).to_array(),
            offset: offset as u32,
            reach,
            _pad: [0; 2],
        };
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let params_buf = init("normals params", bytemuck::bytes_of(&params));
        let mut object_bytes = bytemuck::cast_slice::<u32, u8>(&object_of).to_vec();
        object_bytes.resize(object_bytes.len().max(16), 0);
        let object_buf = init("normals object of", &object_bytes);
        table.push(NormalObject::zeroed());
        let table_buf = init("normals objects", bytemuck::cast_slice(&table));
        let n = u64::from(count);
        let keys = storage(device, "normals keys", n * 4);
        let values = storage(device, "normals values", n * 4);
        let keys_alt = storage(device, "normals keys alt", n * 4);
        let values_alt = storage(device, "normals values alt", n * 4);
        let key_count = init("normals count", bytemuck::bytes_of(&[count, 0, 0, 0]));
        let cell_ranges = storage(device, "normals cell ranges", u64::from(cells) * 8);
        let sort = RadixSort::new(device, gpu.executor());
        let scan = Scan::new(device);
        let plan = sort.plan(
            device,
            &scan,
            &SortBuffers {
                count: &key_count,
                keys: &keys,
                values: &values,
                keys_alt: &keys_alt,
                values_alt: &values_alt,
            },
            count.max(1),
            32 - cells.saturating_sub(1).leading_zeros().min(31),
        );
        let (sorted_keys, sorted_values) = if plan.result_in_alternates() {
            (&keys_alt, &values_alt)
        } else {
            (&keys, &values)
        };
        let keys_kernel = Kernel::new(
            device,
            "normals keys",
            &source(include_str!("../../shaders/relight/normals_keys.wgsl")),
            "main",
        );
        let points_kernel = Kernel::new(
            device,
            "normals points",
            &source(include_str!("../../shaders/relight/normals_points.wgsl")),
            "main",
        );
        let pca = Kernel::new(
            device,
            "normals pca",
            &source(include_str!("../../shaders/relight/normals_pca.wgsl")),
            "main",
        );
        let tile_ranges = Ranges::new(device);
        let keys_bind = keys_kernel.bind_named(
            device,
            &[
                ("params", &params_buf),
                ("gaussians", gaussians),
                ("keys", &keys),
                ("values", &values),
            ],
        );
        let ranges_bind = tile_ranges.bind(device, &key_count, sorted_keys, &cell_ranges);
        let points = storage(device, "normals points", n * 16);
        let points_bind = points_kernel.bind_named(
            device,
            &[
                ("params", &params_buf),
                ("gaussians", gaussians),
                ("sorted_values", sorted_values),
                ("object_of", &object_buf),
                ("points", &points),
            ],
        );
        let pca_bind = pca.bind_named(
            device,
            &[
                ("params", &params_buf),
                ("ranges", &cell_ranges),
                ("sorted_values", sorted_values),
                ("points", &points),
                ("objects", &table_buf),
                ("shading", shading),
            ],
        );
        Ok(GpuNormals {
            keys: keys_kernel,
            points: points_kernel,
            pca,
            tile_ranges,
            sort,
            scan,
            plan,
            keys_bind,
            ranges_bind,
            points_bind,
            pca_bind,
            cell_ranges,
            count,
            _buffers: vec![
                params_buf, object_buf, table_buf, keys, values, keys_alt, values_alt, key_count,
                points,
            ],
        })
    }

    /// Recompute the normals from the Gaussians' current means (after the derive pass).
    pub fn run(&self, gpu: &GpuContext) -> Result<(), GpuError> {
        if self.count == 0 {
            return Ok(());
        }
        let groups = self.count.div_ceil(256);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.cell_ranges, 0, None);
        {
            let mut c = enc.begin_compute_pass(&Default::default());
            self.keys.dispatch(&mut c, &self.keys_bind, groups);
            self.sort.record(&mut c, &self.scan, &self.plan);
            self.tile_ranges
                .kernel
                .dispatch(&mut c, &self.ranges_bind, groups);
            self.points.dispatch(&mut c, &self.points_bind, groups);
            self.pca.dispatch(&mut c, &self.pca_bind, groups);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.check()
    }
}

/// The spacing of a set of Gaussian centres: the median distance to the 6th nearest
/// neighbour (a lattice's face neighbours), from a sample of at most 2 000 points.
pub fn spacing_of(points: &[Vec3]) -> f32 {
    use kiddo::immutable::float::kdtree::ImmutableKdTree;
    use kiddo::SquaredEuclidean;
    if points.len() < 8 {
        return 0.0;
    }
    let coords: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    let tree: ImmutableKdTree<f32, u32, 3, 32> = ImmutableKdTree::new_from_slice(&coords);
    let step = (points.len() / 2000).max(1);
    let mut d: Vec<f32> = points
        .iter()
        .step_by(step)
        .map(|p| {
            let nb = tree.nearest_n::<SquaredEuclidean>(
                &p.to_array(),
                std::num::NonZero::new(7).expect("7"),
            );
            nb.last().map_or(0.0, |n| n.distance.sqrt())
        })
        .collect();
    d.sort_by(f32::total_cmp);
    d[d.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn layouts_match_wgsl() {
        let src = source("");
        assert_layout!(
            &src,
            NormalsParams,
            "NormalsParams",
            [lo_h, dims_count, offset, reach]
        );
        assert_layout!(&src, NormalObject, "NormalObject", [radius, layer]);
    }
}
