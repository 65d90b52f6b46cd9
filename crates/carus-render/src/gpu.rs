//! The GPU connection is carus-gpu's (shared with the TLED solver, so a
//! viewer can draw the solver's buffers on one device); here its faults
//! become [`RenderError`]s with the renderer's fixes.

use std::time::Duration;

pub use carus_gpu::{AdapterChoice, Gpu as GpuContext};
use carus_gpu::DeviceError;

use crate::error::RenderError;

/// Longest wait for the GPU to finish one picture or one readback. A
/// software rasteriser on two cores draws a report picture in well under a
/// second; a minute means something hangs.
pub const GPU_TIMEOUT: Duration = Duration::from_secs(60);

impl From<DeviceError> for RenderError {
    fn from(error: DeviceError) -> Self {
        match error {
            DeviceError::NoAdapter { backends, found } => RenderError::NoAdapter { backends, found },
            DeviceError::DeviceRequest { adapter, reason } => RenderError::DeviceRequest { adapter, reason },
            DeviceError::Device { during, message } => RenderError::Gpu { during, message },
            DeviceError::DeviceLost { during, message } => RenderError::DeviceLost(format!("while {during}: {message}")),
            DeviceError::Timeout { during, seconds } => RenderError::Timeout { during, seconds },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_backend_says_how_to_get_one() {
        let err: RenderError = GpuContext::headless_on(wgpu::Backends::empty(), AdapterChoice::BestAvailable)
            .unwrap_err()
            .into();
        let text = err.to_string();
        assert!(matches!(err, RenderError::NoAdapter { .. }), "{text}");
        assert!(text.contains("mesa-vulkan-drivers") && text.contains("no backend"), "{text}");
    }
}
