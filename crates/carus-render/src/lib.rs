//! Offscreen rendering of triangle meshes from standard anatomical views.
//!
//! Carus draws its anatomy (pelvis, fetus, pelvic floor) for the docs and
//! the key moments of a labour into its HTML report with this crate; the
//! interactive viewer reuses its drawing. Input is plain data
//! ([`RenderMesh`]), so any crate can call it without depending on the
//! anatomy or simulation crates.
//!
//! - [`Renderer::new_headless`] opens a real GPU or a software Vulkan
//!   driver (Mesa's lavapipe) without a window.
//! - [`Camera::standard`] looks at the scene from a [`View`] of the pelvis
//!   frame (x to the mother's right, y anterior, z cranial).
//! - [`Renderer::render`] returns an RGBA8 [`Image`]; [`Image::encode_png`]
//!   and [`Image::save_png`] turn it into PNG.
//! - [`MeshPainter`] is the drawing without the target, for a window's
//!   render pass.

mod camera;
mod colour;
mod contact_sheet;
mod error;
mod gpu;
mod mesh;
mod offscreen;
mod painter;
mod picture;
mod png;
mod scene;
mod shapes;

pub use camera::{Camera, Projection, View};
pub use colour::{linear_to_srgb, srgb_to_linear, ColourMap};
pub use contact_sheet::{ContactSheet, LABEL_STRIP};
pub use error::RenderError;
pub use gpu::{GpuContext, GPU_TIMEOUT};
pub use mesh::{Bounds, RenderMesh, ScalarField};
pub use offscreen::{GpuScene, Renderer};
pub use painter::{GpuMesh, MeshPainter, TargetFormat};
pub use picture::Image;
pub use scene::{DirectionalLight, Lights, Scene};
