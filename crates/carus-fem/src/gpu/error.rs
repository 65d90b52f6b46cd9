//! Errors of the GPU backend. Each says what was tried and the fix.

use thiserror::Error;

use crate::error::FemError;

/// The package that provides Mesa's CPU Vulkan driver on Debian and Ubuntu.
pub const LAVAPIPE_HINT: &str =
    "install a GPU driver with Vulkan support, or Mesa's CPU driver lavapipe (apt-get install mesa-vulkan-drivers libvulkan1), or use the CPU backend (--backend cpu)";

#[derive(Debug, Clone, PartialEq, Error)]
pub enum GpuError {
    #[error(
        "no usable GPU adapter: tried the {backends} backend(s) and found {found}; {LAVAPIPE_HINT}"
    )]
    NoAdapter { backends: String, found: String },
    #[error("could not open a device on adapter `{adapter}`: {reason}")]
    DeviceRequest { adapter: String, reason: String },
    #[error(
        "the {buffer} buffer needs {bytes} bytes, over the {limit_name} of {limit} bytes on adapter `{adapter}` \
         (model of {elements} elements, {nodes} nodes); use a coarser mesh, a GPU with larger limits, or the CPU backend"
    )]
    BufferTooLarge {
        buffer: &'static str,
        bytes: u64,
        limit_name: &'static str,
        limit: u64,
        adapter: String,
        elements: usize,
        nodes: usize,
    },
    #[error("adapter `{adapter}` allows {available} {what} per kernel, the TLED kernels need {needed}; open the device with the adapter's limits (GpuDevice::headless does)")]
    LimitTooLow {
        what: &'static str,
        needed: u64,
        available: u64,
        adapter: String,
    },
    #[error("the boundary conditions use {count} different load shapes, the GPU backend takes at most {max}; share load shapes between loads or use the CPU backend")]
    TooManyLoadShapes { count: usize, max: usize },
    #[error("the GPU reported an error while {during}: {message}")]
    Device {
        during: &'static str,
        message: String,
    },
    #[error("the GPU device was lost while {during} ({message}); the state on the GPU is gone: restore a snapshot on a new device, or use the CPU backend")]
    DeviceLost {
        during: &'static str,
        message: String,
    },
    #[error("the GPU did not finish {during} within {seconds} s; lower GpuOptions::max_steps_per_submission or raise GpuOptions::wait_timeout")]
    Timeout { during: &'static str, seconds: u64 },
    #[error(transparent)]
    Solver(#[from] FemError),
}
