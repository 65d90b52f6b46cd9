//! A triangle surface prepared for exact signed closest-point queries: the
//! bony pelvis (static, in the pelvis frame) or a fetal surface (in its body
//! frame, so its BVH is built once and never refitted).
//!
//! Broad phase: parry's BVH over the triangles, queried with a bounded search
//! distance so that far branches are pruned at once. Narrow phase: the exact
//! closest point on the nearest triangle (parry), signed with the
//! angle-weighted pseudo-normal of the feature it lands on (face, edge or
//! vertex; Baerentzen and Aanaes 2005), which is exact for closed,
//! consistently oriented surfaces and still well defined on open ones.

use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::query::{PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh, TrianglePointLocation};

use crate::error::ContactError;

/// The nearest point of a surface to a query point, with its sign.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Closest point on the surface.
    pub point: DVec3,
    /// Unit outward normal there: the direction that leaves the solid the
    /// surface bounds (from an inside query point towards the surface point).
    pub normal: DVec3,
    /// Distance to the surface, negative when the query point is inside.
    pub signed_distance: f64,
    /// Index of the triangle that holds `point`.
    pub triangle: u32,
}

/// Triangle surface with its BVH and pseudo-normals. Constant once built.
pub struct TriangleCollider {
    mesh: TriMesh,
    face_normals: Vec<DVec3>,
    /// Per triangle, the pseudo-normals of its edges in parry's order
    /// (0: AB, 1: BC, 2: AC): the sum of the unit normals of the two faces.
    edge_normals: Vec<[DVec3; 3]>,
    /// Angle-weighted sum of the unit normals of the faces round each vertex.
    vertex_normals: Vec<DVec3>,
}

impl std::fmt::Debug for TriangleCollider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TriangleCollider")
            .field("vertices", &self.mesh.vertices().len())
            .field("triangles", &self.face_normals.len())
            .finish()
    }
}

impl TriangleCollider {
    /// Builds the collider. `what` names the surface in errors ("pelvis",
    /// "fetal head"). Triangles are counter-clockwise seen from outside.
    pub fn new(
        what: &'static str,
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<Self, ContactError> {
        validate_surface(what, vertices, triangles)?;
        let corner = |t: &[u32; 3], i: usize| vertices[t[i] as usize];

        let face_normals: Vec<DVec3> = triangles
            .iter()
            .map(|t| {
                (corner(t, 1) - corner(t, 0))
                    .cross(corner(t, 2) - corner(t, 0))
                    .normalize()
            })
            .collect();

        let mut vertex_normals = vec![DVec3::ZERO; vertices.len()];
        for (t, n) in triangles.iter().zip(&face_normals) {
            for i in 0..3 {
                let p = corner(t, i);
                let e1 = corner(t, (i + 1) % 3) - p;
                let e2 = corner(t, (i + 2) % 3) - p;
                vertex_normals[t[i] as usize] += e1.angle_between(e2) * *n;
            }
        }

        // Edge pseudo-normals: sum the face normals of all triangles sharing
        // the undirected edge (one on an open boundary).
        let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
        let mut edge_sum: std::collections::HashMap<(u32, u32), DVec3> =
            std::collections::HashMap::with_capacity(triangles.len() * 2);
        const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (0, 2)];
        for (t, n) in triangles.iter().zip(&face_normals) {
            for (i, j) in EDGES {
                *edge_sum.entry(key(t[i], t[j])).or_insert(DVec3::ZERO) += *n;
            }
        }
        let edge_normals = triangles
            .iter()
            .map(|t| EDGES.map(|(i, j)| edge_sum[&key(t[i], t[j])]))
            .collect();

        let mesh = TriMesh::new(vertices.to_vec(), triangles.to_vec())
            .map_err(|_| ContactError::EmptySurface { what })?;
        Ok(TriangleCollider {
            mesh,
            face_normals,
            edge_normals,
            vertex_normals,
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.face_normals.len()
    }

    /// Corner positions of triangle `t`.
    pub fn corners(&self, t: u32) -> [DVec3; 3] {
        let v = self.mesh.vertices();
        self.mesh.indices()[t as usize].map(|i| v[i as usize])
    }

    /// Triangles whose bounding boxes meet the box `(min, max)` (BVH query),
    /// in ascending order.
    pub fn triangles_near(&self, min: DVec3, max: DVec3) -> Vec<u32> {
        let query = Aabb::new(min, max);
        let mut found: Vec<u32> = self.mesh.bvh().intersect_aabb(&query).collect();
        found.sort_unstable();
        found
    }

    /// The nearest surface point within `max_distance` of `point`, signed;
    /// `None` when the surface is farther than that (which prunes the BVH).
    pub fn closest_point(&self, point: DVec3, max_distance: f64) -> Option<SurfacePoint> {
        let (projection, (triangle, location)) = self
            .mesh
            .project_local_point_and_get_location_with_max_dist(point, false, max_distance)?;
        let t = triangle as usize;
        let pseudo_normal = match location {
            TrianglePointLocation::OnVertex(i) => {
                self.vertex_normals[self.mesh.indices()[t][i as usize] as usize]
            }
            TrianglePointLocation::OnEdge(i, _) => self.edge_normals[t][i as usize],
            TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => {
                self.face_normals[t]
            }
        };
        let offset = point - projection.point;
        let distance = offset.length();
        let inside = offset.dot(pseudo_normal) < 0.0;
        // The outward direction of the shortest way out; on the surface
        // itself (distance ~ 0) the pseudo-normal is the only direction left,
        // or the face's where a folded surface's normals cancel.
        let scale = 1e-12 * (1.0 + projection.point.abs().max_element());
        let normal = if distance > scale {
            if inside {
                -offset / distance
            } else {
                offset / distance
            }
        } else {
            pseudo_normal.try_normalize().unwrap_or(self.face_normals[t])
        };
        Some(SurfacePoint {
            point: projection.point,
            normal,
            signed_distance: if inside { -distance } else { distance },
            triangle,
        })
    }

    /// The first surface crossing from `point` along the unit `direction`
    /// within `max_distance`, as a point inside the surface that far from
    /// it, with `direction` as its way out: for a point that came into a
    /// thin wall from `direction`'s side and has passed its middle, where
    /// the nearest surface is the far face ([`closest_point`] would push it
    /// on through).
    ///
    /// [`closest_point`]: TriangleCollider::closest_point
    pub fn crossing_along(&self, point: DVec3, direction: DVec3, max_distance: f64) -> Option<SurfacePoint> {
        let time = self.mesh.cast_local_ray(&Ray::new(point, direction), max_distance, false)?;
        let at = point + time * direction;
        let on = self.closest_point(at, 1e-9 * (1.0 + at.abs().max_element()))?;
        Some(SurfacePoint { point: at, normal: direction, signed_distance: -time, triangle: on.triangle })
    }

    /// Where the line through `point` along `direction` enters the surface:
    /// its first crossing met coming from far back along `-direction`.
    /// This is where a force along `direction` acting on that line meets
    /// the body it pushes. `None` when the line misses the surface.
    pub fn entry_point(&self, point: DVec3, direction: DVec3) -> Option<DVec3> {
        let along = direction.try_normalize()?;
        let bounds = self.mesh.local_aabb();
        let reach = point.distance(bounds.center()) + bounds.half_extents().length() + 1.0;
        let start = point - reach * along;
        let time = self.mesh.cast_local_ray(&Ray::new(start, along), 2.0 * reach, false)?;
        Some(start + time * along)
    }
}

/// Checks indices, finiteness and non-zero triangle areas.
pub(crate) fn validate_surface(
    what: &'static str,
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
) -> Result<(), ContactError> {
    if triangles.is_empty() {
        return Err(ContactError::EmptySurface { what });
    }
    if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
        return Err(ContactError::NonFiniteVertex { what, vertex });
    }
    for (triangle, t) in triangles.iter().enumerate() {
        if let Some(&vertex) = t.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(ContactError::VertexOutOfRange {
                what,
                triangle,
                vertex,
                count: vertices.len(),
            });
        }
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let twice_area = (b - a).cross(c - a).length();
        let extent = (b - a).length().max((c - a).length());
        if twice_area.is_nan() || twice_area <= 1e-14 * extent * extent {
            return Err(ContactError::DegenerateTriangle { what, triangle });
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Closed UV sphere of radius `r`, `rings` x `segments`, poles on the z
    /// axis, counter-clockwise seen from outside.
    pub(crate) fn uv_sphere(r: f64, rings: u32, segments: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut v = vec![DVec3::new(0.0, 0.0, -r)];
        for i in 1..rings {
            let polar = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..segments {
                let az = 2.0 * std::f64::consts::PI * j as f64 / segments as f64;
                v.push(
                    r * DVec3::new(polar.sin() * az.cos(), polar.sin() * az.sin(), -polar.cos()),
                );
            }
        }
        v.push(DVec3::new(0.0, 0.0, r));
        let top = v.len() as u32 - 1;
        let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let mut t = Vec::new();
        for j in 0..segments {
            t.push([0, ring(1, j + 1), ring(1, j)]);
            t.push([top, ring(rings - 1, j), ring(rings - 1, j + 1)]);
        }
        for i in 1..rings - 1 {
            for j in 0..segments {
                t.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
                t.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
            }
        }
        (v, t)
    }

    /// Closest point on a triangle: the brute-force reference, independent of parry.
    pub(crate) fn closest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> DVec3 {
        carus_anatomy::surface::closest_point_on_triangle(p, a, b, c)
    }

    /// Random triangle soup in the unit cube (non-degenerate triangles).
    pub(crate) fn random_mesh() -> impl Strategy<Value = (Vec<DVec3>, Vec<[u32; 3]>)> {
        prop::collection::vec(prop::array::uniform9(-1.0f64..1.0), 1..40).prop_filter_map(
            "degenerate triangle",
            |tris| {
                let mut v = Vec::new();
                let mut t = Vec::new();
                for c in tris {
                    let [a, b, d] = [0, 3, 6].map(|k| DVec3::new(c[k], c[k + 1], c[k + 2]));
                    if (b - a).cross(d - a).length() < 1e-3 {
                        return None;
                    }
                    let base = v.len() as u32;
                    v.extend([a, b, d]);
                    t.push([base, base + 1, base + 2]);
                }
                Some((v, t))
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// C3: point-to-mesh distance through the BVH equals brute force
        /// over every triangle.
        #[test]
        fn c3_distance_matches_brute_force(
            (v, t) in random_mesh(),
            queries in prop::collection::vec(prop::array::uniform3(-2.0f64..2.0), 1..20),
        ) {
            let collider = TriangleCollider::new("random", &v, &t).unwrap();
            for q in queries {
                let p = DVec3::from_array(q);
                let brute = t.iter()
                    .map(|tri| (p - closest_on_triangle(p, tri.map(|i| v[i as usize]))).length())
                    .fold(f64::INFINITY, f64::min);
                let hit = collider.closest_point(p, f64::MAX).unwrap();
                prop_assert!((hit.signed_distance.abs() - brute).abs() <= 1e-12 * (1.0 + brute),
                    "bvh {} brute {}", hit.signed_distance.abs(), brute);
                // A bounded search finds it exactly when it lies within the bound.
                prop_assert_eq!(collider.closest_point(p, brute * 0.999).is_some(), false);
                prop_assert!(collider.closest_point(p, brute * 1.001 + 1e-12).is_some());
            }
        }

        /// The sign is the inside test of a closed convex surface: inside
        /// exactly when behind every face plane.
        #[test]
        fn sign_matches_convex_inside_test(q in prop::array::uniform3(-0.15f64..0.15)) {
            let (v, t) = uv_sphere(0.1, 8, 12);
            let collider = TriangleCollider::new("sphere", &v, &t).unwrap();
            let p = DVec3::from_array(q);
            let behind_all = t.iter().all(|tri| {
                let [a, b, c] = tri.map(|i| v[i as usize]);
                (p - a).dot((b - a).cross(c - a)) < 0.0
            });
            let hit = collider.closest_point(p, f64::MAX).unwrap();
            if hit.signed_distance.abs() > 1e-9 {
                prop_assert_eq!(hit.signed_distance < 0.0, behind_all);
            }
            // The outward normal leads from an inside point to the surface.
            if hit.signed_distance < -1e-9 {
                prop_assert!((p + hit.normal * -hit.signed_distance - hit.point).length() < 1e-9);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// A line through a sphere enters it where the exact line-sphere
        /// crossing on its back side lies (to the faceting's depth); a line
        /// that passes it by misses it.
        #[test]
        fn a_line_enters_a_sphere_on_its_back_side(
            q in prop::array::uniform3(-0.05f64..0.05),
            d in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let (v, t) = uv_sphere(0.1, 24, 32);
            let collider = TriangleCollider::new("sphere", &v, &t).unwrap();
            let (p, along) = (DVec3::from_array(q), DVec3::from_array(d));
            prop_assume!(along.length() > 0.1);
            let u = along.normalize();
            // |p - s u| = r with s the smaller root.
            let (b, c) = (p.dot(u), p.length_squared() - 0.01);
            let exact = p - (b + (b * b - c).sqrt()) * u;
            let entry = collider.entry_point(p, along).unwrap();
            prop_assert!(entry.distance(exact) < 2e-3, "{} against {}", entry, exact);
            let aside = p + 0.2 * u.any_orthonormal_vector();
            prop_assert!(collider.entry_point(aside, along).is_none());
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Random (often sliver) tetrahedra: sharp edges and corners, where
        /// only the right edge or vertex pseudo-normal gives the right sign.
        #[test]
        fn sign_is_exact_near_sharp_edges_and_corners(c in prop::array::uniform12(-1.0f64..1.0),
                                                       q in prop::array::uniform3(-1.5f64..1.5)) {
            let mut v: Vec<DVec3> = [0, 3, 6, 9].map(|k| DVec3::new(c[k], c[k + 1], c[k + 2])).to_vec();
            let volume = (v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0]));
            prop_assume!(volume.abs() > 1e-3);
            if volume < 0.0 {
                v.swap(2, 3);
            }
            let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
            let collider = TriangleCollider::new("tetrahedron", &v, &t).unwrap();
            let p = DVec3::from_array(q);
            let hit = collider.closest_point(p, f64::MAX).unwrap();
            prop_assume!(hit.signed_distance.abs() > 1e-9);
            let inside = t.iter().all(|tri| {
                let [a, b, c] = tri.map(|i| v[i as usize]);
                (p - a).dot((b - a).cross(c - a)) < 0.0
            });
            prop_assert_eq!(hit.signed_distance < 0.0, inside);
        }
    }

    /// Closed torus (major radius `big`, minor `small`) about z, outward normals.
    fn torus(big: f64, small: f64, around: u32, across: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        use std::f64::consts::TAU;
        let mut v = Vec::new();
        for i in 0..around {
            let u = TAU * i as f64 / around as f64;
            for j in 0..across {
                let w = TAU * j as f64 / across as f64;
                let r = big + small * w.cos();
                v.push(DVec3::new(r * u.cos(), r * u.sin(), small * w.sin()));
            }
        }
        let id = |i: u32, j: u32| (i % around) * across + j % across;
        let mut t = Vec::new();
        for i in 0..around {
            for j in 0..across {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (v, t)
    }

    /// Generalised winding number (solid angles, van Oosterom and Strackee
    /// 1983): 1 inside a closed outward surface, 0 outside.
    fn winding_number(p: DVec3, v: &[DVec3], t: &[[u32; 3]]) -> f64 {
        t.iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|i| v[i as usize] - p);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let num = a.dot(b.cross(c));
                let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
                2.0 * num.atan2(den)
            })
            .sum::<f64>()
            / (4.0 * std::f64::consts::PI)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// The pseudo-normal sign on a non-convex closed surface (a torus,
        /// like the bony ring round the birth canal) agrees with the winding
        /// number, near and far, inside the hole and in the tube.
        #[test]
        fn sign_matches_winding_number_on_a_torus(q in prop::array::uniform3(-0.1f64..0.1)) {
            let (v, t) = torus(0.06, 0.02, 32, 12);
            let collider = TriangleCollider::new("torus", &v, &t).unwrap();
            let p = DVec3::new(q[0], q[1], q[2] * 0.3);
            let hit = collider.closest_point(p, f64::MAX).unwrap();
            prop_assume!(hit.signed_distance.abs() > 1e-9);
            let inside = winding_number(p, &v, &t) > 0.5;
            prop_assert_eq!(hit.signed_distance < 0.0, inside);
        }
    }

    #[test]
    fn bad_surfaces_are_refused_with_the_item_named() {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(
            TriangleCollider::new("pelvis", &v, &[]).unwrap_err(),
            ContactError::EmptySurface { what: "pelvis" }
        );
        assert_eq!(
            TriangleCollider::new("pelvis", &v, &[[0, 1, 5]]).unwrap_err(),
            ContactError::VertexOutOfRange {
                what: "pelvis",
                triangle: 0,
                vertex: 5,
                count: 3
            }
        );
        assert_eq!(
            TriangleCollider::new("pelvis", &v, &[[0, 1, 1]]).unwrap_err(),
            ContactError::DegenerateTriangle {
                what: "pelvis",
                triangle: 0
            }
        );
        let nan = vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)];
        assert_eq!(
            TriangleCollider::new("pelvis", &nan, &[[0, 1, 2]]).unwrap_err(),
            ContactError::NonFiniteVertex {
                what: "pelvis",
                vertex: 2
            }
        );
    }
}
