//! The shadow volume (docs/relighting.md), CPU reference of `shaders/render/shadow_*.wgsl`
//! and of the visibility lookup in `shade.wgsl`.
//!
//! All Gaussians — static and simulated, on screen or not — splat their optical mass into
//! one volume of optical depth per frame; each light then needs only the transmittance
//! from every voxel to it, and a Gaussian's visibility is one trilinear lookup. The volume
//! does not depend on the lights, so moving a light costs one march per voxel, and the
//! voxel size sets the softness of the shadow edges (no aliasing on splats).

use glam::{UVec3, Vec3};

use crate::splat::Sym3;

/// Fixed-point unit of the stored optical depth (`DEPTH_UNIT` in `lighting.wgsl`).
pub const DEPTH_UNIT: f32 = 1.0 / 1024.0;

/// A box of cubic voxels: voxel (i, j, k) has its centre at lo + (i + ½, j + ½, k + ½)·h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeGrid {
    pub lo: Vec3,
    pub h: f32,
    pub res: UVec3,
}

impl VolumeGrid {
    /// The grid covering `lo..hi` padded by two voxels, with `resolution` voxels along the
    /// longest side (at least 4 per axis).
    pub fn covering(lo: Vec3, hi: Vec3, resolution: u32) -> VolumeGrid {
        let resolution = resolution.max(4);
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let h = size.max_element() / (resolution - 4) as f32;
        let res = ((size / h).ceil().as_uvec3() + 4).max(UVec3::splat(4));
        VolumeGrid {
            lo: lo - 2.0 * h,
            h,
            res,
        }
    }

    pub fn voxels(&self) -> usize {
        self.res.as_usizevec3().element_product()
    }

    fn index(&self, v: UVec3) -> usize {
        (v.x + self.res.x * (v.y + self.res.y * v.z)) as usize
    }

    /// A world point in voxel-centre coordinates (centres at integers).
    fn local(&self, x: Vec3) -> Vec3 {
        (x - self.lo) / self.h - 0.5
    }
}

/// The optical depth τ·2πσ₁σ₂ / h² of one Gaussian (per voxel length, in DEPTH_UNITs): see
/// `shadow_splat.wgsl`.
fn optical_mass(opacity: f32, cov: &Sym3, h: f32) -> f32 {
    let [xx, xy, xz, yy, yz, zz] = *cov;
    let tr = xx + yy + zz;
    let c2 = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
    let det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if c2.is_nan() || c2 <= 0.0 {
        return 0.0;
    }
    let l3 = (det / c2).max(0.0);
    let area = std::f32::consts::TAU * (c2 - l3 * (tr - l3)).max(0.0).sqrt();
    -(1.0 - opacity.min(0.99)).ln() * area / (h * h) / DEPTH_UNIT
}

/// The optical-depth volume of a set of Gaussians, in DEPTH_UNITs per voxel (u32, as the
/// GPU accumulates it).
pub fn splat(grid: &VolumeGrid, means: &[Vec3], covs: &[Sym3], opacities: &[f32]) -> Vec<u32> {
    let mut depth = vec![0u32; grid.voxels()];
    let top = (grid.res - 1).as_vec3();
    for ((m, c), o) in means.iter().zip(covs).zip(opacities) {
        let rel = grid.local(*m);
        let transparent = o.is_nan() || *o <= 0.0;
        if transparent || !rel.cmpge(Vec3::ZERO).all() || !rel.cmplt(top).all() {
            continue;
        }
        let per_length = optical_mass(*o, c, grid.h);
        if per_length.is_nan() || per_length <= 0.0 || per_length > 1e9 {
            continue;
        }
        let base = rel.floor();
        let f = rel - base;
        for k in 0..8u32 {
            let o = UVec3::new(k & 1, (k >> 1) & 1, k >> 2);
            let w = Vec3::select(o.cmpeq(UVec3::ONE), f, 1.0 - f);
            let add = (per_length * w.x * w.y * w.z).round() as u32;
            let i = grid.index(base.as_uvec3() + o);
            depth[i] = depth[i].wrapping_add(add);
        }
    }
    depth
}

/// Optical depth per voxel length at `x` (voxel-centre coordinates), trilinear, zero
/// outside the volume.
fn depth_at(grid: &VolumeGrid, depth: &[u32], x: Vec3) -> f32 {
    let lo = x.floor();
    let f = x - lo;
    let mut sum = 0.0;
    for k in 0..8u32 {
        let o = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32);
        let c = lo + o;
        if c.cmplt(Vec3::ZERO).any() || c.cmpge(grid.res.as_vec3()).any() {
            continue;
        }
        let w = Vec3::select(o.cmpeq(Vec3::ONE), f, 1.0 - f);
        sum += w.x * w.y * w.z * depth[grid.index(c.as_uvec3())] as f32;
    }
    sum * DEPTH_UNIT
}

/// Transmittance exp(−∫σ ds) from world point `from` to the light at `light`, marched like
/// `shadow_transmit.wgsl` (one-voxel steps, stopping where the ray leaves the volume or the
/// optical depth passes 12).
pub fn transmittance(grid: &VolumeGrid, depth: &[u32], from: Vec3, light: Vec3) -> f32 {
    let start = grid.local(from);
    let to = grid.local(light) - start;
    let dist = to.length();
    if dist.is_nan() || dist <= 0.0 {
        return 1.0;
    }
    let dir = to / dist;
    let inv = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::splat(1e30), 1.0 / dir);
    let t0 = (Vec3::splat(-0.5) - start) * inv;
    let t1 = (grid.res.as_vec3() - 0.5 - start) * inv;
    let exit = t0.max(t1).min_element();
    let end = dist.min(exit.max(0.0));
    let steps = end.ceil() as u32;
    let ds = end / steps.max(1) as f32;
    let mut tau = 0.0;
    for s in 0..steps {
        if tau >= 12.0 {
            break;
        }
        tau += depth_at(grid, depth, start + dir * ((s as f32 + 0.5) * ds)) * ds;
    }
    (-tau).exp()
}

/// The visibility of a light from a Gaussian at `p` with unit normal `n`: the transmittance
/// from two voxels toward the light and 1.5 voxels along the normal (so a Gaussian and its
/// surface do not shadow themselves), as `shade.wgsl` looks it up.
/// This reference marches from that point directly; the GPU interpolates the per-voxel
/// march, which agrees to within the interpolation.
pub fn visibility(grid: &VolumeGrid, depth: &[u32], p: Vec3, n: Vec3, light: Vec3) -> f32 {
    let l = (light - p).normalize_or_zero();
    let x = p + l * (2.0 * grid.h) + n * (1.5 * grid.h);
    let rel = grid.local(x);
    if rel.cmplt(Vec3::ZERO).any() || rel.cmpgt((grid.res - 1).as_vec3()).any() {
        return 1.0;
    }
    transmittance(grid, depth, x, light)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall of overlapping Gaussians between a point and the light blocks it by about
    /// exp(−τ·coverage); beside the wall the light passes.
    #[test]
    fn a_wall_blocks_the_light_and_only_behind_it() {
        let grid = VolumeGrid::covering(Vec3::splat(-1.0), Vec3::splat(1.0), 32);
        let mut means = Vec::new();
        // A 1×1 wall in the plane z = 0 over x, y ∈ [−0.5, 0.5], spacing 0.02, σ = 0.02.
        for i in 0..=50 {
            for j in 0..=50 {
                means.push(Vec3::new(
                    -0.5 + 0.02 * i as f32,
                    -0.5 + 0.02 * j as f32,
                    0.0,
                ));
            }
        }
        let s2 = 0.02f32 * 0.02;
        let covs = vec![[s2, 0.0, 0.0, s2, 0.0, 1e-6]; means.len()];
        let opacities = vec![0.5f32; means.len()];
        let depth = splat(&grid, &means, &covs, &opacities);
        let light = Vec3::new(0.0, 0.0, 3.0);
        // Coverage: each Gaussian covers 2πσ² over a spacing² cell: 2π = 6.28 layers of
        // τ = ln 2, so T ≈ 2^−6.28 ≈ 0.013 behind the wall.
        let behind = transmittance(&grid, &depth, Vec3::new(0.0, 0.0, -0.5), light);
        let beside = transmittance(&grid, &depth, Vec3::new(0.8, 0.0, -0.5), light);
        let want = (-(2.0f32.ln()) * std::f32::consts::TAU).exp();
        assert!((behind - want).abs() < 0.01, "behind {behind} vs {want}");
        assert!(beside > 0.999, "beside {beside}");
    }
}
