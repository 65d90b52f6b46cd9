//! The GPU connection: adapter choice, device, and turning the device's
//! asynchronous errors and waits into `Result`s with time limits.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::error::RenderError;

/// Longest wait for the GPU to finish one picture or one readback. A
/// software rasteriser on two cores draws a report picture in well under a
/// second; a minute means something hangs.
pub const GPU_TIMEOUT: Duration = Duration::from_secs(60);

/// A device and its queue, with the adapter's description.
pub struct GpuContext {
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Which adapter the device runs on.
    pub adapter_info: wgpu::AdapterInfo,
    /// Errors reported outside any error scope, and device loss: kept here
    /// (instead of wgpu's default panic) until the next call collects them.
    uncaptured: Arc<Mutex<Option<Fault>>>,
}

/// A problem the device reported outside any error scope.
#[derive(Debug, Clone, PartialEq)]
enum Fault {
    Error(String),
    Lost(String),
}

/// Preference among adapter kinds: real GPUs first, software rasterisers
/// (lavapipe, WARP, SwiftShader) accepted last.
fn preference(kind: wgpu::DeviceType) -> u8 {
    match kind {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

impl GpuContext {
    /// Opens the best adapter without any window: a real GPU when there is
    /// one, otherwise a software adapter such as Mesa's lavapipe. The
    /// `WGPU_BACKEND` environment variable narrows the backends searched.
    pub fn new_headless() -> Result<Self, RenderError> {
        let descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = descriptor.backends & wgpu::Instance::enabled_backend_features();
        let instance = wgpu::Instance::new(descriptor);
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let adapter = adapters
            .into_iter()
            .min_by_key(|a| preference(a.get_info().device_type))
            .ok_or_else(|| RenderError::NoAdapter {
                backends: backend_names(backends),
            })?;
        let adapter_info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("carus-render"),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::DeviceRequest {
            adapter: adapter_info.name.clone(),
            reason: e.to_string(),
        })?;
        let context = Self::from_device(device, queue, adapter_info);
        let sink = Arc::clone(&context.uncaptured);
        context
            .device
            .on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
                record(&sink, Fault::Error(error.to_string()));
            }));
        let sink = Arc::clone(&context.uncaptured);
        context
            .device
            .set_device_lost_callback(move |reason, message| {
                record(&sink, Fault::Lost(format!("{reason:?}: {message}")));
            });
        Ok(context)
    }

    /// Wraps a device opened elsewhere (the viewer's window, the GPU
    /// solver) so pictures can be drawn with it. The caller keeps its own
    /// uncaptured-error handler; errors inside `render` are caught by error
    /// scopes either way.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter_info: wgpu::AdapterInfo,
    ) -> Self {
        Self {
            device,
            queue,
            adapter_info,
            uncaptured: Arc::new(Mutex::new(None)),
        }
    }

    /// True when the adapter is a software rasteriser (such as lavapipe).
    pub fn is_software(&self) -> bool {
        self.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// Runs `work` inside validation, out-of-memory and internal error
    /// scopes and returns its value, or the first error the device reported.
    pub(crate) fn scoped<T>(
        &self,
        during: &'static str,
        work: impl FnOnce() -> T,
    ) -> Result<T, RenderError> {
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        // Scopes pop innermost first.
        let errors = [validation.pop(), memory.pop(), internal.pop()].map(pollster::block_on);
        if let Some(error) = errors.into_iter().flatten().next() {
            return Err(RenderError::Gpu {
                during,
                message: error.to_string(),
            });
        }
        self.check_uncaptured(during)?;
        Ok(value)
    }

    /// Fails with an error recorded outside the scopes, such as device loss.
    pub(crate) fn check_uncaptured(&self, during: &'static str) -> Result<(), RenderError> {
        let recorded = self
            .uncaptured
            .lock()
            .map(|mut slot| slot.take())
            .unwrap_or(None);
        match recorded {
            Some(Fault::Lost(message)) => Err(RenderError::DeviceLost(message)),
            Some(Fault::Error(message)) => Err(RenderError::Gpu { during, message }),
            None => Ok(()),
        }
    }

    /// Blocks until a submission has finished, at most `GPU_TIMEOUT`.
    pub(crate) fn wait(
        &self,
        submission: wgpu::SubmissionIndex,
        during: &'static str,
    ) -> Result<(), RenderError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(submission),
                timeout: Some(GPU_TIMEOUT),
            })
            .map(|_| ())
            .map_err(|error| match error {
                wgpu::PollError::Timeout => RenderError::Timeout {
                    during,
                    seconds: GPU_TIMEOUT.as_secs(),
                },
                other => RenderError::Gpu {
                    during,
                    message: other.to_string(),
                },
            })?;
        self.check_uncaptured(during)
    }
}

/// "VULKAN, METAL", or a hint when the environment ruled every backend out.
fn backend_names(backends: wgpu::Backends) -> String {
    let names: Vec<&str> = backends.iter_names().map(|(name, _)| name).collect();
    if names.is_empty() {
        "none: WGPU_BACKEND names no backend built into carus-render (vulkan, metal, dx12)".into()
    } else {
        names.join(", ")
    }
}

/// Keeps the first message: later ones are usually its consequences.
fn record(sink: &Mutex<Option<Fault>>, fault: Fault) {
    if let Ok(mut slot) = sink.lock() {
        slot.get_or_insert(fault);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_gpus_are_preferred_to_software() {
        let mut kinds = [
            wgpu::DeviceType::Cpu,
            wgpu::DeviceType::Other,
            wgpu::DeviceType::IntegratedGpu,
            wgpu::DeviceType::DiscreteGpu,
            wgpu::DeviceType::VirtualGpu,
        ];
        kinds.sort_by_key(|k| preference(*k));
        assert_eq!(kinds[0], wgpu::DeviceType::DiscreteGpu);
        assert_eq!(kinds[4], wgpu::DeviceType::Cpu);
    }

    #[test]
    fn backends_are_named_for_people() {
        assert_eq!(backend_names(wgpu::Backends::VULKAN), "VULKAN");
        assert!(backend_names(wgpu::Backends::empty()).contains("WGPU_BACKEND"));
    }

    #[test]
    fn only_the_first_uncaptured_error_is_kept() {
        let sink = Mutex::new(None);
        record(&sink, Fault::Error("first".into()));
        record(&sink, Fault::Lost("second".into()));
        assert_eq!(*sink.lock().unwrap(), Some(Fault::Error("first".into())));
    }
}
