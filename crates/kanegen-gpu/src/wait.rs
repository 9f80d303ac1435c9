//! Waiting for the device: blocking (`device.poll` until the queue is idle) or as a future
//! that polls the device each time it is polled.

use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};

use crate::GpuError;

/// How a call waits for the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Wait {
    /// Block the thread in `device.poll(Wait)`.
    Block,
    /// Return `Pending` until the device is idle (the future polls the device).
    Async,
}

/// A future that is ready when the device's queue is empty.
struct Idle<'a> {
    device: &'a wgpu::Device,
}

impl Future for Idle<'_> {
    type Output = Result<(), GpuError>;
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        match self.device.poll(wgpu::PollType::Poll) {
            Ok(wgpu::PollStatus::QueueEmpty) => Poll::Ready(Ok(())),
            Ok(_) => {
                cx.waker().wake_by_ref();
                Poll::Pending
            }
            Err(e) => Poll::Ready(Err(GpuError::Readback(e.to_string()))),
        }
    }
}

impl Wait {
    /// Until the device has finished every submission.
    pub(crate) async fn idle(self, device: &wgpu::Device) -> Result<(), GpuError> {
        match self {
            Wait::Block => device
                .poll(wgpu::PollType::wait_indefinitely())
                .map(|_| ())
                .map_err(|e| GpuError::Readback(e.to_string())),
            Wait::Async => Idle { device }.await,
        }
    }
}

/// The first `bytes` bytes of `buffer` (`MAP_READ`), copied out; the buffer is unmapped again.
pub(crate) async fn map_read(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    bytes: u64,
    wait: Wait,
) -> Result<Vec<u8>, GpuError> {
    if bytes == 0 {
        return Ok(Vec::new());
    }
    let mapped: Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>> = Arc::default();
    let flag = mapped.clone();
    let slice = buffer.slice(0..bytes);
    slice.map_async(wgpu::MapMode::Read, move |r| {
        *flag.lock().expect("lock") = Some(r);
    });
    loop {
        wait.idle(device).await?;
        let done = mapped.lock().expect("lock").take();
        match done {
            Some(Ok(())) => break,
            Some(Err(e)) => return Err(GpuError::Readback(e.to_string())),
            None => {}
        }
    }
    let out = slice
        .get_mapped_range()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(out)
}
