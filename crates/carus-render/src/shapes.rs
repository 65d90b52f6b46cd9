//! Simple marker shapes for pictures: spheres for landmarks, tubes for
//! curves such as the pelvic axis, filled polygons for planes.

use glam::Vec3;

use crate::mesh::RenderMesh;

/// Rings (pole to pole) and segments (around) of a marker sphere: smooth at
/// report sizes, a few hundred triangles.
const SPHERE_RINGS: u32 = 16;
const SPHERE_SEGMENTS: u32 = 24;

/// Sides of a tube's cross-section.
const TUBE_SIDES: u32 = 12;

impl RenderMesh {
    /// A sphere (landmark marker), counter-clockwise from outside.
    pub fn sphere(name: impl Into<String>, centre: [f32; 3], radius: f32, rgb: [f32; 3]) -> Self {
        let c = Vec3::from(centre);
        let mut positions = Vec::new();
        for ring in 0..=SPHERE_RINGS {
            let polar = std::f32::consts::PI * ring as f32 / SPHERE_RINGS as f32;
            for segment in 0..=SPHERE_SEGMENTS {
                let azimuth = std::f32::consts::TAU * segment as f32 / SPHERE_SEGMENTS as f32;
                let dir = Vec3::new(
                    polar.sin() * azimuth.cos(),
                    polar.sin() * azimuth.sin(),
                    polar.cos(),
                );
                positions.push((c + radius * dir).to_array());
            }
        }
        let row = SPHERE_SEGMENTS + 1;
        let mut indices = Vec::new();
        for ring in 0..SPHERE_RINGS {
            for segment in 0..SPHERE_SEGMENTS {
                let a = ring * row + segment;
                let b = a + row;
                indices.extend([a, b, a + 1, a + 1, b, b + 1]);
            }
        }
        // Exact normals: the seam and poles repeat vertices, which computed
        // normals would shade as creases.
        let normals = positions
            .iter()
            .map(|p| {
                (Vec3::from(*p) - c)
                    .try_normalize()
                    .unwrap_or(Vec3::Z)
                    .to_array()
            })
            .collect();
        RenderMesh::new(name, positions, indices, rgb).with_normals(normals)
    }

    /// A tube of `radius` along a polyline (open ends), for curves such as
    /// the pelvic axis. Repeated consecutive points are skipped.
    pub fn tube(name: impl Into<String>, points: &[[f32; 3]], radius: f32, rgb: [f32; 3]) -> Self {
        let mut path: Vec<Vec3> = Vec::with_capacity(points.len());
        for p in points.iter().map(|p| Vec3::from(*p)) {
            if path.last().is_none_or(|last| last.distance(p) > 0.0) {
                path.push(p);
            }
        }
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        if path.len() >= 2 {
            // The cross-section turns with the curve by parallel transport,
            // so the tube does not twist.
            let tangent = |i: usize| {
                let (a, b) = (path[i.saturating_sub(1)], path[(i + 1).min(path.len() - 1)]);
                (b - a).normalize()
            };
            let mut side = tangent(0).any_orthonormal_vector();
            for (i, centre) in path.iter().enumerate() {
                let t = tangent(i);
                side = (side - t * side.dot(t))
                    .try_normalize()
                    .unwrap_or_else(|| t.any_orthonormal_vector());
                let other = t.cross(side);
                for k in 0..TUBE_SIDES {
                    let angle = std::f32::consts::TAU * k as f32 / TUBE_SIDES as f32;
                    let n = side * angle.cos() + other * angle.sin();
                    positions.push((*centre + radius * n).to_array());
                    normals.push(n.to_array());
                }
            }
        }
        let mut indices = Vec::new();
        for i in 0..path.len().saturating_sub(1) as u32 {
            for k in 0..TUBE_SIDES {
                let k1 = (k + 1) % TUBE_SIDES;
                let (a, b) = (i * TUBE_SIDES, (i + 1) * TUBE_SIDES);
                indices.extend([a + k, a + k1, b + k1, a + k, b + k1, b + k]);
            }
        }
        RenderMesh::new(name, positions, indices, rgb).with_normals(normals)
    }

    /// A filled polygon (fan from its centroid), for a plane's outline such
    /// as the pelvic inlet; faces the side from which the outline runs
    /// counter-clockwise.
    pub fn polygon(name: impl Into<String>, outline: &[[f32; 3]], rgb: [f32; 3]) -> Self {
        let count = outline.len() as u32;
        let centroid = outline.iter().map(|p| Vec3::from(*p)).sum::<Vec3>() / count.max(1) as f32;
        let mut positions = vec![centroid.to_array()];
        positions.extend_from_slice(outline);
        let indices = (0..count)
            .flat_map(|k| [0, 1 + k, 1 + (k + 1) % count])
            .collect();
        RenderMesh::new(name, positions, indices, rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distance_from(p: [f32; 3], c: Vec3) -> f32 {
        Vec3::from(p).distance(c)
    }

    #[test]
    fn sphere_vertices_lie_on_it_and_its_triangles_face_outwards() {
        let c = Vec3::new(1.0, -2.0, 0.5);
        let mesh = RenderMesh::sphere("landmark", c.to_array(), 0.3, [1.0, 0.0, 0.0]);
        mesh.validate(0).unwrap();
        assert!(mesh
            .positions
            .iter()
            .all(|p| (distance_from(*p, c) - 0.3).abs() < 1e-5));
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, d] =
                [tri[0], tri[1], tri[2]].map(|i| Vec3::from(mesh.positions[i as usize]));
            let n = (b - a).cross(d - a);
            // Degenerate triangles at the poles have no direction.
            if n.length() > 1e-9 {
                assert!(n.dot((a + b + d) / 3.0 - c) > 0.0);
            }
        }
    }

    #[test]
    fn tube_keeps_its_radius_along_a_bent_path() {
        let path = [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 2.0],
        ];
        let mesh = RenderMesh::tube("pelvic axis", &path, 0.05, [0.2, 0.4, 1.0]);
        mesh.validate(0).unwrap();
        // Three distinct points, one ring of vertices each, two segments.
        assert_eq!(mesh.positions.len(), 3 * TUBE_SIDES as usize);
        assert_eq!(mesh.indices.len(), 2 * TUBE_SIDES as usize * 6);
        for (i, centre) in [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 2.0]]
            .iter()
            .enumerate()
        {
            let ring = &mesh.positions[i * TUBE_SIDES as usize..(i + 1) * TUBE_SIDES as usize];
            assert!(ring
                .iter()
                .all(|p| (distance_from(*p, Vec3::from(*centre)) - 0.05).abs() < 1e-5));
        }
    }

    #[test]
    fn tube_of_one_point_is_refused_by_validation() {
        let mesh = RenderMesh::tube("dot", &[[0.0; 3], [0.0; 3]], 0.1, [1.0; 3]);
        assert!(mesh
            .validate(2)
            .unwrap_err()
            .to_string()
            .contains("no vertices"));
    }

    #[test]
    fn polygon_fans_from_its_centroid() {
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let mesh = RenderMesh::polygon("inlet plane", &square, [0.5; 3]);
        mesh.validate(0).unwrap();
        assert_eq!(mesh.positions[0], [0.5, 0.5, 0.0]);
        assert_eq!(mesh.indices.len(), 12);
        assert!(mesh.vertex_normals().iter().all(|n| *n == [0.0, 0.0, 1.0]));
    }
}
