//! The GPU connection is carus-gpu's (shared with the renderer, so the
//! solver's buffers can live on the device that draws them); here its
//! faults become [`GpuError`]s with the solver's fixes.

pub use carus_gpu::{AdapterChoice, DeviceError, Gpu as GpuDevice};

use super::error::GpuError;

impl From<DeviceError> for GpuError {
    fn from(error: DeviceError) -> Self {
        match error {
            DeviceError::NoAdapter { backends, found } => GpuError::NoAdapter { backends, found },
            DeviceError::DeviceRequest { adapter, reason } => GpuError::DeviceRequest { adapter, reason },
            DeviceError::Device { during, message } => GpuError::Device { during, message },
            DeviceError::DeviceLost { during, message } => GpuError::DeviceLost { during, message },
            DeviceError::Timeout { during, seconds } => GpuError::Timeout { during, seconds },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_backend_fails_with_the_fix() {
        let err: GpuError = GpuDevice::headless_on(wgpu::Backends::empty(), AdapterChoice::BestAvailable)
            .unwrap_err()
            .into();
        let text = err.to_string();
        assert!(matches!(err, GpuError::NoAdapter { .. }), "{text}");
        assert!(text.contains("mesa-vulkan-drivers") && text.contains("no backend"), "{text}");
    }
}
