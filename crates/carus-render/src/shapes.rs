//! Simple marker shapes for pictures: spheres for landmarks, tubes for
//! curves such as the pelvic axis, filled polygons for planes, arrows for
//! forces.

use glam::Vec3;

use crate::mesh::RenderMesh;

/// Rings (pole to pole) and segments (around) of a marker sphere: smooth at
/// report sizes, a few hundred triangles.
const SPHERE_RINGS: u32 = 16;
const SPHERE_SEGMENTS: u32 = 24;

/// Sides of a tube's cross-section.
const TUBE_SIDES: u32 = 12;

/// An arrow's head: its radius and its longest length, in shaft radii.
const ARROW_HEAD_RADIUS: f32 = 2.5;
const ARROW_HEAD_LENGTH: f32 = 6.0;

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

    /// An arrow from `tail` to `tip` with a shaft of `radius` and a cone for
    /// its head (at most half its length), closed at the cone's base. Every
    /// arrow has the same vertices and triangles in number, so one uploaded
    /// arrow can be rewritten in place as another. A zero-length arrow has
    /// no vertices.
    pub fn arrow(name: impl Into<String>, tail: [f32; 3], tip: [f32; 3], radius: f32, rgb: [f32; 3]) -> Self {
        let (tail, tip) = (Vec3::from(tail), Vec3::from(tip));
        let Some(along) = (tip - tail).try_normalize() else {
            return RenderMesh::new(name, Vec::new(), Vec::new(), rgb);
        };
        let head_length = (ARROW_HEAD_LENGTH * radius).min(0.5 * tail.distance(tip));
        let head_radius = ARROW_HEAD_RADIUS * radius;
        let neck = tip - head_length * along;
        let side = along.any_orthonormal_vector();
        let other = along.cross(side);
        let radial = |k: u32| {
            let angle = std::f32::consts::TAU * k as f32 / TUBE_SIDES as f32;
            side * angle.cos() + other * angle.sin()
        };
        // The cone's surface normal leans forwards by its half-angle.
        let slant = |k: u32| (head_length * radial(k) + head_radius * along).normalize();
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut ring = |centre: Vec3, r: f32, normal: &dyn Fn(u32) -> Vec3| {
            for k in 0..TUBE_SIDES {
                positions.push((centre + r * radial(k)).to_array());
                normals.push(normal(k).to_array());
            }
        };
        ring(tail, radius, &radial);
        ring(neck, radius, &radial);
        ring(neck, head_radius, &slant);
        ring(tip, 0.0, &slant);
        ring(neck, head_radius, &|_| -along);
        positions.push(neck.to_array());
        normals.push((-along).to_array());
        let n = TUBE_SIDES;
        let centre_of_base = 5 * n;
        let mut indices = Vec::new();
        for k in 0..n {
            let k1 = (k + 1) % n;
            // Shaft, then cone (each side to its own apex vertex), then the base.
            indices.extend([k, k1, n + k1, k, n + k1, n + k]);
            indices.extend([2 * n + k, 2 * n + k1, 3 * n + k]);
            indices.extend([centre_of_base, 4 * n + k1, 4 * n + k]);
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
    fn arrow_runs_from_tail_to_tip_and_faces_outwards() {
        let (tail, tip) = (Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.1, 0.2, 1.3));
        let mesh = RenderMesh::arrow("force", tail.to_array(), tip.to_array(), 0.02, [1.0, 0.0, 0.0]);
        mesh.validate(0).unwrap();
        let along = |p: &[f32; 3]| (Vec3::from(*p) - tail).dot(Vec3::Z);
        let reach = mesh.positions.iter().map(along).fold(f32::MIN, f32::max);
        let start = mesh.positions.iter().map(along).fold(f32::MAX, f32::min);
        assert!((reach - 1.0).abs() < 1e-6 && start.abs() < 1e-6, "{start} .. {reach}");
        // Nothing strays wider than the head.
        let widest = mesh.positions.iter().map(|p| Vec3::from(*p).truncate().distance(tail.truncate())).fold(0.0, f32::max);
        assert!((widest - ARROW_HEAD_RADIUS * 0.02).abs() < 1e-6, "{widest}");
        // Every triangle faces away from the shaft's axis, or backwards at the head's base.
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| Vec3::from(mesh.positions[i as usize]));
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            let axis_point = tail + Vec3::Z * (centroid - tail).z;
            let outwards = match tri.contains(&(5 * TUBE_SIDES)) {
                true => -Vec3::Z,
                false => centroid - axis_point,
            };
            assert!(n.dot(outwards) > 0.0, "{tri:?}");
        }
        // A short arrow has as many vertices and triangles as a long one,
        // its head at most half of it.
        let short = RenderMesh::arrow("force", [0.0; 3], [0.01, 0.0, 0.0], 0.02, [1.0; 3]);
        assert_eq!((short.positions.len(), short.indices.len()), (mesh.positions.len(), mesh.indices.len()));
        let neck = Vec3::from(short.positions[TUBE_SIDES as usize]);
        assert!((neck.x - 0.005).abs() < 1e-7, "{neck}");
        assert!(RenderMesh::arrow("none", [1.0; 3], [1.0; 3], 0.02, [1.0; 3]).positions.is_empty());
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
