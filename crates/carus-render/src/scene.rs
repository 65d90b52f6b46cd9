//! What is drawn: meshes, lights and the background.

use crate::error::RenderError;
use crate::mesh::{Bounds, RenderMesh};

/// A directional light fixed to the camera, so every view is lit alike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalLight {
    /// Direction towards the light in camera space (x picture right,
    /// y picture up, z towards the viewer); need not be unit length.
    pub towards_light: [f32; 3],
    /// Intensity (1 lights a facing surface with its full colour).
    pub intensity: f32,
}

/// A studio set-up: key and fill lights, a headlight, ambient and a rim
/// term so that bone reads as three-dimensional from any view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lights {
    /// Main light, from the upper left in front.
    pub key: DirectionalLight,
    /// Softer light from the other side, filling the key's shadows.
    pub fill: DirectionalLight,
    /// Light from the eye itself (intensity only).
    pub headlight: f32,
    /// Uniform light on every surface.
    pub ambient: f32,
    /// Brightening of surfaces seen edge-on, outlining silhouettes.
    pub rim: f32,
}

impl Default for Lights {
    fn default() -> Self {
        Self {
            key: DirectionalLight {
                towards_light: [-0.5, 0.6, 0.65],
                intensity: 0.8,
            },
            fill: DirectionalLight {
                towards_light: [0.7, -0.2, 0.5],
                intensity: 0.2,
            },
            headlight: 0.1,
            ambient: 0.08,
            rim: 0.25,
        }
    }
}

/// Meshes, lights and the background of one picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Meshes; opaque ones are drawn first, transparent ones after, far to near.
    pub meshes: Vec<RenderMesh>,
    /// Lighting.
    pub lights: Lights,
    /// sRGB background colour with alpha.
    pub background: [f32; 4],
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            meshes: Vec::new(),
            lights: Lights::default(),
            background: [1.0, 1.0, 1.0, 1.0],
        }
    }
}

impl Scene {
    /// A scene of these meshes with the default lights on white.
    pub fn new(meshes: Vec<RenderMesh>) -> Self {
        Self {
            meshes,
            ..Self::default()
        }
    }

    /// Bounds of every mesh, to fit a camera to.
    pub fn bounds(&self) -> Result<Bounds, RenderError> {
        self.meshes
            .iter()
            .filter_map(RenderMesh::bounds)
            .reduce(Bounds::union)
            .ok_or(RenderError::EmptyBounds("the scene has no vertices"))
    }

    /// Checks every mesh and the background.
    pub fn validate(&self) -> Result<(), RenderError> {
        check_background(self.background)?;
        self.meshes
            .iter()
            .enumerate()
            .try_for_each(|(i, mesh)| mesh.validate(i))
    }
}

/// A background must be an sRGB colour with alpha, every channel in 0..=1.
pub(crate) fn check_background(background: [f32; 4]) -> Result<(), RenderError> {
    if background.iter().all(|c| (0.0..=1.0).contains(c)) {
        Ok(())
    } else {
        Err(RenderError::InvalidBackground(background))
    }
}
