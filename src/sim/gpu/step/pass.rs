//! The step as a family of GPU passes (`gpu::pass`): what its passes bind over (the step's
//! buffers, and where the sort left the sorted pairs) and what they dispatch over.
//! [`super::Passes`] holds a path's passes in order, so a new pass is its own file and one
//! line in `Passes::new`.

use crate::gpu::pass::{Bound, Family};

use super::{Sorted, StepBuffers};

/// The family of the step's passes.
pub(crate) struct Step;

impl Family for Step {
    type Inputs<'a> = BindAt<'a>;
    type Extent<'a> = Extent<'a>;
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
    /// The first step of a submission (the only one that runs [`super::Prepare`]).
    pub first: bool,
}

/// A bind group per page of `b`'s particles.
pub(crate) fn per_page(b: &StepBuffers, bind: impl Fn(u32) -> wgpu::BindGroup) -> Bound {
    Bound::Pages((0..b.pages.pages.count).map(bind).collect())
}

/// Each page's bind group of `bound` with the page's particle count.
pub(crate) fn pages<'a>(
    bound: &'a Bound,
    at: &'a Extent,
) -> impl Iterator<Item = (&'a wgpu::BindGroup, u32)> + 'a {
    bound.pages().iter().zip(at.page_counts.iter().copied())
}
