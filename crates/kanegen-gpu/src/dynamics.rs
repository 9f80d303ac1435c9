//! [`Dynamics`]: one generated module's kernels on a device, with their pipelines, parameter
//! buffers and state buffers created once and reused; batches chunked to the device's
//! largest storage binding.

use std::collections::HashMap;
use std::marker::PhantomData;
use std::time::{Duration, Instant};

use kanegen_runtime::gpu::{GpuModule, KernelInputs};

use crate::wait::{Wait, map_read};
use crate::{Gpu, GpuError, GpuFloat, Timing};

/// Binding numbers (see `kanegen_runtime::gpu`).
const PARAMS: u32 = 0;
const PRE: u32 = 1;
const BATCH: u32 = 2;
const IN_Q: u32 = 3;
const IN_U: u32 = 4;
const IN_X: u32 = 5;
const OUT: u32 = 6;

/// What one dispatch reads and writes per state, in values of the float type.
#[derive(Clone, Debug)]
pub(crate) struct Shape {
    /// The entry point.
    pub(crate) entry: String,
    /// Values of `q`, `u` and the third input per state.
    pub(crate) inputs: [usize; 3],
    /// Values of the result per state.
    pub(crate) outputs: usize,
    /// Rollout steps (0 for other kernels).
    pub(crate) steps: u32,
    /// Rollouts: record every step.
    pub(crate) record: bool,
    /// Rollouts: the step.
    pub(crate) dt: f64,
}

/// Where results go.
pub(crate) enum Sink<'a, T> {
    /// Read back into this slice (`outputs · count` values, structure of arrays).
    Host(&'a mut [T]),
    /// Kept in one new device buffer per chunk.
    Device(&'a mut Vec<(wgpu::Buffer, usize, usize)>),
}

/// A generated module's kernels on a [`Gpu`], in the float type `T` (`f32` on every adapter,
/// `f64` where it has `SHADER_F64`).
///
/// States are passed as structures of arrays over the batch: for `count` states, value `j` of
/// state `i` is at `q[j * count + i]` (likewise `u`, `u̇`, `τ`), and entry `k` of the dense
/// row-major result of state `i` at `out[k * count + i]`.
#[derive(Debug)]
pub struct Dynamics<T: GpuFloat> {
    pub(crate) gpu: Gpu,
    pub(crate) module: GpuModule,
    shader: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    bind_layout: wgpu::BindGroupLayout,
    pipelines: HashMap<String, wgpu::ComputePipeline>,
    params: wgpu::Buffer,
    pre: wgpu::Buffer,
    uniform: wgpu::Buffer,
    /// `q`, `u`, third input, results, staging: grown as batches need.
    io: [Option<wgpu::Buffer>; 5],
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    pub(crate) timing: Timing,
    max_chunk: usize,
    _float: PhantomData<T>,
}

/// A buffer of at least `bytes` (rounded up to 16, at least 16).
fn buffer(gpu: &Gpu, label: &str, bytes: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).div_ceil(16) * 16,
        usage,
        mapped_at_creation: false,
    })
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl<T: GpuFloat> Dynamics<T> {
    /// The kernels of `module` on `gpu` with the parameters `params` (in the order of the
    /// generated `Params::to_array`; empty for baked parameters): compiles the shader, uploads
    /// the parameters and runs `precompute` once. Pipelines are created on first use of each
    /// kernel and kept.
    pub fn new(gpu: &Gpu, module: &GpuModule, params: &[f64]) -> Result<Self, GpuError> {
        if T::F64 && !gpu.f64 {
            return Err(GpuError::NoF64(gpu.info.name.clone()));
        }
        let device = &gpu.device;
        let source = if T::F64 {
            module.wgsl_f64
        } else {
            module.wgsl_f32
        };
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(module.model),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let uniform_entry = wgpu::BindGroupLayoutEntry {
            binding: BATCH,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("kanegen-gpu bindings"),
            entries: &[
                storage_entry(PARAMS, true),
                storage_entry(PRE, false),
                uniform_entry,
                storage_entry(IN_Q, true),
                storage_entry(IN_U, true),
                storage_entry(IN_X, true),
                storage_entry(OUT, false),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("kanegen-gpu layout"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let size = std::mem::size_of::<T>() as u64;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let queries = gpu.timestamps.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kanegen-gpu timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = buffer(
                gpu,
                "timestamps",
                16,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            );
            let read = buffer(
                gpu,
                "timestamps read",
                16,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            (set, resolve, read)
        });
        let limits = &gpu.limits;
        let max_chunk =
            (limits.max_compute_workgroups_per_dimension as usize) * module.workgroup_size as usize;
        let mut d = Self {
            params: buffer(gpu, "params", module.params as u64 * size, storage),
            pre: buffer(
                gpu,
                "precomputed",
                module.precomputed as u64 * size,
                storage,
            ),
            uniform: buffer(
                gpu,
                "batch",
                32,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            gpu: gpu.clone(),
            module: *module,
            shader,
            layout,
            bind_layout,
            pipelines: HashMap::new(),
            io: Default::default(),
            queries,
            timing: Timing::default(),
            max_chunk,
            _float: PhantomData,
        };
        d.set_params(params)?;
        Ok(d)
    }

    /// The module's kernels and layout.
    pub fn module(&self) -> &GpuModule {
        &self.module
    }

    /// The device.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The times of the last [`Dynamics::evaluate`], forward dynamics or rollout call.
    pub fn last_timing(&self) -> Timing {
        self.timing
    }

    /// At most this many states per dispatch (default and upper bound: what the device's
    /// workgroup-count limit allows; batches are also chunked to fit the largest storage
    /// binding). Smaller chunks keep buffers small.
    pub fn set_max_chunk(&mut self, states: usize) {
        let cap = (self.gpu.limits.max_compute_workgroups_per_dimension as usize)
            * self.module.workgroup_size as usize;
        self.max_chunk = states.clamp(1, cap);
    }

    /// New parameter values (same order and length as for [`Dynamics::new`]): uploaded, and
    /// the precomputed values recomputed on the device.
    pub fn set_params(&mut self, params: &[f64]) -> Result<(), GpuError> {
        if params.len() != self.module.params {
            return Err(GpuError::InputLength {
                input: "params",
                got: params.len(),
                expected: self.module.params,
                count: 1,
            });
        }
        if params.is_empty() {
            return Ok(());
        }
        let values: Vec<T> = params.iter().map(|&v| T::from_f64(v)).collect();
        self.gpu
            .queue
            .write_buffer(&self.params, 0, bytemuck::cast_slice(&values));
        if self.module.precomputed > 0 {
            let pipeline = self.pipeline("precompute").clone();
            let q = self.io_buffer(0, 16);
            let (u, x, out) = (
                self.io_buffer(1, 16),
                self.io_buffer(2, 16),
                self.io_buffer(3, 16),
            );
            let bind = self.bind_group(&q, &u, &x, &out);
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
            self.gpu.queue.submit([encoder.finish()]);
            self.gpu
                .device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| GpuError::Readback(e.to_string()))?;
        }
        Ok(())
    }

    /// The compute pipeline of entry point `entry`, created on first use.
    fn pipeline(&mut self, entry: &str) -> &wgpu::ComputePipeline {
        if !self.pipelines.contains_key(entry) {
            let p = self
                .gpu
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&self.layout),
                    module: &self.shader,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                });
            self.pipelines.insert(entry.to_owned(), p);
        }
        &self.pipelines[entry]
    }

    /// Buffer `slot` of `io` with at least `bytes`, grown (replaced) when too small.
    fn io_buffer(&mut self, slot: usize, bytes: u64) -> wgpu::Buffer {
        let usage = match slot {
            0..=2 => wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            3 => wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            _ => wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        };
        match &self.io[slot] {
            Some(b) if b.size() >= bytes => b.clone(),
            _ => {
                let b = buffer(&self.gpu, "state", bytes, usage);
                self.io[slot] = Some(b.clone());
                b
            }
        }
    }

    fn bind_group(
        &self,
        q: &wgpu::Buffer,
        u: &wgpu::Buffer,
        x: &wgpu::Buffer,
        out: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        fn entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("kanegen-gpu batch"),
                layout: &self.bind_layout,
                entries: &[
                    entry(PARAMS, &self.params),
                    entry(PRE, &self.pre),
                    entry(BATCH, &self.uniform),
                    entry(IN_Q, q),
                    entry(IN_U, u),
                    entry(IN_X, x),
                    entry(OUT, out),
                ],
            })
    }

    /// The shape of registry kernel `name`.
    pub(crate) fn kernel_shape(&self, name: &str) -> Result<Shape, GpuError> {
        let k = self
            .module
            .kernel(name)
            .ok_or_else(|| GpuError::UnknownKernel {
                model: self.module.model,
                kernel: name.to_owned(),
                available: self
                    .module
                    .kernels
                    .iter()
                    .map(|k| k.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            })?;
        let n = self.module.dof;
        let inputs = match k.inputs {
            KernelInputs::Q => [n, 0, 0],
            KernelInputs::QU => [n, n, 0],
            KernelInputs::QUUd => [n, n, n],
        };
        Ok(Shape {
            entry: name.to_owned(),
            inputs,
            outputs: k.len(),
            steps: 0,
            record: false,
            dt: 0.0,
        })
    }

    /// Checks the inputs' lengths against `shape` and `count`.
    pub(crate) fn check(
        shape: &Shape,
        count: usize,
        inputs: [(&'static str, &[T]); 3],
    ) -> Result<(), GpuError> {
        for ((name, data), per) in inputs.iter().zip(shape.inputs) {
            let expected = per * count;
            if per > 0 && data.len() != expected {
                return Err(GpuError::InputLength {
                    input: name,
                    got: data.len(),
                    expected,
                    count,
                });
            }
        }
        Ok(())
    }

    /// Runs `shape` over `count` states in chunks: per chunk, upload, dispatch, and read back
    /// or keep the results; the three phases timed apart.
    pub(crate) async fn run(
        &mut self,
        shape: &Shape,
        count: usize,
        inputs: [&[T]; 3],
        mut sink: Sink<'_, T>,
        wait: Wait,
    ) -> Result<(), GpuError> {
        let size = std::mem::size_of::<T>() as u64;
        let widest = shape
            .inputs
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
            .max(shape.outputs) as u64;
        let limit = self
            .gpu
            .max_binding_bytes()
            .min(self.gpu.limits.max_buffer_size);
        let per_state = widest * size;
        let fit = (limit / per_state.max(1)) as usize;
        if fit == 0 {
            return Err(GpuError::BatchTooLarge {
                kernel: shape.entry.clone(),
                bytes: per_state,
                limit,
            });
        }
        let chunk = fit.min(self.max_chunk).min(count.max(1));
        self.timing = Timing {
            timestamps: self.queries.is_some(),
            ..Timing::default()
        };
        let pipeline = self.pipeline(&shape.entry).clone();
        let wg = self.module.workgroup_size as usize;
        let mut start = 0;
        while start < count {
            let c = chunk.min(count - start);
            self.timing.chunks += 1;
            // Upload.
            let t0 = Instant::now();
            let bufs: Vec<wgpu::Buffer> = (0..3)
                .map(|s| self.io_buffer(s, (shape.inputs[s] * c) as u64 * size))
                .collect();
            for ((buf, data), per) in bufs.iter().zip(inputs).zip(shape.inputs) {
                if per == 0 {
                    continue;
                }
                if c == count {
                    self.gpu
                        .queue
                        .write_buffer(buf, 0, bytemuck::cast_slice(data));
                } else {
                    for j in 0..per {
                        let from = &data[j * count + start..j * count + start + c];
                        self.gpu.queue.write_buffer(
                            buf,
                            (j * c) as u64 * size,
                            bytemuck::cast_slice(from),
                        );
                    }
                }
            }
            let dt_hi = shape.dt as f32;
            let dt_lo = (shape.dt - f64::from(dt_hi)) as f32;
            let words: [u32; 8] = [
                c as u32,
                c as u32,
                shape.steps,
                u32::from(shape.record),
                dt_hi.to_bits(),
                dt_lo.to_bits(),
                0,
                0,
            ];
            self.gpu
                .queue
                .write_buffer(&self.uniform, 0, bytemuck::cast_slice(&words));
            let out_bytes = (shape.outputs * c) as u64 * size;
            let out = match &sink {
                Sink::Host(_) => self.io_buffer(3, out_bytes),
                Sink::Device(_) => buffer(
                    &self.gpu,
                    "results",
                    out_bytes,
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                ),
            };
            self.gpu.queue.submit([]);
            wait.idle(&self.gpu.device).await?;
            self.timing.upload += t0.elapsed();
            // Dispatch.
            let t1 = Instant::now();
            let bind = self.bind_group(&bufs[0], &bufs[1], &bufs[2], &out);
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&shape.entry),
                    timestamp_writes: self.queries.as_ref().map(|(set, ..)| {
                        wgpu::ComputePassTimestampWrites {
                            query_set: set,
                            beginning_of_pass_write_index: Some(0),
                            end_of_pass_write_index: Some(1),
                        }
                    }),
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(c.div_ceil(wg) as u32, 1, 1);
            }
            if let Some((set, resolve, read)) = &self.queries {
                encoder.resolve_query_set(set, 0..2, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
            }
            self.gpu.queue.submit([encoder.finish()]);
            wait.idle(&self.gpu.device).await?;
            let wall = t1.elapsed();
            self.timing.kernel += match &self.queries {
                Some((_, _, read)) => {
                    let ticks: [u64; 2] = {
                        let bytes = map_read(&self.gpu.device, read, 16, wait).await?;
                        let t: &[u64] = bytemuck::cast_slice(&bytes);
                        [t[0], t[1]]
                    };
                    let period = f64::from(self.gpu.queue.get_timestamp_period());
                    Duration::from_nanos((ticks[1].saturating_sub(ticks[0]) as f64 * period) as u64)
                }
                None => wall,
            };
            // Read back, or keep.
            let t2 = Instant::now();
            match &mut sink {
                Sink::Host(dst) => {
                    let staging = self.io_buffer(4, out_bytes);
                    let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
                    encoder.copy_buffer_to_buffer(
                        &out,
                        0,
                        &staging,
                        0,
                        out_bytes.max(4).div_ceil(4) * 4,
                    );
                    self.gpu.queue.submit([encoder.finish()]);
                    let bytes = map_read(&self.gpu.device, &staging, out_bytes, wait).await?;
                    let values: &[T] = bytemuck::cast_slice(&bytes);
                    for k in 0..shape.outputs {
                        dst[k * count + start..k * count + start + c]
                            .copy_from_slice(&values[k * c..k * c + c]);
                    }
                }
                Sink::Device(kept) => kept.push((out, start, c)),
            }
            self.timing.download += t2.elapsed();
            start += c;
        }
        Ok(())
    }
}
