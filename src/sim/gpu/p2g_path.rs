//! The three ways P2G sums particle contributions on the grid (docs/method.md §2, §2.4),
//! and which one a run takes.

use crate::gpu::GpuContext;
use crate::sim::StepParams;

/// How P2G sums particle contributions on the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum P2gPath {
    /// Sort by cell, then each node gathers in a fixed order: deterministic, needs no
    /// atomics (runs on every backend).
    Gather,
    /// Each particle adds to its 27 nodes with float atomics (SHADER_FLOAT32_ATOMIC): no
    /// sort; the summation order, and so the last bits, vary between runs.
    Atomic,
    /// Each particle adds to its 27 nodes with integer atomics on 64-bit fixed-point sums
    /// (docs/method.md §2.4): no sort, and the sums are the same in any order, so
    /// deterministic; runs on every backend.
    Fixed,
}

impl P2gPath {
    /// Every path, in the order of their names.
    pub const ALL: [P2gPath; 3] = [P2gPath::Gather, P2gPath::Atomic, P2gPath::Fixed];

    /// The path of a name ([`P2gPath::name`]).
    pub fn from_name(name: &str) -> Option<P2gPath> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// As the manifest and the command line name it.
    pub fn name(self) -> &'static str {
        match self {
            P2gPath::Gather => "gather",
            P2gPath::Atomic => "atomic",
            P2gPath::Fixed => "fixed",
        }
    }

    /// Atomics where the adapter has them, else the gather.
    pub fn best(gpu: &GpuContext) -> P2gPath {
        if gpu.features.float32_atomics {
            P2gPath::Atomic
        } else {
            P2gPath::Gather
        }
    }

    /// The fastest deterministic path that runs `params` for `particles` particles on
    /// `gpu`: the gather for two-field separation (the scatter paths have one field), and
    /// where P2G gathers by subgroups ([`GpuContext::cpu_subgroups_of_eight`]: CPU drivers,
    /// on which the fixed-point scatter's integer atomics run one lane at a time) with the
    /// particles in one storage binding and the gather's buffers within the adapter's
    /// limits (`plan::sim_needs`); else the fixed-point scatter.
    pub fn deterministic_for(
        gpu: &GpuContext,
        params: &StepParams,
        particles: usize,
        gather_fits: bool,
    ) -> P2gPath {
        let one_page = super::GpuSim::pages_for(gpu, particles).count == 1;
        if params.separation != crate::sim::Separation::None
            || (gpu.cpu_subgroups_of_eight() && one_page && gather_fits)
        {
            P2gPath::Gather
        } else {
            P2gPath::Fixed
        }
    }

    /// The best path that runs `params`: the gather for two-field separation (the atomic
    /// path has one field), else [`Self::best`].
    pub fn for_params(gpu: &GpuContext, params: &StepParams) -> P2gPath {
        if params.separation != crate::sim::Separation::None {
            P2gPath::Gather
        } else {
            Self::best(gpu)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::P2gPath;

    /// Every path is found by its name, and nothing else is.
    #[test]
    fn names_round_trip() {
        for p in P2gPath::ALL {
            assert_eq!(P2gPath::from_name(p.name()), Some(p));
        }
        assert_eq!(P2gPath::from_name("scatter"), None);
    }
}
