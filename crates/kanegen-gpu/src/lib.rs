//! Runs kanegen-generated robot dynamics on a GPU: the WGSL compute kernels a module gets
//! with `kanegen::Builder::gpu(true)`, through [`wgpu`] (Vulkan, Metal, DX12; on Linux without
//! a GPU, Mesa's lavapipe software device).
//!
//! - [`Gpu`]: the adapter, device and queue, set up once.
//! - [`Dynamics`]: one module's kernels on a device in `f32` or `f64` (where the adapter has
//!   `SHADER_F64`), with pipelines and buffers created once and reused: [`Dynamics::evaluate`]
//!   (any registry function at a batch of states, blocking or [`Dynamics::evaluate_async`];
//!   [`Dynamics::evaluate_on_device`] keeps the results there), [`Dynamics::forward_dynamics`]
//!   and [`Dynamics::rollout`] (many rollouts of semi-implicit Euler entirely on the device).
//! - [`Timing`]: upload, kernel and read-back times of the last call, apart.
//!
//! Batches larger than the device's largest storage binding (128 MiB on lavapipe) or its
//! workgroup count are split into chunks. States are structures of arrays over the batch
//! (value `j` of state `i` at `j * count + i`). The guide's chapter `docs/gpu.md` has the
//! details, precision and measured figures.
//!
//! ```no_run
//! # mod arm { pub mod gpu { pub const MODULE: kanegen_runtime::gpu::GpuModule =
//! #   kanegen_runtime::gpu::GpuModule { model: "arm", dof: 2, params: 0, precomputed: 0,
//! #   workgroup_size: 64, wgsl_f32: "", wgsl_f64: "", kernels: &[], forward_dynamics: true }; } }
//! use kanegen_gpu::{Dynamics, Gpu};
//! let gpu = Gpu::new()?;
//! let mut arm = Dynamics::<f32>::new(&gpu, &arm::gpu::MODULE, &[])?;
//! let count = 4096;
//! let q = vec![0.1f32; 2 * count];
//! let m = arm.evaluate("mass_matrix", count, &q, &[], &[])?; // m[k * count + i]
//! println!("{:?}", arm.last_timing());
//! # Ok::<(), kanegen_gpu::GpuError>(())
//! ```
#![forbid(unsafe_code)]

mod api;
mod device;
mod dynamics;
mod error;
mod float;
mod wait;

pub use api::{Resident, Rollout};
pub use device::Gpu;
pub use dynamics::Dynamics;
pub use error::GpuError;
pub use float::GpuFloat;
pub use kanegen_runtime::gpu::{GpuModule, Kernel, KernelInputs};
pub use wgpu;

use std::time::Duration;

/// The times of one call, apart: summed over its chunks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Writing the inputs into device buffers (wall clock until the device has them).
    pub upload: Duration,
    /// The kernel: from GPU timestamps where the device has `TIMESTAMP_QUERY`, else the
    /// wall clock from submission until the device is idle.
    pub kernel: Duration,
    /// Copying the results back and mapping them (zero when they stay on the device).
    pub download: Duration,
    /// Whether [`Timing::kernel`] comes from timestamps.
    pub timestamps: bool,
    /// Number of chunks the batch was split into.
    pub chunks: usize,
}

impl Timing {
    /// Upload, kernel and read-back together.
    pub fn total(&self) -> Duration {
        self.upload + self.kernel + self.download
    }
}
