//! PCA normals on the GPU, in the deformed configuration (`lighting.simulated_normals =
//! "recompute"`): the simulated Gaussians are hashed into a uniform grid
//! (`shaders/relight/normals_keys.wgsl`), sorted by cell (the GPU primitive
//! `gpu::sort::RadixSort`), the cells' runs found (`gpu::ranges`), the centres copied into cell order
//! (`normals_points.wgsl`), and each Gaussian's normal refitted from the same object's
//! centres within a radius (`normals_pca.wgsl`) — written straight into the
//! renderer's shading records, with no readback. The CPU twin is
//! [`crate::relight::normals::pca_normals`] (k nearest instead of a radius).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::ops::Range;
use wgpu::util::DeviceExt;

mod passes;

use crate::gpu::pass::{bind_in_order, clear_all, Bound, Pass};
use crate::gpu::wgsl::Source;
use crate::gpu::{GpuContext, GpuError};
use crate::render::gpu::lighting::LIGHTING;
use crate::render::GpuRenderer;
use crate::sim::gpu::wgsl;
use passes::{
    CellPoints, CellRanges, CellSort, HashKeys, Pca, Refit, RefitBuffers, RefitExtent, RefitInputs,
};

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
    passes: Vec<Box<dyn Pass<Refit>>>,
    /// Each pass's bind groups over `buffers` and the renderer's.
    bound: Vec<Bound>,
    buffers: RefitBuffers,
    count: u32,
}

fn storage(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    crate::gpu::buffers::storage(device, label, bytes, wgpu::BufferUsages::empty())
}

/// The hash grid over `lo..hi` for `objects`: its constants, each object's radius and
/// layer (and an empty last entry), each Gaussian's object, and its cell count.
fn hash_grid(
    objects: &[RecomputedObject],
    lo: Vec3,
    hi: Vec3,
) -> (NormalsParams, Vec<NormalObject>, Vec<u32>, u32) {
    let offset = objects.first().map_or(0, |o| o.range.start);
    let end = objects.last().map_or(0, |o| o.range.end);
    let count = (end - offset) as u32;
    let mut object_of = vec![u32::MAX; count as usize];
    let mut table = Vec::new();
    let mut radius = 0.0f32;
    for (k, o) in objects.iter().enumerate() {
        for i in o.range.clone() {
            object_of[i - offset] = k as u32;
        }
        let r = RADIUS_PER_SPACING * o.spacing;
        radius = radius.max(r);
        table.push(NormalObject {
            radius: r,
            layer: 0.5 * o.spacing,
            _pad: [0.0; 2],
        });
    }
    table.push(NormalObject::zeroed());
    let size = (hi - lo).max(Vec3::splat(1e-6));
    let h = (radius / CELLS_PER_RADIUS)
        .max(1e-6)
        .max((size.x * size.y * size.z / MAX_CELLS).cbrt());
    let reach = (radius / h).ceil().max(1.0) as u32;
    let dims = (size / h).ceil().as_uvec3().max(glam::UVec3::ONE);
    let params = NormalsParams {
        lo_h: lo.extend(h).to_array(),
        dims_count: dims.extend(count).to_array(),
        offset: offset as u32,
        reach,
        _pad: [0; 2],
    };
    (params, table, object_of, dims.x * dims.y * dims.z)
}

impl GpuNormals {
    /// Normals for `objects` (contiguous, increasing ranges) of `renderer`'s Gaussians,
    /// which must stay inside the box `lo..hi` (the simulation domain; Gaussians outside
    /// are hashed into the border cells). The renderer needs lighting set.
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
        let (params, table, object_of, cells) = hash_grid(objects, lo, hi);
        let count = object_of.len() as u32;
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let mut object_bytes = bytemuck::cast_slice::<u32, u8>(&object_of).to_vec();
        object_bytes.resize(object_bytes.len().max(16), 0);
        let n = u64::from(count);
        let buffers = RefitBuffers {
            params: init("normals params", bytemuck::bytes_of(&params)),
            object_of: init("normals object of", &object_bytes),
            objects: init("normals objects", bytemuck::cast_slice(&table)),
            keys: storage(device, "normals keys", n * 4),
            values: storage(device, "normals values", n * 4),
            keys_alt: storage(device, "normals keys alt", n * 4),
            values_alt: storage(device, "normals values alt", n * 4),
            key_count: init("normals count", bytemuck::bytes_of(&[count, 0, 0, 0])),
            cell_ranges: storage(device, "normals cell ranges", u64::from(cells) * 8),
            points: storage(device, "normals points", n * 16),
        };
        let passes: Vec<Box<dyn Pass<Refit>>> = vec![
            Box::new(HashKeys::new(device)),
            Box::new(CellSort::new(device, gpu.executor())),
            Box::new(CellRanges::new(device)),
            Box::new(CellPoints::new(device)),
            Box::new(Pca::new(device)),
        ];
        let inputs = RefitInputs {
            b: &buffers,
            gaussians,
            shading,
            count,
            cells,
            sorted: None,
        };
        let bound = bind_in_order(&list(&passes), device, inputs);
        Ok(GpuNormals {
            passes,
            bound,
            buffers,
            count,
        })
    }

    /// Recompute the normals from the Gaussians' current means (after the derive pass).
    pub fn run(&self, gpu: &GpuContext) -> Result<(), GpuError> {
        if self.count == 0 {
            return Ok(());
        }
        let at = RefitExtent {
            b: &self.buffers,
            count: self.count,
        };
        let passes = list(&self.passes);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        clear_all(&passes, &mut enc, &at);
        let stages = crate::gpu::pass::stages(&passes, &self.bound, &at, |_| true);
        crate::gpu::stages::record(&mut enc, "normals", &stages);
        gpu.queue.submit([enc.finish()]);
        gpu.check()
    }
}

fn list(passes: &[Box<dyn Pass<Refit>>]) -> Vec<&dyn Pass<Refit>> {
    passes.iter().map(|p| p.as_ref()).collect()
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
