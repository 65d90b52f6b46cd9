//! Contact samples of a rigid fetal surface: points in the body frame, each
//! with the surface area it stands for. The penalty law scales each point's
//! stiffness by that area, so the contact pressure, and with it the total
//! force at a given penetration, does not depend on how finely the surface
//! is sampled.

use std::collections::HashMap;

use glam::DVec3;

use crate::collider::validate_surface;
use crate::error::{check_non_negative, ContactError};

/// Sample points of a body surface in its own frame (structure of arrays).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceSamples {
    pub points: Vec<DVec3>,
    /// Tributary area of each point, m^2; they sum to the surface area.
    pub areas: Vec<f64>,
}

impl SurfaceSamples {
    /// One sample per vertex, each carrying a third of the area of the
    /// triangles round it.
    pub fn from_vertices(
        what: &'static str,
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<Self, ContactError> {
        validate_surface(what, vertices, triangles)?;
        let mut areas = vec![0.0; vertices.len()];
        for t in triangles {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let third = (b - a).cross(c - a).length() / 6.0;
            for &i in t {
                areas[i as usize] += third;
            }
        }
        Ok(SurfaceSamples { points: vertices.to_vec(), areas })
    }

    /// Samples about `spacing_m` apart: triangles larger than the spacing are
    /// subdivided (so coarse meshes get enough points), then the candidates
    /// are clustered on a grid of that cell size (so dense meshes are
    /// decimated), keeping per cell the first candidate (vertices come first)
    /// and the summed area. Deterministic: the output order follows the input.
    pub fn with_spacing(
        what: &'static str,
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
        spacing_m: f64,
    ) -> Result<Self, ContactError> {
        check_non_negative("sample_spacing_m", spacing_m, false)?;
        validate_surface(what, vertices, triangles)?;
        let mut candidates: Vec<DVec3> = vertices.to_vec();
        let mut areas = vec![0.0; vertices.len()];
        for t in triangles {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let n = (longest / spacing_m).ceil().max(1.0) as usize;
            // Barycentric grid (i, j), i + j <= n, row j holding n + 1 - j
            // points; its corners are the triangle's own vertices.
            let slot = |i: usize, j: usize| j * (n + 1) - j * j.saturating_sub(1) / 2 + i;
            let mut grid = vec![0usize; (n + 1) * (n + 2) / 2];
            for j in 0..=n {
                for i in 0..=(n - j) {
                    grid[slot(i, j)] = match (i, j) {
                        (0, 0) => t[0] as usize,
                        (i, 0) if i == n => t[1] as usize,
                        (0, j) if j == n => t[2] as usize,
                        _ => {
                            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                            candidates.push(a + (b - a) * u + (c - a) * v);
                            areas.push(0.0);
                            candidates.len() - 1
                        }
                    };
                }
            }
            let index_of = |i: usize, j: usize| grid[slot(i, j)];
            let share = (b - a).cross(c - a).length() / (6.0 * (n * n) as f64);
            for j in 0..n {
                for i in 0..(n - j) {
                    // Upward sub-triangle (i,j),(i+1,j),(i,j+1) and, where it
                    // exists, the downward one (i+1,j),(i+1,j+1),(i,j+1).
                    for p in [index_of(i, j), index_of(i + 1, j), index_of(i, j + 1)] {
                        areas[p] += share;
                    }
                    if i + j + 1 < n {
                        for p in [index_of(i + 1, j), index_of(i + 1, j + 1), index_of(i, j + 1)] {
                            areas[p] += share;
                        }
                    }
                }
            }
        }

        let mut cell_of: HashMap<[i64; 3], usize> = HashMap::new();
        let mut samples = SurfaceSamples { points: Vec::new(), areas: Vec::new() };
        for (p, area) in candidates.into_iter().zip(areas) {
            let key = (p / spacing_m).floor().as_i64vec3().to_array();
            match cell_of.get(&key) {
                Some(&k) => samples.areas[k] += area,
                None => {
                    cell_of.insert(key, samples.points.len());
                    samples.points.push(p);
                    samples.areas.push(area);
                }
            }
        }
        Ok(samples)
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    pub fn total_area(&self) -> f64 {
        self.areas.iter().sum()
    }

    /// The samples that `keep` accepts (given each point), in their order.
    pub fn filtered(&self, keep: impl Fn(DVec3) -> bool) -> SurfaceSamples {
        let (points, areas) = self
            .points
            .iter()
            .zip(&self.areas)
            .filter(|(p, _)| keep(**p))
            .map(|(p, a)| (*p, *a))
            .unzip();
        SurfaceSamples { points, areas }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collider::tests::uv_sphere;

    /// A filtered set keeps the accepted points with their areas, in order.
    #[test]
    fn filtering_keeps_points_with_their_areas_in_order() {
        let (v, t) = uv_sphere(1.0, 6, 12);
        let all = SurfaceSamples::from_vertices("sphere", &v, &t).unwrap();
        let upper = all.filtered(|p| p.z > 0.0);
        let expected: Vec<(DVec3, f64)> =
            all.points.iter().zip(&all.areas).filter(|(p, _)| p.z > 0.0).map(|(p, a)| (*p, *a)).collect();
        assert!(!upper.is_empty() && upper.len() < all.len());
        assert_eq!(upper.points.iter().copied().zip(upper.areas.iter().copied()).collect::<Vec<_>>(), expected);
    }

    fn surface_area(v: &[DVec3], t: &[[u32; 3]]) -> f64 {
        t.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| v[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn areas_sum_to_the_surface_area() {
        let (v, t) = uv_sphere(0.05, 10, 16);
        let exact = surface_area(&v, &t);
        let by_vertex = SurfaceSamples::from_vertices("sphere", &v, &t).unwrap();
        assert!((by_vertex.total_area() - exact).abs() < 1e-15);
        for spacing in [0.002, 0.01, 0.05] {
            let s = SurfaceSamples::with_spacing("sphere", &v, &t, spacing).unwrap();
            assert!((s.total_area() - exact).abs() < 1e-14, "spacing {spacing}");
        }
    }

    #[test]
    fn spacing_controls_the_sample_count() {
        // Two triangles of 1 m^2 (a unit square): about (1/s)^2 samples.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let t = vec![[0, 1, 2], [0, 2, 3]];
        for spacing in [0.1, 0.05] {
            let s = SurfaceSamples::with_spacing("square", &v, &t, spacing).unwrap();
            let expected = (1.0 / spacing + 1.0).powi(2);
            let ratio = s.len() as f64 / expected;
            assert!((0.9..=1.1).contains(&ratio), "spacing {spacing}: {} samples", s.len());
            // Every sample lies on the square.
            assert!(s.points.iter().all(|p| p.z == 0.0 && p.x >= 0.0 && p.x <= 1.0 && p.y >= 0.0 && p.y <= 1.0));
        }
        // A dense sphere decimated to 2 cm keeps far fewer points than vertices.
        let (v, t) = uv_sphere(0.05, 40, 80);
        let s = SurfaceSamples::with_spacing("sphere", &v, &t, 0.02).unwrap();
        assert!(s.len() < v.len() / 10, "{} of {}", s.len(), v.len());
    }

    #[test]
    fn bad_spacing_is_refused() {
        let (v, t) = uv_sphere(0.05, 4, 6);
        let err = SurfaceSamples::with_spacing("sphere", &v, &t, 0.0).unwrap_err();
        assert!(matches!(err, ContactError::InvalidParameter { name: "sample_spacing_m", .. }));
    }
}
