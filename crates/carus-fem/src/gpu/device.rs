//! The GPU connection: headless adapter choice, or a device opened elsewhere
//! (the viewer's, so it can later draw straight from the solver's buffers),
//! and bounded waits that turn device faults into errors.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::error::GpuError;

/// Which adapters a headless open accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdapterChoice {
    /// The best adapter there is: a real GPU first, else a software one
    /// such as Mesa's lavapipe (what CI tests on).
    BestAvailable,
    /// A real (non-CPU) GPU only.
    RealGpuOnly,
}

/// A problem the device reported outside any error scope.
#[derive(Debug, Clone, PartialEq)]
enum Fault {
    Error(String),
    Lost(String),
}

/// A wgpu device and queue with the adapter's description. Cloning shares
/// the device (wgpu handles are reference-counted).
#[derive(Clone)]
pub struct GpuDevice {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: wgpu::AdapterInfo,
    /// Faults recorded by the callbacks of a device opened here; a device
    /// given by a caller keeps the caller's callbacks and reports through
    /// error scopes and polling only.
    faults: Arc<Mutex<Option<Fault>>>,
}

impl std::fmt::Debug for GpuDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuDevice")
            .field("adapter", &self.adapter.name)
            .field("backend", &self.adapter.backend)
            .finish()
    }
}

/// Real GPUs first, software rasterisers (lavapipe, WARP, SwiftShader) last.
fn preference(kind: wgpu::DeviceType) -> u8 {
    match kind {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// "VULKAN, METAL", or a note when the selection names no backend.
fn backend_names(backends: wgpu::Backends) -> String {
    let names: Vec<&str> = backends.iter_names().map(|(name, _)| name).collect();
    if names.is_empty() {
        "no backend (WGPU_BACKEND names none built into carus-fem: vulkan, metal, dx12)".into()
    } else {
        names.join(", ")
    }
}

impl GpuDevice {
    /// Opens an adapter without a window, searching the backends built in
    /// (narrowed by the `WGPU_BACKEND` environment variable, as in wgpu).
    pub fn headless(choice: AdapterChoice) -> Result<GpuDevice, GpuError> {
        let descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = descriptor.backends & wgpu::Instance::enabled_backend_features();
        Self::headless_on(backends, choice)
    }

    /// [`Self::headless`] on the given backends only.
    pub fn headless_on(
        backends: wgpu::Backends,
        choice: AdapterChoice,
    ) -> Result<GpuDevice, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.backends = backends;
        let instance = wgpu::Instance::new(descriptor);
        let adapters = if backends.is_empty() {
            Vec::new()
        } else {
            pollster::block_on(instance.enumerate_adapters(backends))
        };
        let found: Vec<String> = adapters
            .iter()
            .map(|a| format!("`{}` ({:?})", a.get_info().name, a.get_info().device_type))
            .collect();
        let adapter = adapters
            .into_iter()
            .filter(|a| {
                choice == AdapterChoice::BestAvailable
                    || a.get_info().device_type != wgpu::DeviceType::Cpu
            })
            .min_by_key(|a| preference(a.get_info().device_type))
            .ok_or_else(|| GpuError::NoAdapter {
                backends: backend_names(backends),
                found: if found.is_empty() {
                    "no adapter".into()
                } else {
                    format!(
                        "only software adapters ({}) where a real GPU was asked for",
                        found.join(", ")
                    )
                },
            })?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("carus-fem TLED"),
            // The adapter's own limits: lavapipe's 128 MiB storage bindings,
            // several GiB on data-centre GPUs.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::DeviceRequest {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        let gpu = Self::from_device(device, queue, info);
        let sink = Arc::clone(&gpu.faults);
        gpu.device
            .on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
                record(&sink, Fault::Error(error.to_string()))
            }));
        let sink = Arc::clone(&gpu.faults);
        gpu.device.set_device_lost_callback(move |reason, message| {
            let detail = if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") };
            record(&sink, Fault::Lost(detail))
        });
        Ok(gpu)
    }

    /// Wraps a device opened elsewhere (for example by carus-render's
    /// `GpuContext` or the viewer's window), so the solver's buffers live on
    /// the device that draws them.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter: wgpu::AdapterInfo,
    ) -> GpuDevice {
        GpuDevice {
            device,
            queue,
            adapter,
            faults: Arc::new(Mutex::new(None)),
        }
    }

    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.adapter
    }

    /// True for a software rasteriser such as lavapipe.
    pub fn is_software(&self) -> bool {
        self.adapter.device_type == wgpu::DeviceType::Cpu
    }

    /// Runs `work` inside out-of-memory, validation and internal error
    /// scopes and returns its value, or the first error the device reported.
    pub(crate) fn scoped<T>(
        &self,
        during: &'static str,
        work: impl FnOnce() -> T,
    ) -> Result<T, GpuError> {
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        // Scopes pop innermost first.
        let errors = [validation.pop(), memory.pop(), internal.pop()].map(pollster::block_on);
        if let Some(error) = errors.into_iter().flatten().next() {
            return Err(GpuError::Device {
                during,
                message: error.to_string(),
            });
        }
        self.check_faults(during)?;
        Ok(value)
    }

    /// Fails with a fault recorded outside the scopes, such as device loss.
    pub(crate) fn check_faults(&self, during: &'static str) -> Result<(), GpuError> {
        let fault = self
            .faults
            .lock()
            .map(|mut slot| slot.take())
            .unwrap_or(None);
        match fault {
            Some(Fault::Lost(message)) => Err(GpuError::DeviceLost { during, message }),
            Some(Fault::Error(message)) => Err(GpuError::Device { during, message }),
            None => Ok(()),
        }
    }

    /// Blocks until everything submitted has finished, at most `timeout`.
    pub(crate) fn wait(&self, during: &'static str, timeout: Duration) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(timeout),
            })
            .map_err(|error| match error {
                wgpu::PollError::Timeout => GpuError::Timeout {
                    during,
                    seconds: timeout.as_secs().max(1),
                },
                other => GpuError::Device {
                    during,
                    message: other.to_string(),
                },
            })?;
        self.check_faults(during)
    }

    /// Copies `bytes` bytes of `source` into host memory (a staging copy,
    /// a bounded wait, a map).
    pub(crate) fn read_buffer(
        &self,
        source: &wgpu::Buffer,
        offset: u64,
        bytes: u64,
        during: &'static str,
        timeout: Duration,
    ) -> Result<Vec<u8>, GpuError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = self.scoped(during, || {
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tled readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("tled readback"),
                });
            encoder.copy_buffer_to_buffer(source, offset, &staging, 0, bytes);
            self.queue.submit([encoder.finish()]);
            staging
        })?;
        let (sender, receiver) = std::sync::mpsc::channel();
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, move |result| {
            // The receiver below is still waiting; if it is gone no one needs the answer.
            let _ = sender.send(result);
        });
        self.wait(during, timeout)?;
        receiver
            .try_recv()
            .map_err(|_| GpuError::Timeout {
                during,
                seconds: timeout.as_secs().max(1),
            })?
            .map_err(|e| GpuError::Device {
                during,
                message: e.to_string(),
            })?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Device {
                during,
                message: e.to_string(),
            })?
            .to_vec();
        staging.unmap();
        Ok(data)
    }
}

/// Keeps the first fault: later ones are usually its consequences.
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
        ];
        kinds.sort_by_key(|k| preference(*k));
        assert_eq!(
            kinds,
            [
                wgpu::DeviceType::DiscreteGpu,
                wgpu::DeviceType::IntegratedGpu,
                wgpu::DeviceType::Other,
                wgpu::DeviceType::Cpu
            ]
        );
    }

    #[test]
    fn no_backend_fails_with_the_fix() {
        let err = GpuDevice::headless_on(wgpu::Backends::empty(), AdapterChoice::BestAvailable)
            .unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, GpuError::NoAdapter { .. }), "{text}");
        assert!(
            text.contains("mesa-vulkan-drivers") && text.contains("no backend"),
            "{text}"
        );
    }

    #[test]
    fn only_the_first_fault_is_kept() {
        let sink = Mutex::new(None);
        record(&sink, Fault::Error("first".into()));
        record(&sink, Fault::Lost("second".into()));
        assert_eq!(*sink.lock().unwrap(), Some(Fault::Error("first".into())));
    }
}
