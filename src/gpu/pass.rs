//! The one shape of a GPU pass, shared by the simulation's step and the renderer's frame
//! (projection, lighting, sorts, tiles, rasterisation): a pass is a type that owns its
//! pipelines and has
//!
//! - a name (its stage in per-pass timings, `gpu::stages`);
//! - `bind`: its bind groups over its family's buffers, a [`Bound`], made when the buffers
//!   change, not per step or frame. Passes are bound in order, and a pass may note in the
//!   inputs what the passes after it need (where a sort left its result);
//! - `clear`: the buffers it accumulates into, cleared before the passes of a step or frame
//!   are recorded (whether or not it runs in it, so what later passes read is defined);
//! - `record`: its dispatches into a compute pass;
//! - `runs`: whether it has work in this step or frame.
//!
//! A [`Family`] names what its passes bind over and dispatch over; [`bind_in_order`] and
//! [`stages`] are the loops every family runs over its list of passes.

use super::ranges::RangesPass;
use super::scan::ScanPlan;
use super::sort::SortPlan;
use super::stages::Stage;

/// A family of passes: the step, the renderer's frame.
pub trait Family {
    /// What its passes bind over (its buffers), and what earlier passes noted for later
    /// ones.
    type Inputs<'a>;
    /// What its passes dispatch over (counts, and which step or frame it is).
    type Extent<'a>;
}

/// One GPU pass of family `F` (the module's documentation).
pub trait Pass<F: Family> {
    /// Its name in per-pass timings.
    fn name(&self) -> &'static str;

    /// Its bind groups over `at`'s buffers; it may note in `at` what later passes read.
    fn bind(&self, device: &wgpu::Device, at: &mut F::Inputs<'_>) -> Bound;

    /// Clear what it accumulates into, before any pass is recorded.
    fn clear(&self, _enc: &mut wgpu::CommandEncoder, _at: &F::Extent<'_>) {}

    /// Record its dispatches over `bound` (what [`bind`](Self::bind) made) for `at`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &F::Extent<'_>);

    /// Whether it has work in the step or frame `at`.
    fn runs(&self, _at: &F::Extent<'_>) -> bool {
        true
    }
}

/// A pass's bind groups (or a primitive's plan, which holds its own).
pub enum Bound {
    /// One bind group over whole buffers.
    Whole(wgpu::BindGroup),
    /// One per page of a per-record array (`gpu::pages`).
    Pages(Vec<wgpu::BindGroup>),
    /// The radix sort's plan (its passes' bind groups and buffers).
    Sort(SortPlan),
    /// The key ranges' pass.
    Ranges(RangesPass),
    /// A pass of several kernels and primitives: their bind groups in the order it
    /// records them.
    Parts(Vec<Bound>),
    /// A prefix scan's plan.
    Scan(ScanPlan),
}

impl Bound {
    pub fn whole(&self) -> &wgpu::BindGroup {
        match self {
            Bound::Whole(bind) => bind,
            _ => unreachable!("a whole-buffer pass bound otherwise"),
        }
    }

    /// The bind group of each page.
    pub fn pages(&self) -> &[wgpu::BindGroup] {
        match self {
            Bound::Pages(binds) => binds,
            _ => unreachable!("a per-page pass bound otherwise"),
        }
    }

    pub fn sort_plan(&self) -> &SortPlan {
        match self {
            Bound::Sort(plan) => plan,
            _ => unreachable!("a sort bound otherwise"),
        }
    }

    pub fn ranges(&self) -> &RangesPass {
        match self {
            Bound::Ranges(pass) => pass,
            _ => unreachable!("a ranges pass bound otherwise"),
        }
    }

    pub fn scan_plan(&self) -> &ScanPlan {
        match self {
            Bound::Scan(plan) => plan,
            _ => unreachable!("a scan bound otherwise"),
        }
    }

    pub fn parts(&self) -> &[Bound] {
        match self {
            Bound::Parts(parts) => parts,
            _ => unreachable!("a pass of several parts bound otherwise"),
        }
    }
}

/// Bind `passes` in order over `at` (each sees what the ones before it noted): one
/// [`Bound`] per pass.
pub fn bind_in_order<F: Family>(
    passes: &[&dyn Pass<F>],
    device: &wgpu::Device,
    mut at: F::Inputs<'_>,
) -> Vec<Bound> {
    passes.iter().map(|p| p.bind(device, &mut at)).collect()
}

/// Record every pass's clears.
pub fn clear_all<F: Family>(
    passes: &[&dyn Pass<F>],
    enc: &mut wgpu::CommandEncoder,
    at: &F::Extent<'_>,
) {
    for pass in passes {
        pass.clear(enc, at);
    }
}

/// The passes among `passes` that run in `at` and that `chosen` keeps (by position), as
/// named stages over their `bound` bind groups.
pub fn stages<'s, 'e: 's, F: Family>(
    passes: &[&'s dyn Pass<F>],
    bound: &'s [Bound],
    at: &'s F::Extent<'e>,
    chosen: impl Fn(usize) -> bool,
) -> Vec<Stage<'s>> {
    passes
        .iter()
        .zip(bound)
        .enumerate()
        .filter(|&(i, (pass, _))| chosen(i) && pass.runs(at))
        .map(|(_, (&pass, bound))| Stage::new(pass.name(), move |c| pass.record(c, bound, at)))
        .collect()
}
