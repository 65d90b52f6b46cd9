//! Mesh overlap: the pairs of triangles of two posed surfaces that
//! intersect (for example a fetal head placed into a pelvis at the start of
//! a run, which must not begin inside the bone), and the pairs of one
//! surface that cross each other (a surface folded on itself, which the
//! contact's inside test misreads). Broad phase: each triangle's bounding
//! box queries the BVH; narrow phase: the exact triangle-triangle test.

use glam::DVec3;

use crate::collider::TriangleCollider;
use crate::rigid::RigidPose;
use crate::tri_tri::triangles_intersect;

/// Intersecting triangle pairs `[triangle of a, triangle of b]`, sorted.
pub fn overlapping_triangles(
    a: &TriangleCollider,
    a_pose: &RigidPose,
    b: &TriangleCollider,
    b_pose: &RigidPose,
) -> Vec<[u32; 2]> {
    let to_a = |p: DVec3| a_pose.inverse_point(b_pose.point(p));
    let mut pairs = Vec::new();
    for tb in 0..b.triangle_count() as u32 {
        let corners = b.corners(tb).map(to_a);
        let lo = corners[0].min(corners[1]).min(corners[2]);
        let hi = corners[0].max(corners[1]).max(corners[2]);
        for ta in a.triangles_near(lo, hi) {
            if triangles_intersect(a.corners(ta), corners) {
                pairs.push([ta, tb]);
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// Pairs `[t, u]` (t < u, sorted) of triangles of one surface that
/// intersect without sharing a corner: where the surface crosses itself.
/// Neighbours that share a corner touch by construction and are left out
/// (a fold through a shared corner alone is not found).
pub fn self_intersections(surface: &TriangleCollider) -> Vec<[u32; 2]> {
    let mut pairs = Vec::new();
    for t in 0..surface.triangle_count() as u32 {
        let corners = surface.corners(t);
        let lo = corners[0].min(corners[1]).min(corners[2]);
        let hi = corners[0].max(corners[1]).max(corners[2]);
        for u in surface.triangles_near(lo, hi).into_iter().filter(|&u| u > t) {
            let other = surface.corners(u);
            let neighbours = corners.iter().any(|p| other.contains(p));
            if !neighbours && triangles_intersect(corners, other) {
                pairs.push([t, u]);
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collider::tests::{random_mesh, uv_sphere};
    use glam::DQuat;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// C3: the BVH-accelerated overlap finds exactly the pairs a brute
        /// force test over all pairs finds.
        #[test]
        fn c3_overlap_matches_brute_force((va, ta) in random_mesh(), (vb, tb) in random_mesh(),
                                          shift in prop::array::uniform3(-0.5f64..0.5), angle in 0.0f64..3.0) {
            let a = TriangleCollider::new("a", &va, &ta).unwrap();
            let b = TriangleCollider::new("b", &vb, &tb).unwrap();
            let a_pose = RigidPose::new(DVec3::new(0.1, -0.2, 0.3), DQuat::from_rotation_z(0.7));
            let b_pose = RigidPose::new(DVec3::from_array(shift), DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), angle));
            let mut brute = Vec::new();
            for i in 0..ta.len() as u32 {
                for j in 0..tb.len() as u32 {
                    // Both in world coordinates, independently of the BVH path.
                    let wa = a.corners(i).map(|p| a_pose.point(p));
                    let wb = b.corners(j).map(|p| b_pose.point(p));
                    if triangles_intersect(wa, wb) {
                        brute.push([i, j]);
                    }
                }
            }
            prop_assert_eq!(overlapping_triangles(&a, &a_pose, &b, &b_pose), brute);
        }
    }

    /// A closed sphere does not cross itself; with one vertex pushed
    /// through the far side, the triangles round it cross the far wall.
    #[test]
    fn a_sphere_pushed_through_itself_crosses_itself() {
        let (mut v, t) = uv_sphere(0.05, 10, 20);
        assert!(self_intersections(&TriangleCollider::new("sphere", &v, &t).unwrap()).is_empty());
        let top = (0..v.len()).max_by(|&a, &b| v[a].x.total_cmp(&v[b].x)).unwrap();
        v[top].x = -0.08;
        let folded = self_intersections(&TriangleCollider::new("folded", &v, &t).unwrap());
        assert!(!folded.is_empty());
        assert!(folded.iter().all(|&[a, b]| a < b));
    }

    /// The generated pelvis is a clean shell: its outer wall, pushed out
    /// from the canal wall by the bone's thickness, no longer folds through
    /// itself at the brim (286 crossing pairs in the default pelvis before
    /// carus-anatomy relaxed it), for the default and a contracted inlet.
    #[test]
    fn generated_pelves_do_not_cross_themselves() {
        use carus_anatomy::pelvis::PelvisDiameters;
        let contracted = PelvisDiameters { inlet_ap_mm: 85.0, inlet_oblique_mm: 112.0, ..PelvisDiameters::default() };
        for d in [PelvisDiameters::default(), contracted] {
            let pelvis = carus_anatomy::Pelvis::generate(&d).unwrap();
            let s = &pelvis.surface;
            let pairs = self_intersections(&TriangleCollider::new("pelvis", &s.vertices, &s.triangles).unwrap());
            assert!(pairs.is_empty(), "{} crossing pairs for {d:?}", pairs.len());
        }
    }

    #[test]
    fn nested_spheres_do_not_overlap_and_crossing_ones_do() {
        let (v, t) = uv_sphere(0.05, 10, 20);
        let big = TriangleCollider::new("big", &v, &t).unwrap();
        let (v2, t2) = uv_sphere(0.02, 8, 12);
        let small = TriangleCollider::new("small", &v2, &t2).unwrap();
        let centre = RigidPose::IDENTITY;
        assert!(overlapping_triangles(&big, &centre, &small, &centre).is_empty());
        let on_wall = RigidPose::new(DVec3::new(0.05, 0.0, 0.0), DQuat::IDENTITY);
        assert!(!overlapping_triangles(&big, &centre, &small, &on_wall).is_empty());
    }
}
