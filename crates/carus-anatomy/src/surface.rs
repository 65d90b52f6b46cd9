//! Closed triangle surfaces: the bony pelvis, the fetal skin, imported meshes.

use std::collections::HashMap;

use glam::{DAffine3, DVec3};
use serde::{Deserialize, Serialize};

/// A triangle surface in metres. Triangles list vertex indices counter-clockwise
/// seen from outside, so the right-hand normal points outwards.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TriSurface {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Why a surface is not a closed, consistently oriented 2-manifold.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceDefect {
    #[error("the surface has no triangles")]
    Empty,
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex { vertex: usize },
    #[error("triangle {triangle} refers to vertex {vertex}, but there are only {count} vertices")]
    VertexOutOfRange {
        triangle: usize,
        vertex: u32,
        count: usize,
    },
    #[error("triangle {triangle} is degenerate (repeated vertex)")]
    DegenerateTriangle { triangle: usize },
    #[error("edge {a}-{b} borders only one triangle ({triangle}): the surface is open there")]
    OpenEdge { a: u32, b: u32, triangle: usize },
    #[error("edge {a}-{b} borders {count} triangles: the surface is non-manifold there")]
    NonManifoldEdge { a: u32, b: u32, count: usize },
    #[error("edge {a}-{b} is traversed the same way by two triangles: orientation flips there")]
    InconsistentOrientation { a: u32, b: u32 },
    #[error("the enclosed volume is negative: the triangles face inwards")]
    InwardFacing,
}

impl TriSurface {
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        TriSurface {
            vertices,
            triangles,
        }
    }

    /// Corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Total area, m^2.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Signed enclosed volume (divergence theorem), m^3: positive when closed
    /// and outward-facing.
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.volume_share(t)).sum()
    }

    /// Triangle `t`'s share of [`TriSurface::signed_volume`] (the signed
    /// volume of the tetrahedron it spans with the origin), m^3.
    pub fn volume_share(&self, t: usize) -> f64 {
        let [a, b, c] = self.corners(t);
        a.dot(b.cross(c)) / 6.0
    }

    /// Axis-aligned bounds `(min, max)`; `None` when there are no vertices.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.vertices.first()?;
        Some(
            self.vertices
                .iter()
                .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v))),
        )
    }

    /// Applies a rigid or affine map to every vertex. A map with negative
    /// determinant (a mirror) also reverses triangle order to keep normals outward.
    pub fn transform(&mut self, map: &DAffine3) {
        for v in &mut self.vertices {
            *v = map.transform_point3(*v);
        }
        if map.matrix3.determinant() < 0.0 {
            self.turn_inside_out();
        }
    }

    /// Reverses every triangle's winding, so each faces the other way.
    pub fn turn_inside_out(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Checks that every coordinate is finite, every edge borders exactly two
    /// triangles traversing it in opposite directions, and the volume is
    /// positive (closed, consistently oriented, outward-facing).
    pub fn check_closed(&self) -> Result<(), SurfaceDefect> {
        self.check_finite_and_indexed()?;
        // Directed edge -> triangle that traverses it.
        let mut directed: HashMap<(u32, u32), usize> =
            HashMap::with_capacity(self.triangles.len() * 3);
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if directed.insert((a, b), t).is_some() {
                    let undirected = self.edge_use_count(a, b);
                    return Err(if undirected > 2 {
                        SurfaceDefect::NonManifoldEdge {
                            a,
                            b,
                            count: undirected,
                        }
                    } else {
                        SurfaceDefect::InconsistentOrientation { a, b }
                    });
                }
            }
        }
        for (&(a, b), &t) in &directed {
            if !directed.contains_key(&(b, a)) {
                return Err(SurfaceDefect::OpenEdge { a, b, triangle: t });
            }
        }
        if self.signed_volume() <= 0.0 {
            return Err(SurfaceDefect::InwardFacing);
        }
        Ok(())
    }

    /// Checks coordinates and indices only (for surfaces that may be open).
    pub fn check_finite_and_indexed(&self) -> Result<(), SurfaceDefect> {
        if self.triangles.is_empty() {
            return Err(SurfaceDefect::Empty);
        }
        if let Some(vertex) = self.vertices.iter().position(|v| !v.is_finite()) {
            return Err(SurfaceDefect::NonFiniteVertex { vertex });
        }
        let count = self.vertices.len();
        for (triangle, tri) in self.triangles.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= count) {
                return Err(SurfaceDefect::VertexOutOfRange {
                    triangle,
                    vertex,
                    count,
                });
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(SurfaceDefect::DegenerateTriangle { triangle });
            }
        }
        Ok(())
    }

    fn edge_use_count(&self, a: u32, b: u32) -> usize {
        self.triangles
            .iter()
            .filter(|tri| {
                (0..3).any(|k| {
                    let (p, q) = (tri[k], tri[(k + 1) % 3]);
                    (p, q) == (a, b) || (p, q) == (b, a)
                })
            })
            .count()
    }

    /// Appends another surface (its indices shifted), e.g. to merge bones.
    pub fn append(&mut self, other: &TriSurface) {
        let offset = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }
}

/// Closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriSurface {
        TriSurface::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
    }

    #[test]
    fn closed_tetrahedron_passes_and_has_its_volume() {
        let s = tetrahedron();
        s.check_closed().unwrap();
        assert!((s.signed_volume() - 1.0 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn defects_are_named() {
        let mut open = tetrahedron();
        open.triangles.pop();
        assert!(matches!(
            open.check_closed(),
            Err(SurfaceDefect::OpenEdge { .. })
        ));

        let mut inward = tetrahedron();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        assert_eq!(inward.check_closed(), Err(SurfaceDefect::InwardFacing));

        let mut flipped = tetrahedron();
        flipped.triangles[3].swap(1, 2);
        assert!(matches!(
            flipped.check_closed(),
            Err(SurfaceDefect::InconsistentOrientation { .. })
        ));

        let mut nan = tetrahedron();
        nan.vertices[2].x = f64::NAN;
        assert_eq!(
            nan.check_closed(),
            Err(SurfaceDefect::NonFiniteVertex { vertex: 2 })
        );
    }

    #[test]
    fn mirroring_keeps_the_surface_outward() {
        let mut s = tetrahedron();
        s.transform(&DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        s.check_closed().unwrap();
    }
}
