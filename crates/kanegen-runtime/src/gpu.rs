//! The layout of a generated module's GPU kernels (`Builder::gpu(true)`): what the
//! `kanegen-gpu` crate needs to run them. A generated module holds one [`GpuModule`] as
//! `gpu::MODULE`, next to the kernels' WGSL source (`gpu::WGSL_F32`, `gpu::WGSL_F64`).
//!
//! Buffer layout, shared by every entry point (bind group 0): binding 0 the parameters (in
//! the order of `Params::to_array`), 1 the precomputed values (written by the `precompute`
//! entry point), 2 a uniform `Batch { count, stride, steps, record, dt, dt_lo, _, _ }` (eight
//! 32-bit words), 3 the coordinates `q`, 4 the speeds `u`, 5 the third input (`u̇`, `τ`, or a
//! rollout's generalized forces), 6 the results. State inputs and results are structures of
//! arrays: entry `k` of state `i` at `k · stride + i`.

/// Which state inputs a kernel reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelInputs {
    /// `q`.
    Q,
    /// `q`, `u`.
    QU,
    /// `q`, `u`, `u̇`.
    QUUd,
}

/// One per-state entry point of a generated module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernel {
    /// The entry point's name: the generated Rust function's (`mass_matrix`,
    /// `frame_pose_left_hand`).
    pub name: &'static str,
    /// Its inputs.
    pub inputs: KernelInputs,
    /// Rows of its dense result (row-major; both triangles of a symmetric matrix).
    pub rows: usize,
    /// Columns of its dense result (1 for a vector or scalar).
    pub cols: usize,
}

impl Kernel {
    /// Entries of the dense result per state.
    pub const fn len(&self) -> usize {
        self.rows * self.cols
    }

    /// Whether the result has no entry.
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A generated module's GPU kernels and their layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuModule {
    /// The model's name.
    pub model: &'static str,
    /// Number of speeds (and of coordinates) per state.
    pub dof: usize,
    /// Number of parameters the kernels read (0 with baked parameters).
    pub params: usize,
    /// Number of precomputed parameter-only values.
    pub precomputed: usize,
    /// Invocations per workgroup of the per-state entry points.
    pub workgroup_size: u32,
    /// The kernels in `f32`.
    pub wgsl_f32: &'static str,
    /// The kernels in `f64` (adapters with `SHADER_F64`).
    pub wgsl_f64: &'static str,
    /// The per-state entry points of the registry functions.
    pub kernels: &'static [Kernel],
    /// Whether the module has the `forward_dynamics` and `rollout` entry points (it has the
    /// mass matrix and the velocity and gravity terms).
    pub forward_dynamics: bool,
}

impl GpuModule {
    /// The kernel named `name`, if the module has it.
    pub fn kernel(&self, name: &str) -> Option<&'static Kernel> {
        self.kernels.iter().find(|k| k.name == name)
    }
}
