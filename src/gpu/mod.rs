//! wgpu context: adapter choice, limits, optional features, and what every GPU pass
//! uses: kernels with derived layouts, buffers, readback, and the primitives the renderer,
//! the simulation and relighting share (radix [`sort`], prefix [`scan`], key [`ranges`]).

pub mod buffers;
mod kernel;
#[cfg(test)]
pub(crate) mod layout_check;
pub mod limits;
pub mod pages;
pub mod pass;
pub mod ranges;
pub mod scan;
pub mod sort;
pub mod stages;
pub mod wgsl;

pub use kernel::{dispatch_1d, Kernel, Shader};

use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

/// A graphics API to force instead of choosing automatically.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendChoice {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl BackendChoice {
    fn backends(self) -> wgpu::Backends {
        match self {
            BackendChoice::Vulkan => wgpu::Backends::VULKAN,
            BackendChoice::Gl => wgpu::Backends::GL,
            BackendChoice::Metal => wgpu::Backends::METAL,
            BackendChoice::Dx12 => wgpu::Backends::DX12,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found{backend}. Install a GPU driver, or Mesa's software drivers on a machine \
         without a GPU (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`, which provides lavapipe)"
    )]
    NoAdapter { backend: String },
    #[error("could not open the GPU device on {adapter}: {source}")]
    Device {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
    #[error("GPU wait failed: {0}")]
    Poll(#[from] wgpu::PollError),
    #[error("reading back a GPU buffer failed: {0}")]
    Map(#[from] wgpu::BufferAsyncError),
    #[error("reading back a GPU buffer failed: {0}")]
    MapRange(String),
    #[error("GPU error: {0}")]
    Failed(String),
    #[error("{what} needs {needed} bytes in one buffer, but this adapter allows at most {limit}; {advice}")]
    TooLarge {
        what: String,
        needed: u64,
        limit: u64,
        advice: String,
    },
    #[error("{what} reads at most {max} page(s) of {size} Gaussians on {adapter}, but {gaussians} Gaussians need {pages}; render fewer Gaussians (raise the opacity threshold, or split the scene) or use a GPU with larger storage bindings")]
    TooManyPages {
        what: &'static str,
        gaussians: u32,
        pages: u32,
        size: u32,
        max: u32,
        adapter: String,
    },
}

/// Optional capabilities found on the adapter (and enabled on the device when present).
#[derive(Clone, Copy, Debug, Default)]
pub struct OptionalFeatures {
    pub float32_atomics: bool,
    pub subgroups: bool,
    pub timestamps: bool,
}

/// How an adapter runs the invocations of a workgroup. It sets the workgroup shapes of the
/// passes whose cost is barriers and per-invocation overhead more than arithmetic (the
/// radix sort, the rasteriser); both shapes compute the same result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Executor {
    /// A GPU: invocations run side by side and a barrier is cheap, so many light
    /// invocations hide memory latency best.
    Gpu,
    /// A CPU driver (lavapipe, llvmpipe): a workgroup runs on one core as SIMD vectors of
    /// 4–16 invocations taken in turn, and every barrier switches between all of them, so
    /// fewer invocations that each do more work are faster.
    Cpu,
}

impl Executor {
    pub fn of(info: &wgpu::AdapterInfo) -> Executor {
        match info.device_type {
            wgpu::DeviceType::Cpu => Executor::Cpu,
            _ => Executor::Gpu,
        }
    }
}

/// The opened device and what we know about it.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub features: OptionalFeatures,
    pub limits: wgpu::Limits,
    /// The first GPU error not caught elsewhere (validation, out of memory, device lost):
    /// recorded instead of wgpu's default panic, and reported by [`GpuContext::wait`].
    errors: Arc<Mutex<Option<String>>>,
}

fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    // The GL backend on Linux needs no window for compute work.
    // Indirect dispatch arguments are written only by our own kernels, which keep them
    // within the portable limits (the simulation's compact_blocks.wgsl), so wgpu's
    // validation of them — an extra compute dispatch and barrier per indirect dispatch,
    // costly on CPU drivers — is switched off.
    desc.flags =
        wgpu::InstanceFlags::default().with_env() - wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL;
    wgpu::Instance::new(desc)
}

/// Discrete > integrated > virtual > software (CPU) > anything else.
fn preference(info: &wgpu::AdapterInfo) -> u32 {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 5,
        wgpu::DeviceType::IntegratedGpu => 4,
        wgpu::DeviceType::VirtualGpu => 3,
        wgpu::DeviceType::Cpu => 2,
        wgpu::DeviceType::Other => 1,
    };
    // Among equals, Vulkan/Metal/DX12 before GL (GL lacks float atomics and timestamps).
    let api = u32::from(info.backend != wgpu::Backend::Gl);
    kind * 2 + api
}

/// All adapters visible to wgpu for `backends`, best first.
fn enumerate(backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let mut list = pollster::block_on(instance(backends).enumerate_adapters(backends));
    list.sort_by_key(|a| std::cmp::Reverse(preference(&a.get_info())));
    list
}

/// All adapters visible to wgpu (or to the forced backend), best first.
pub fn adapters(backend: Option<BackendChoice>) -> Vec<wgpu::Adapter> {
    enumerate(backend.map_or(wgpu::Backends::all(), BackendChoice::backends))
}

/// The adapters to choose from: those of the forced backend, else Vulkan/Metal/DX12 ones,
/// and GL only when there are none (probing GL costs time and prints driver noise).
fn candidates(backend: Option<BackendChoice>) -> Vec<wgpu::Adapter> {
    if backend.is_some() {
        return adapters(backend);
    }
    let primary = enumerate(wgpu::Backends::PRIMARY);
    if primary.is_empty() {
        enumerate(wgpu::Backends::GL)
    } else {
        primary
    }
}

fn optional_features(adapter: &wgpu::Adapter) -> (wgpu::Features, OptionalFeatures) {
    let have = adapter.features();
    let mut want = wgpu::Features::empty();
    let mut found = OptionalFeatures::default();
    for (flag, slot) in [
        (
            wgpu::Features::SHADER_FLOAT32_ATOMIC,
            &mut found.float32_atomics,
        ),
        (wgpu::Features::SUBGROUP, &mut found.subgroups),
        (wgpu::Features::TIMESTAMP_QUERY, &mut found.timestamps),
    ] {
        if have.contains(flag) {
            want |= flag;
            *slot = true;
        }
    }
    (want, found)
}

impl GpuContext {
    /// Open the best adapter (or the best of a forced backend) with its real limits.
    pub fn new(backend: Option<BackendChoice>) -> Result<GpuContext, GpuError> {
        let adapter =
            candidates(backend)
                .into_iter()
                .next()
                .ok_or_else(|| GpuError::NoAdapter {
                    backend: backend
                        .map(|b| format!(" for backend {b:?}"))
                        .unwrap_or_default(),
                })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (required_features, features) = optional_features(&adapter);
        let desc = wgpu::DeviceDescriptor {
            label: Some("splatter"),
            required_features,
            required_limits: limits.clone(),
            memory_hints: wgpu::MemoryHints::Performance,
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).map_err(|source| {
                GpuError::Device {
                    adapter: describe(&info),
                    source,
                }
            })?;
        let errors = Arc::new(Mutex::new(None));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| match e {
                wgpu::Error::OutOfMemory { .. } => {
                    "the GPU ran out of memory; render fewer Gaussians or a smaller image"
                        .to_owned()
                }
                other => other.to_string(),
            });
        }));
        let sink = errors.clone();
        device.set_device_lost_callback(move |reason, message| {
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| format!("the GPU device was lost ({reason:?}): {message}"));
        });
        Ok(GpuContext {
            adapter,
            device,
            queue,
            info,
            features,
            limits,
            errors,
        })
    }

    /// How this adapter runs workgroups.
    pub fn executor(&self) -> Executor {
        Executor::of(&self.info)
    }

    /// Whether this adapter is a CPU driver whose subgroups are always 8 invocations, one
    /// SIMD vector (lavapipe with 256-bit vectors): the passes that hand values between
    /// lanes with `subgroupBroadcast` instead of each lane reading them (the rasteriser's
    /// splat reads, the simulation's P2G) are built for that shape.
    pub fn cpu_subgroups_of_eight(&self) -> bool {
        let eight = self.info.subgroup_min_size == 8 && self.info.subgroup_max_size == 8;
        self.executor() == Executor::Cpu && self.features.subgroups && eight
    }

    /// One line naming the adapter, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Cpu, Vulkan)`.
    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// Largest storage buffer binding this device accepts.
    pub fn max_binding(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// Block until all submitted work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        self.check()
    }

    /// Fail with the first GPU error recorded so far, if any.
    pub fn check(&self) -> Result<(), GpuError> {
        match self.errors.lock().unwrap_or_else(|p| p.into_inner()).take() {
            Some(message) => Err(GpuError::Failed(message)),
            None => Ok(()),
        }
    }
}

/// The contexts tests run on: the best adapter, plus the GL backend when it exists and is
/// not the best one, so that the portable paths are exercised too (on a machine without a
/// GPU: lavapipe and llvmpipe). `SPLATTER_TEST_BACKEND=vulkan|gl` restricts to one.
pub fn test_contexts() -> Vec<GpuContext> {
    let only = match std::env::var("SPLATTER_TEST_BACKEND").as_deref() {
        Ok("gl") => Some(BackendChoice::Gl),
        Ok("vulkan") => Some(BackendChoice::Vulkan),
        _ => None,
    };
    let best = GpuContext::new(only).expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut list = vec![best];
    if only.is_none() && list[0].info.backend != wgpu::Backend::Gl {
        if let Ok(gl) = GpuContext::new(Some(BackendChoice::Gl)) {
            list.push(gl);
        }
    }
    list
}

pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.device_type, info.backend)
}

/// The report of `splatter info`: every adapter with its features and key limits.
pub fn info_report(backend: Option<BackendChoice>) -> String {
    let list = adapters(backend);
    let mut out = String::new();
    if list.is_empty() {
        let _ = writeln!(
            out,
            "{}",
            GpuError::NoAdapter {
                backend: String::new()
            }
        );
        return out;
    }
    for (i, a) in list.iter().enumerate() {
        let info = a.get_info();
        let limits = a.limits();
        let (_, f) = optional_features(a);
        let chosen = if i == 0 { "  <- chosen" } else { "" };
        let _ = writeln!(out, "adapter {i}: {}{chosen}", describe(&info));
        let _ = writeln!(out, "  driver: {} {}", info.driver, info.driver_info);
        let _ = writeln!(
            out,
            "  features: f32 atomics {}, subgroups {}, timestamps {}",
            yes(f.float32_atomics),
            yes(f.subgroups),
            yes(f.timestamps)
        );
        let _ = writeln!(
            out,
            "  limits: storage binding {} MiB, buffer {} MiB, workgroup storage {} KiB, invocations/workgroup {}, workgroups/dimension {}",
            limits.max_storage_buffer_binding_size >> 20,
            limits.max_buffer_size >> 20,
            limits.max_compute_workgroup_storage_size >> 10,
            limits.max_compute_invocations_per_workgroup,
            limits.max_compute_workgroups_per_dimension,
        );
    }
    out
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}
