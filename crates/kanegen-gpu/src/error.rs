//! The typed errors of the GPU runtime.

/// What can go wrong setting up or running the kernels.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter (GPU or software Vulkan device) was found.
    #[error(
        "no GPU adapter found (Vulkan, Metal or DX12): install a driver, or Mesa's lavapipe (`mesa-vulkan-drivers`) for a software device; {0}"
    )]
    NoAdapter(String),
    /// The adapter refused the device.
    #[error("the adapter `{adapter}` refused a device: {message}")]
    NoDevice {
        /// The adapter's name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// `f64` kernels were asked for on an adapter without `SHADER_F64`.
    #[error("the adapter `{0}` has no SHADER_F64: run the f32 kernels (`Dynamics::<f32>`) on it")]
    NoF64(String),
    /// The generated module has no kernel of this name.
    #[error("model `{model}` has no GPU kernel `{kernel}`; its kernels: {available}")]
    UnknownKernel {
        /// The model.
        model: &'static str,
        /// The name asked for.
        kernel: String,
        /// The names it has.
        available: String,
    },
    /// The module has no forward dynamics kernels (it lacks the mass matrix or the velocity
    /// and gravity terms).
    #[error(
        "model `{0}` has no forward_dynamics/rollout kernels: generate it with the mass matrix and nonlinear_effects, coriolis and gravity, or inverse_dynamics"
    )]
    NoForwardDynamics(&'static str),
    /// An input slice has the wrong length.
    #[error("input `{input}` has {got} values; {count} states need {expected}")]
    InputLength {
        /// `q`, `u`, `ud`, `tau`, `forces`, `params`.
        input: &'static str,
        /// Its length.
        got: usize,
        /// The length expected.
        expected: usize,
        /// The number of states.
        count: usize,
    },
    /// Even one state does not fit the adapter's largest storage binding.
    #[error(
        "one state of `{kernel}` needs {bytes} bytes in one binding, more than the adapter's limit of {limit} bytes per storage binding: fewer rollout steps per call, or record only the final state"
    )]
    BatchTooLarge {
        /// The kernel.
        kernel: String,
        /// Bytes one state needs in its largest binding.
        bytes: u64,
        /// The adapter's `max_storage_buffer_binding_size`.
        limit: u64,
    },
    /// Reading results back from the device failed.
    #[error("reading results from the device failed: {0}")]
    Readback(String),
}
