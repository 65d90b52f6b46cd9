//! Plain-data triangle meshes as callers hand them to the renderer.
//!
//! No dependency on any other Carus crate: the anatomy and labour crates
//! convert their surfaces into these vectors.

use glam::Vec3;

use crate::colour::ColourMap;
use crate::error::RenderError;

/// A per-vertex scalar field (stress, stretch) drawn through a colour map.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarField {
    /// One value per vertex.
    pub values: Vec<f32>,
    /// Values mapped to the two ends of the colour map; values outside are clamped.
    pub range: [f32; 2],
    /// The colour map.
    pub colour_map: ColourMap,
}

/// One triangle mesh with its own colour.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderMesh {
    /// Name used in error messages ("pelvis", "fetal head").
    pub name: String,
    /// Vertex positions, in any length unit (the camera fits the scene's bounds).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals agreeing with the winding; `None`: computed from
    /// the triangles (area-weighted).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Triangles, three vertex indices each, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// sRGB colour with opacity in alpha (below 1: drawn semi-transparent).
    pub colour: [f32; 4],
    /// Optional scalar field; where present it replaces the colour's RGB.
    pub scalars: Option<ScalarField>,
}

impl RenderMesh {
    /// An opaque mesh of one sRGB colour, normals computed.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<[f32; 3]>,
        indices: Vec<u32>,
        rgb: [f32; 3],
    ) -> Self {
        Self {
            name: name.into(),
            positions,
            normals: None,
            indices,
            colour: [rgb[0], rgb[1], rgb[2], 1.0],
            scalars: None,
        }
    }

    /// Uses the given vertex normals instead of computing them.
    pub fn with_normals(mut self, normals: Vec<[f32; 3]>) -> Self {
        self.normals = Some(normals);
        self
    }

    /// Sets the opacity (1 opaque, 0 invisible).
    pub fn with_opacity(mut self, opacity: f32) -> Self {
        self.colour[3] = opacity;
        self
    }

    /// Colours the mesh by a per-vertex scalar field.
    pub fn with_scalars(
        mut self,
        values: Vec<f32>,
        range: [f32; 2],
        colour_map: ColourMap,
    ) -> Self {
        self.scalars = Some(ScalarField {
            values,
            range,
            colour_map,
        });
        self
    }

    /// True when the mesh is drawn blended over what lies behind it.
    pub fn is_transparent(&self) -> bool {
        self.colour[3] < 1.0
    }

    /// Axis-aligned bounds of the vertices; `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<Bounds> {
        Bounds::of_points(&self.positions)
    }

    /// Checks sizes, indices and numbers; `index` is the mesh's place in its scene.
    pub fn validate(&self, index: usize) -> Result<(), RenderError> {
        let fail = |problem: String| RenderError::InvalidMesh {
            mesh: index,
            name: self.name.clone(),
            problem,
        };
        if self.positions.is_empty() || self.indices.is_empty() {
            return Err(fail("has no vertices or no triangles".into()));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(fail(format!(
                "index count {} is not a multiple of 3 (triangles only)",
                self.indices.len()
            )));
        }
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(fail(format!(
                "vertex {v} has a non-finite coordinate {:?}",
                self.positions[v]
            )));
        }
        if let Some(i) = self
            .indices
            .iter()
            .position(|&i| i as usize >= self.positions.len())
        {
            return Err(fail(format!(
                "triangle {} refers to vertex {} but there are only {} vertices",
                i / 3,
                self.indices[i],
                self.positions.len()
            )));
        }
        if let Some(normals) = &self.normals {
            if normals.len() != self.positions.len() {
                return Err(fail(format!(
                    "{} normals for {} vertices",
                    normals.len(),
                    self.positions.len()
                )));
            }
            if let Some(v) = normals
                .iter()
                .position(|n| n.iter().any(|c| !c.is_finite()))
            {
                return Err(fail(format!("normal {v} is not finite")));
            }
        }
        if let Some(c) = self.colour.iter().find(|c| !(0.0..=1.0).contains(*c)) {
            return Err(fail(format!("colour channel {c} is outside 0..=1")));
        }
        if let Some(field) = &self.scalars {
            if field.values.len() != self.positions.len() {
                return Err(fail(format!(
                    "{} scalar values for {} vertices",
                    field.values.len(),
                    self.positions.len()
                )));
            }
            let [lo, hi] = field.range;
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(fail(format!(
                    "scalar range [{lo}, {hi}] must be finite with its upper end above its lower"
                )));
            }
            if let Some(v) = field.values.iter().position(|s| !s.is_finite()) {
                return Err(fail(format!("scalar value of vertex {v} is not finite")));
            }
        }
        Ok(())
    }

    /// The given normals, or area-weighted normals of the triangles around
    /// each vertex (a vertex on no triangle gets +z).
    pub fn vertex_normals(&self) -> Vec<[f32; 3]> {
        if let Some(normals) = &self.normals {
            return normals.clone();
        }
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] =
                [tri[0], tri[1], tri[2]].map(|i| Vec3::from(self.positions[i as usize]));
            // The cross product's length is twice the area: larger triangles weigh more.
            let n = (b - a).cross(c - a);
            for &i in tri {
                sums[i as usize] += n;
            }
        }
        sums.into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Z).to_array())
            .collect()
    }
}

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest coordinates.
    pub min: [f32; 3],
    /// Largest coordinates.
    pub max: [f32; 3],
}

impl Bounds {
    /// Bounds of a set of points; `None` when empty.
    pub fn of_points(points: &[[f32; 3]]) -> Option<Self> {
        let first = *points.first()?;
        Some(points.iter().fold(
            Self {
                min: first,
                max: first,
            },
            |b, p| b.including(*p),
        ))
    }

    /// The smallest box holding both.
    pub fn union(self, other: Self) -> Self {
        self.including(other.min).including(other.max)
    }

    fn including(self, p: [f32; 3]) -> Self {
        Self {
            min: Vec3::from(self.min).min(Vec3::from(p)).to_array(),
            max: Vec3::from(self.max).max(Vec3::from(p)).to_array(),
        }
    }

    /// Centre of the box.
    pub fn centre(&self) -> Vec3 {
        (Vec3::from(self.min) + Vec3::from(self.max)) * 0.5
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (lo, hi) = (self.min, self.max);
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            )
        })
    }

    /// Half the diagonal: radius of the sphere around the box.
    pub fn radius(&self) -> f32 {
        (Vec3::from(self.max) - Vec3::from(self.min)).length() * 0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> RenderMesh {
        RenderMesh::new(
            "triangle",
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
            [0.5, 0.5, 0.5],
        )
    }

    #[test]
    fn counter_clockwise_triangle_faces_plus_z() {
        for n in triangle().vertex_normals() {
            assert_eq!(n, [0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn bad_index_is_named() {
        let mut mesh = triangle();
        mesh.indices = vec![0, 1, 7];
        let message = mesh.validate(3).unwrap_err().to_string();
        assert!(message.contains("mesh 3"), "{message}");
        assert!(message.contains("vertex 7"), "{message}");
    }

    #[test]
    fn non_finite_vertex_and_wrong_scalar_count_are_refused() {
        let mut mesh = triangle();
        mesh.positions[1][2] = f32::NAN;
        assert!(mesh
            .validate(0)
            .unwrap_err()
            .to_string()
            .contains("vertex 1"));
        let mesh = triangle().with_scalars(vec![1.0], [0.0, 1.0], ColourMap::Viridis);
        assert!(mesh
            .validate(0)
            .unwrap_err()
            .to_string()
            .contains("1 scalar values for 3"));
        let mesh = triangle().with_scalars(vec![1.0; 3], [1.0, 1.0], ColourMap::Viridis);
        assert!(mesh.validate(0).is_err());
    }

    #[test]
    fn bounds_hold_every_point() {
        let b = Bounds::of_points(&[[1.0, -2.0, 3.0], [-1.0, 4.0, 0.0]]).unwrap();
        assert_eq!(b.min, [-1.0, -2.0, 0.0]);
        assert_eq!(b.max, [1.0, 4.0, 3.0]);
        assert_eq!(b.centre(), Vec3::new(0.0, 1.0, 1.5));
        assert!(Bounds::of_points(&[]).is_none());
    }
}
