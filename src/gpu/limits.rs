//! Buffer sizes checked against the adapter's limits before anything is allocated: a
//! [`Need`] per buffer a pass will bind, and one error naming the first that does not fit
//! and what to reduce. The needs themselves are worked out next to the allocations they
//! mirror (`sim::gpu::plan`, `crate::limits` for the renderer and derive).

use super::GpuContext;

/// What a buffer must fit in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    /// One storage binding: its passes bind it whole.
    Binding,
    /// One buffer: its passes bind it in pages.
    Buffer,
}

impl Fit {
    fn place(self) -> &'static str {
        match self {
            Fit::Binding => "one GPU storage binding",
            Fit::Buffer => "one GPU buffer",
        }
    }
}

/// One buffer a run will allocate.
#[derive(Clone, Debug, PartialEq)]
pub struct Need {
    pub what: String,
    pub bytes: u64,
    pub advice: &'static str,
    pub fit: Fit,
}

#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{what} needs {bytes} bytes ({mib:.1} MiB) in {place}, but {adapter} allows at most {limit} bytes ({limit_mib:.1} MiB); {advice}", mib = *bytes as f64 / 1048576.0, limit_mib = *limit as f64 / 1048576.0)]
pub struct LimitError {
    pub what: String,
    pub place: &'static str,
    pub bytes: u64,
    pub limit: u64,
    pub adapter: String,
    pub advice: &'static str,
}

/// The first need above its limit (`binding` or `buffer` bytes), as an error naming
/// `adapter`.
pub fn check(needs: &[Need], binding: u64, buffer: u64, adapter: &str) -> Result<(), LimitError> {
    for need in needs {
        let limit = match need.fit {
            Fit::Binding => binding.min(buffer),
            Fit::Buffer => buffer,
        };
        if need.bytes > limit {
            return Err(LimitError {
                what: need.what.clone(),
                place: need.fit.place(),
                bytes: need.bytes,
                limit,
                adapter: adapter.to_owned(),
                advice: need.advice,
            });
        }
    }
    Ok(())
}

/// [`check`] against `gpu`'s limits.
pub fn check_gpu(gpu: &GpuContext, needs: &[Need]) -> Result<(), LimitError> {
    check(
        needs,
        gpu.max_binding(),
        gpu.limits.max_buffer_size,
        &gpu.describe(),
    )
}
