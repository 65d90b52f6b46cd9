//! The GPU connection of Carus, shared by the TLED solver's GPU backend
//! (carus-fem, feature `gpu`) and the renderer (carus-render): a headless
//! adapter choice, or a device opened elsewhere (a viewer's window), and
//! every asynchronous device fault and wait turned into a bounded `Result`.
//! Each user maps [`DeviceError`] into its own error type, adding its fix.

use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Faults of the device, its opening and its waits.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviceError {
    #[error("no usable GPU adapter: tried the {backends} backend(s) and found {found}")]
    NoAdapter { backends: String, found: String },
    #[error("could not open a device on adapter `{adapter}`: {reason}")]
    DeviceRequest { adapter: String, reason: String },
    /// A validation, out-of-memory or internal error.
    #[error("the GPU reported an error while {during}: {message}")]
    Device { during: &'static str, message: String },
    /// Driver reset, GPU removed, or the device destroyed.
    #[error("the GPU device was lost while {during} ({message})")]
    DeviceLost { during: &'static str, message: String },
    #[error("the GPU did not finish {during} within {seconds} s")]
    Timeout { during: &'static str, seconds: u64 },
}

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
/// the device (wgpu handles are reference-counted), so the solver and the
/// renderer can work on one device.
#[derive(Clone)]
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: wgpu::AdapterInfo,
    /// Faults recorded by the callbacks of a device opened here; a device
    /// given by a caller keeps the caller's callbacks and reports through
    /// error scopes and polling only.
    faults: Arc<Mutex<Option<Fault>>>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
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
        "no backend (WGPU_BACKEND names none that Carus searches headless: vulkan, metal, dx12)".into()
    } else {
        names.join(", ")
    }
}

/// Keeps the first fault: later ones are usually its consequences.
fn record(sink: &Mutex<Option<Fault>>, fault: Fault) {
    if let Ok(mut slot) = sink.lock() {
        slot.get_or_insert(fault);
    }
}

impl Gpu {
    /// Opens an adapter without a window, searching the backends built in
    /// (narrowed by the `WGPU_BACKEND` environment variable, as in wgpu).
    /// Only the primary ones: the viewer's eframe also builds wgpu's GL
    /// backend, whose EGL library, once loaded, races the threads ending
    /// at exit and crashed about one `carus sweep` in 150 (glibc heap).
    pub fn headless(choice: AdapterChoice) -> Result<Gpu, DeviceError> {
        let descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = descriptor.backends & wgpu::Backends::PRIMARY & wgpu::Instance::enabled_backend_features();
        Self::headless_on(backends, choice)
    }

    /// [`Self::headless`] on the given backends only.
    pub fn headless_on(backends: wgpu::Backends, choice: AdapterChoice) -> Result<Gpu, DeviceError> {
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
            .filter(|a| choice == AdapterChoice::BestAvailable || a.get_info().device_type != wgpu::DeviceType::Cpu)
            .min_by_key(|a| preference(a.get_info().device_type))
            .ok_or_else(|| DeviceError::NoAdapter {
                backends: backend_names(backends),
                found: if found.is_empty() {
                    "no adapter".into()
                } else {
                    format!("only software adapters ({}) where a real GPU was asked for", found.join(", "))
                },
            })?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("carus"),
            // The adapter's own limits: lavapipe's 128 MiB storage bindings,
            // several GiB on data-centre GPUs.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| DeviceError::DeviceRequest { adapter: info.name.clone(), reason: e.to_string() })?;
        let gpu = Self::from_device(device, queue, info);
        let sink = Arc::clone(&gpu.faults);
        gpu.device
            .on_uncaptured_error(Arc::new(move |error: wgpu::Error| record(&sink, Fault::Error(error.to_string()))));
        let sink = Arc::clone(&gpu.faults);
        gpu.device.set_device_lost_callback(move |reason, message| {
            let detail = if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") };
            record(&sink, Fault::Lost(detail))
        });
        Ok(gpu)
    }

    /// Wraps a device opened elsewhere (a viewer's window, or another Carus
    /// part), so buffers and pictures live on the device that draws them.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, adapter: wgpu::AdapterInfo) -> Gpu {
        Gpu { device, queue, adapter, faults: Arc::new(Mutex::new(None)) }
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
    pub fn scoped<T>(&self, during: &'static str, work: impl FnOnce() -> T) -> Result<T, DeviceError> {
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        // Scopes pop innermost first.
        let errors = [validation.pop(), memory.pop(), internal.pop()].map(pollster::block_on);
        if let Some(error) = errors.into_iter().flatten().next() {
            return Err(DeviceError::Device { during, message: error.to_string() });
        }
        self.check_faults(during)?;
        Ok(value)
    }

    /// Fails with a fault recorded outside the scopes, such as device loss.
    pub fn check_faults(&self, during: &'static str) -> Result<(), DeviceError> {
        let fault = self.faults.lock().map(|mut slot| slot.take()).unwrap_or(None);
        match fault {
            Some(Fault::Lost(message)) => Err(DeviceError::DeviceLost { during, message }),
            Some(Fault::Error(message)) => Err(DeviceError::Device { during, message }),
            None => Ok(()),
        }
    }

    /// Blocks until `submission` (or everything submitted, for None) has
    /// finished, at most `timeout`.
    pub fn wait(
        &self,
        submission: Option<wgpu::SubmissionIndex>,
        during: &'static str,
        timeout: Duration,
    ) -> Result<(), DeviceError> {
        let seconds = timeout.as_secs().max(1);
        self.device
            .poll(wgpu::PollType::Wait { submission_index: submission, timeout: Some(timeout) })
            .map_err(|error| match error {
                wgpu::PollError::Timeout => DeviceError::Timeout { during, seconds },
                other => DeviceError::Device { during, message: other.to_string() },
            })?;
        self.check_faults(during)
    }

    /// Copies `bytes` bytes of `source` from `offset` into host memory (a
    /// staging copy, a bounded wait, a map).
    pub fn read_buffer(
        &self,
        source: &wgpu::Buffer,
        offset: u64,
        bytes: u64,
        during: &'static str,
        timeout: Duration,
    ) -> Result<Vec<u8>, DeviceError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = self.scoped(during, || {
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("carus readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder =
                self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("carus readback") });
            encoder.copy_buffer_to_buffer(source, offset, &staging, 0, bytes);
            self.queue.submit([encoder.finish()]);
            staging
        })?;
        self.map_read(&staging, during, timeout)
    }

    /// Maps a MAP_READ buffer whose copy has been submitted and returns its
    /// bytes (a bounded wait; the buffer is unmapped again).
    pub fn map_read(&self, buffer: &wgpu::Buffer, during: &'static str, timeout: Duration) -> Result<Vec<u8>, DeviceError> {
        let (sender, receiver) = std::sync::mpsc::channel();
        let slice = buffer.slice(..);
        slice.map_async(wgpu::MapMode::Read, move |result| {
            // The receiver below is still waiting; if it is gone no one needs the answer.
            let _ = sender.send(result);
        });
        self.wait(None, during, timeout)?;
        let seconds = timeout.as_secs().max(1);
        receiver
            .try_recv()
            .map_err(|_| DeviceError::Timeout { during, seconds })?
            .map_err(|e| DeviceError::Device { during, message: e.to_string() })?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| DeviceError::Device { during, message: e.to_string() })?
            .to_vec();
        buffer.unmap();
        Ok(data)
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
        assert_eq!(
            kinds,
            [
                wgpu::DeviceType::DiscreteGpu,
                wgpu::DeviceType::IntegratedGpu,
                wgpu::DeviceType::VirtualGpu,
                wgpu::DeviceType::Other,
                wgpu::DeviceType::Cpu
            ]
        );
    }

    #[test]
    fn only_the_first_fault_is_kept() {
        let sink = Mutex::new(None);
        record(&sink, Fault::Error("first".into()));
        record(&sink, Fault::Lost("second".into()));
        assert_eq!(*sink.lock().unwrap(), Some(Fault::Error("first".into())));
    }

    #[test]
    fn no_backend_is_an_error_that_says_so() {
        let err = Gpu::headless_on(wgpu::Backends::empty(), AdapterChoice::BestAvailable).unwrap_err();
        assert!(matches!(err, DeviceError::NoAdapter { .. }), "{err}");
        assert!(err.to_string().contains("no backend"), "{err}");
    }

    /// CI has lavapipe: a readback returns what was written, and a destroyed
    /// device is an error at the next wait, not a hang.
    #[test]
    fn readback_and_device_loss() {
        let gpu = Gpu::headless(AdapterChoice::BestAvailable)
            .unwrap_or_else(|e| panic!("these tests need a Vulkan adapter (CI installs lavapipe): {e}"));
        let data: Vec<u8> = (0..=255).collect();
        let buffer = gpu.device().create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 256,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue().write_buffer(&buffer, 0, &data);
        let back = gpu.read_buffer(&buffer, 16, 32, "reading back", Duration::from_secs(60)).unwrap();
        assert_eq!(back, data[16..48]);
        gpu.device().destroy();
        let err = gpu.read_buffer(&buffer, 0, 16, "reading back", Duration::from_secs(60)).unwrap_err();
        assert!(matches!(err, DeviceError::DeviceLost { .. } | DeviceError::Device { .. }), "{err}");
    }
}
