//! The calls of [`Dynamics`]: registry kernels, forward dynamics and rollouts, blocking or as
//! futures, with results read back or kept on the device.

use crate::dynamics::{Shape, Sink};
use crate::wait::{Wait, map_read};
use crate::{Dynamics, GpuError, GpuFloat};

/// Results kept on the device ([`Dynamics::evaluate_on_device`]): one buffer per chunk, each
/// a structure of arrays over its chunk (entry `k` of the chunk's state `i` at `k · len + i`).
#[derive(Debug)]
pub struct Resident {
    /// `(buffer, first state, states)` per chunk.
    pub chunks: Vec<(wgpu::Buffer, usize, usize)>,
    /// Entries per state.
    pub entries: usize,
    /// States in all.
    pub count: usize,
}

/// A rollout request ([`Dynamics::rollout`]): initial states, generalized forces per step,
/// step size, and whether every step's state comes back.
#[derive(Clone, Copy, Debug)]
pub struct Rollout<'a, T> {
    /// Initial coordinates, `q0[j * count + i]`.
    pub q0: &'a [T],
    /// Initial speeds, `u0[j * count + i]`.
    pub u0: &'a [T],
    /// Generalized forces of step `k`: `forces[(k * DOF + j) * count + i]`.
    pub forces: &'a [T],
    /// Number of steps.
    pub steps: u32,
    /// The step (s).
    pub dt: f64,
    /// `true`: the state after every step (`2·DOF·steps` values per state: step `k`'s `q` at
    /// `(k·2·DOF + j) · count + i`, its `u` at `(k·2·DOF + DOF + j) · count + i`); `false`: the
    /// final state only (`2·DOF` values per state).
    pub record: bool,
}

impl<T: GpuFloat> Dynamics<T> {
    /// Kernel `kernel` (a registry function's name, `mass_matrix`, or with a frame
    /// `frame_pose_left_hand`) at `count` states: `q` always, `u` and `ud` when the function
    /// reads them (else empty slices). Returns the dense results, entry `k` of state `i` at
    /// `k * count + i`. Blocks until the results are back.
    pub fn evaluate(
        &mut self,
        kernel: &str,
        count: usize,
        q: &[T],
        u: &[T],
        ud: &[T],
    ) -> Result<Vec<T>, GpuError> {
        pollster::block_on(self.evaluate_with(kernel, count, [q, u, ud], Wait::Block))
    }

    /// [`Dynamics::evaluate`] as a future: it polls the device each time it is polled.
    pub async fn evaluate_async(
        &mut self,
        kernel: &str,
        count: usize,
        q: &[T],
        u: &[T],
        ud: &[T],
    ) -> Result<Vec<T>, GpuError> {
        self.evaluate_with(kernel, count, [q, u, ud], Wait::Async)
            .await
    }

    async fn evaluate_with(
        &mut self,
        kernel: &str,
        count: usize,
        inputs: [&[T]; 3],
        wait: Wait,
    ) -> Result<Vec<T>, GpuError> {
        let shape = self.kernel_shape(kernel)?;
        Self::check(
            &shape,
            count,
            [("q", inputs[0]), ("u", inputs[1]), ("ud", inputs[2])],
        )?;
        let mut out = vec![T::default(); shape.outputs * count];
        self.run(&shape, count, inputs, Sink::Host(&mut out), wait)
            .await?;
        Ok(out)
    }

    /// [`Dynamics::evaluate`], the results left on the device (for a kernel of the caller's
    /// own that reads them, or [`Dynamics::read`] later).
    pub fn evaluate_on_device(
        &mut self,
        kernel: &str,
        count: usize,
        q: &[T],
        u: &[T],
        ud: &[T],
    ) -> Result<Resident, GpuError> {
        let shape = self.kernel_shape(kernel)?;
        Self::check(&shape, count, [("q", q), ("u", u), ("ud", ud)])?;
        let mut chunks = Vec::new();
        pollster::block_on(self.run(
            &shape,
            count,
            [q, u, ud],
            Sink::Device(&mut chunks),
            Wait::Block,
        ))?;
        Ok(Resident {
            chunks,
            entries: shape.outputs,
            count,
        })
    }

    /// The values of results kept on the device, laid out as [`Dynamics::evaluate`] returns
    /// them.
    pub fn read(&self, resident: &Resident) -> Result<Vec<T>, GpuError> {
        let size = std::mem::size_of::<T>() as u64;
        let (n, count) = (resident.entries, resident.count);
        let mut out = vec![T::default(); n * count];
        for (buf, start, c) in &resident.chunks {
            let bytes = (n * c) as u64 * size;
            let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("read"),
                size: bytes.max(16).div_ceil(16) * 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(buf, 0, &staging, 0, bytes.div_ceil(4) * 4);
            self.gpu.queue.submit([encoder.finish()]);
            let raw = pollster::block_on(map_read(&self.gpu.device, &staging, bytes, Wait::Block))?;
            let values: &[T] = bytemuck::cast_slice(&raw);
            for k in 0..n {
                out[k * count + start..k * count + start + c]
                    .copy_from_slice(&values[k * c..k * c + c]);
            }
        }
        Ok(out)
    }

    fn require_forward(&self) -> Result<(), GpuError> {
        if self.module.forward_dynamics {
            Ok(())
        } else {
            Err(GpuError::NoForwardDynamics(self.module.model))
        }
    }

    /// Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))` at `count` states (an unrolled
    /// Cholesky factorisation of `M` per state on the device). Layout as
    /// [`Dynamics::evaluate`]; returns `u̇`, `ud[j * count + i]`.
    pub fn forward_dynamics(
        &mut self,
        count: usize,
        q: &[T],
        u: &[T],
        tau: &[T],
    ) -> Result<Vec<T>, GpuError> {
        self.require_forward()?;
        let n = self.module.dof;
        let shape = Shape {
            entry: "forward_dynamics".into(),
            inputs: [n, n, n],
            outputs: n,
            steps: 0,
            record: false,
            dt: 0.0,
        };
        Self::check(&shape, count, [("q", q), ("u", u), ("tau", tau)])?;
        let mut out = vec![T::default(); n * count];
        pollster::block_on(self.run(
            &shape,
            count,
            [q, u, tau],
            Sink::Host(&mut out),
            Wait::Block,
        ))?;
        Ok(out)
    }

    /// `count` rollouts on the device: `r.steps` steps of semi-implicit Euler (`u += dt·u̇`,
    /// then `q += dt·u`, with `u̇` from forward dynamics under step `k`'s forces), every state
    /// in its own invocation. Returns the recorded states (see [`Rollout::record`]).
    pub fn rollout(&mut self, count: usize, r: &Rollout<'_, T>) -> Result<Vec<T>, GpuError> {
        pollster::block_on(self.rollout_with(count, r, Wait::Block))
    }

    /// [`Dynamics::rollout`] as a future.
    pub async fn rollout_async(
        &mut self,
        count: usize,
        r: &Rollout<'_, T>,
    ) -> Result<Vec<T>, GpuError> {
        self.rollout_with(count, r, Wait::Async).await
    }

    async fn rollout_with(
        &mut self,
        count: usize,
        r: &Rollout<'_, T>,
        wait: Wait,
    ) -> Result<Vec<T>, GpuError> {
        self.require_forward()?;
        let n = self.module.dof;
        let steps = r.steps as usize;
        let shape = Shape {
            entry: "rollout".into(),
            inputs: [n, n, n * steps.max(1)],
            outputs: 2 * n * if r.record { steps.max(1) } else { 1 },
            steps: r.steps,
            record: r.record,
            dt: r.dt,
        };
        Self::check(
            &shape,
            count,
            [("q0", r.q0), ("u0", r.u0), ("forces", r.forces)],
        )?;
        let mut out = vec![T::default(); shape.outputs * count];
        self.run(
            &shape,
            count,
            [r.q0, r.u0, r.forces],
            Sink::Host(&mut out),
            wait,
        )
        .await?;
        Ok(out)
    }
}
