//! Errors of the renderer: each names what failed and how to fix it.

use std::path::PathBuf;

/// Everything that can go wrong between a scene and its pixels.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU and no software rasteriser could be found.
    #[error(
        "no graphics adapter found (backends tried: {backends}; found {found}); \
         on Debian/Ubuntu install Mesa's CPU Vulkan driver lavapipe with \
         `apt-get install -y mesa-vulkan-drivers libvulkan1`"
    )]
    NoAdapter {
        /// The wgpu backends that were searched.
        backends: String,
        /// What was there instead.
        found: String,
    },
    /// An adapter exists but refused to open a device.
    #[error("adapter `{adapter}` refused to open a device: {reason}")]
    DeviceRequest {
        /// Adapter name as the driver reports it.
        adapter: String,
        /// Driver's reason.
        reason: String,
    },
    /// The device reported a validation, out-of-memory or internal error.
    #[error("GPU error while {during}: {message}")]
    Gpu {
        /// What the renderer was doing.
        during: &'static str,
        /// The driver's description.
        message: String,
    },
    /// The device was lost (driver reset, GPU removed).
    #[error("GPU device lost: {0}; create a new Renderer")]
    DeviceLost(String),
    /// The GPU did not finish within the time limit.
    #[error("GPU did not finish {during} within {seconds} s")]
    Timeout {
        /// What the renderer was waiting for.
        during: &'static str,
        /// The limit that ran out.
        seconds: u64,
    },
    /// The requested picture size is zero or above the adapter's limit.
    #[error("picture size {width}x{height} is invalid: each side must be 1 to {max} pixels")]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest side the adapter accepts.
        max: u32,
    },
    /// A mesh of the scene is malformed.
    #[error("mesh {mesh} (`{name}`): {problem}")]
    InvalidMesh {
        /// Index of the mesh in the scene.
        mesh: usize,
        /// Its name.
        name: String,
        /// What is wrong and where.
        problem: String,
    },
    /// The background colour is not a colour.
    #[error("background colour {0:?} has a channel outside 0..=1 (sRGB with alpha)")]
    InvalidBackground([f32; 4]),
    /// The scene has nothing to fit a camera to.
    #[error("cannot fit a camera: {0}")]
    EmptyBounds(&'static str),
    /// A camera parameter is out of range.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// PNG encoding or decoding failed.
    #[error("PNG {during} failed: {source}")]
    Png {
        /// "encoding" or "decoding".
        during: &'static str,
        /// The codec's error.
        source: image::ImageError,
    },
    /// Writing a PNG file failed.
    #[error("cannot write `{path}`: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Pixel buffer and stated size disagree.
    #[error("image of {width}x{height} needs {expected} RGBA bytes, got {actual}")]
    PixelCount {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// width * height * 4.
        expected: usize,
        /// Bytes given.
        actual: usize,
    },
}
