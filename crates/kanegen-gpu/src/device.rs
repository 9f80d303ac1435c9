//! [`Gpu`]: the adapter, device and queue, set up once and shared by every
//! [`Dynamics`](crate::Dynamics).

use crate::GpuError;

/// A wgpu device and its queue (Vulkan, Metal or DX12; on Linux without a GPU, Mesa's lavapipe
/// software device). Set up once; cheap to share by reference.
#[derive(Clone, Debug)]
pub struct Gpu {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) info: wgpu::AdapterInfo,
    pub(crate) limits: wgpu::Limits,
    pub(crate) f64: bool,
    pub(crate) timestamps: bool,
}

impl Gpu {
    /// The default adapter (`RequestAdapterOptions::default()`: a discrete or integrated GPU,
    /// else a software device), with `SHADER_F64` and `TIMESTAMP_QUERY` where it offers them
    /// and its own limits on storage buffers. Blocks; see [`Gpu::new_async`].
    pub fn new() -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async())
    }

    /// [`Gpu::new`] as a future.
    pub async fn new_async() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let offered = adapter.features();
        let wanted = wgpu::Features::SHADER_F64 | wgpu::Features::TIMESTAMP_QUERY;
        let features = offered & wanted;
        let adapter_limits = adapter.limits();
        let limits = wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage,
            max_compute_workgroups_per_dimension: adapter_limits
                .max_compute_workgroups_per_dimension,
            ..wgpu::Limits::default()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("kanegen-gpu"),
                required_features: features,
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::NoDevice {
                adapter: info.name.clone(),
                message: e.to_string(),
            })?;
        Ok(Self {
            device,
            queue,
            limits,
            f64: features.contains(wgpu::Features::SHADER_F64),
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            info,
        })
    }

    /// The adapter's name (`llvmpipe (LLVM 15.0.6, 256 bits)`, `NVIDIA H100 80GB HBM3`).
    pub fn adapter_name(&self) -> &str {
        &self.info.name
    }

    /// The backend (`Vulkan`, `Metal`, `Dx12`).
    pub fn backend(&self) -> String {
        format!("{:?}", self.info.backend)
    }

    /// Whether the device runs `f64` kernels (`SHADER_F64`).
    pub fn has_f64(&self) -> bool {
        self.f64
    }

    /// Whether kernel times come from GPU timestamp queries (else from the wall clock
    /// around the dispatch).
    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    /// The largest storage binding the device allows, in bytes (what [`Dynamics`](crate::Dynamics) chunks
    /// batches by; 128 MiB on lavapipe).
    pub fn max_binding_bytes(&self) -> u64 {
        self.limits.max_storage_buffer_binding_size
    }
}
