//! The float types the kernels run in.

/// `f32` or `f64`: the float type of a [`Dynamics`](crate::Dynamics) and of its inputs and
/// results.
pub trait GpuFloat:
    bytemuck::Pod + Copy + Default + PartialEq + core::fmt::Debug + Send + Sync
{
    /// Whether this is `f64` (needs the adapter's `SHADER_F64`).
    const F64: bool;
    /// The value of an `f64`, rounded.
    fn from_f64(v: f64) -> Self;
    /// The value as `f64`.
    fn to_f64(self) -> f64;
}

impl GpuFloat for f32 {
    const F64: bool = false;
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl GpuFloat for f64 {
    const F64: bool = true;
    fn from_f64(v: f64) -> Self {
        v
    }
    fn to_f64(self) -> f64 {
        self
    }
}
