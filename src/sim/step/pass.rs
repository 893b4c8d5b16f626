//! What a pass of the step is to the step: a name (for timings), its bind groups over the
//! step's buffers, and its dispatches. [`super::Passes`] holds the passes of a path in
//! order as `Box<dyn StepPass>`, binds them in that order and records them as stages, so a
//! new pass is its own file and one line in `Passes::new`.

use crate::gpu::sort::SortPlan;

use super::{Sorted, StepBuffers};

/// One pass of the step.
pub(crate) trait StepPass {
    /// Its name in per-pass timings.
    fn name(&self) -> &'static str;

    /// Its bind groups over `at`'s buffers (per page of the particles for a per-particle
    /// pass that reads them in order).
    fn bind(&self, device: &wgpu::Device, at: &BindAt) -> Bound;

    /// Record its dispatches over `bound` (what [`bind`](Self::bind) made) for `at`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent);

    /// Whether it runs in a step of a submission: `first`, the first. Every pass runs in
    /// every step except the scatter path's [`super::Prepare`].
    fn runs(&self, _first: bool) -> bool {
        true
    }
}

/// What a pass binds over: the step's buffers and, once the sort has been bound (the
/// gather path, in step order), where the sorted cell keys and particle indices are.
pub(crate) struct BindAt<'a> {
    pub b: &'a StepBuffers,
    pub sorted: Option<Sorted<'a>>,
    /// Particles, and the bits of their cell keys the sort orders by.
    pub particles: u32,
    pub sort_bits: u32,
}

impl BindAt<'_> {
    /// The sorted keys and indices; a pass that reads them comes after the sort.
    pub fn sorted(&self) -> &Sorted<'_> {
        self.sorted
            .as_ref()
            .expect("a pass that reads the sorted particles is bound before the sort")
    }
}

/// What a pass dispatches over.
pub(crate) struct Extent<'a> {
    pub b: &'a StepBuffers,
    pub particles: u32,
    /// Blocks of 4³ nodes of the domain.
    pub blocks: u32,
    /// Particles of each page.
    pub page_counts: &'a [u32],
}

/// A pass's bind groups.
pub(crate) enum Bound {
    /// One bind group over whole buffers.
    Whole(wgpu::BindGroup),
    /// One per page of the particles (`gpu::pages`).
    Pages(Vec<wgpu::BindGroup>),
    /// The radix sort's plan (its passes' bind groups and buffers).
    Sort(SortPlan),
}

impl Bound {
    /// A bind group per page of `b`'s particles.
    pub fn per_page(b: &StepBuffers, bind: impl Fn(u32) -> wgpu::BindGroup) -> Bound {
        Bound::Pages((0..b.pages.pages.count).map(bind).collect())
    }

    pub fn whole(&self) -> &wgpu::BindGroup {
        match self {
            Bound::Whole(bind) => bind,
            _ => unreachable!("a whole-buffer pass bound otherwise"),
        }
    }

    /// Each page's bind group with the page's particle count.
    pub fn pages<'a>(
        &'a self,
        at: &'a Extent,
    ) -> impl Iterator<Item = (&'a wgpu::BindGroup, u32)> + 'a {
        let binds = match self {
            Bound::Pages(binds) => binds.as_slice(),
            _ => unreachable!("a per-page pass bound otherwise"),
        };
        binds.iter().zip(at.page_counts.iter().copied())
    }

    pub fn sort_plan(&self) -> &SortPlan {
        match self {
            Bound::Sort(plan) => plan,
            _ => unreachable!("the sort bound otherwise"),
        }
    }
}
