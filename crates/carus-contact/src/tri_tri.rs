//! Exact triangle-triangle intersection test (Moller 1997, "A fast
//! triangle-triangle intersection test", J. Graphics Tools 2(2)), with the
//! coplanar case handled by 2-D edge crossings and containment. parry has no
//! triangle-triangle test of its own (its GJK answers for convex shapes in
//! general, with a tolerance), so this is written out here. Triangles that
//! only touch count as intersecting (closed sets).

use glam::{DVec2, DVec3};

/// Whether two triangles share at least one point.
pub fn triangles_intersect(t1: [DVec3; 3], t2: [DVec3; 3]) -> bool {
    let scale = t1.iter().chain(&t2).fold(0.0f64, |m, p| m.max(p.abs().max_element())).max(1e-300);

    // Signed distances (times |n2|) of t1's corners to the plane of t2.
    let n2 = (t2[1] - t2[0]).cross(t2[2] - t2[0]);
    let du = snap(t1.map(|p| n2.dot(p - t2[0])), n2.length() * scale);
    if same_strict_sign(du) {
        return false;
    }
    let n1 = (t1[1] - t1[0]).cross(t1[2] - t1[0]);
    let dv = snap(t2.map(|p| n1.dot(p - t1[0])), n1.length() * scale);
    if same_strict_sign(dv) {
        return false;
    }

    // Both triangles cross the other's plane: compare their intervals on the
    // line where the planes meet, projected on that line's largest axis.
    let direction = n1.cross(n2);
    let axis = direction.abs().max_position();
    let (Some(i1), Some(i2)) = (
        line_interval(t1.map(|p| p[axis]), du),
        line_interval(t2.map(|p| p[axis]), dv),
    ) else {
        return coplanar_intersect(t1, t2, n1);
    };
    i1.0.max(i2.0) <= i1.1.min(i2.1)
}

/// Zeroes plane distances within rounding of the plane (relative to the
/// size of the cross product that scales them), so that touching and
/// coplanar configurations are recognised.
fn snap(d: [f64; 3], magnitude: f64) -> [f64; 3] {
    let eps = 1e-12 * magnitude;
    d.map(|x| if x.abs() <= eps { 0.0 } else { x })
}

fn same_strict_sign(d: [f64; 3]) -> bool {
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

/// The interval a triangle covers on the planes' intersection line, from its
/// corners' coordinates `p` along that line and their plane distances `d`;
/// `None` when the triangle lies in the other's plane.
fn line_interval(p: [f64; 3], d: [f64; 3]) -> Option<(f64, f64)> {
    // The corner alone on its side of the plane goes first.
    let (lone, a, b) = if d[0] * d[1] > 0.0 {
        (2, 0, 1)
    } else if d[0] * d[2] > 0.0 {
        (1, 0, 2)
    } else if d[1] * d[2] > 0.0 || d[0] != 0.0 {
        (0, 1, 2)
    } else if d[1] != 0.0 {
        (1, 0, 2)
    } else if d[2] != 0.0 {
        (2, 0, 1)
    } else {
        return None;
    };
    let cut = |other: usize| p[lone] + (p[other] - p[lone]) * d[lone] / (d[lone] - d[other]);
    let (s, t) = (cut(a), cut(b));
    Some((s.min(t), s.max(t)))
}

/// Coplanar triangles: project on the axis plane where they are largest and
/// test edge crossings, then containment of one in the other.
fn coplanar_intersect(t1: [DVec3; 3], t2: [DVec3; 3], normal: DVec3) -> bool {
    let drop = normal.abs().max_position();
    let (i, j) = match drop {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let a = t1.map(|p| DVec2::new(p[i], p[j]));
    let b = t2.map(|p| DVec2::new(p[i], p[j]));
    for e in 0..3 {
        for f in 0..3 {
            if segments_intersect(a[e], a[(e + 1) % 3], b[f], b[(f + 1) % 3]) {
                return true;
            }
        }
    }
    point_in_triangle(a[0], b) || point_in_triangle(b[0], a)
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

fn segments_intersect(p1: DVec2, p2: DVec2, q1: DVec2, q2: DVec2) -> bool {
    let (d1, d2) = (orient(q1, q2, p1), orient(q1, q2, p2));
    let (d3, d4) = (orient(p1, p2, q1), orient(p1, p2, q2));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |a: DVec2, b: DVec2, p: DVec2, d: f64| {
        d == 0.0 && p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
    };
    on(q1, q2, p1, d1) || on(q1, q2, p2, d2) || on(p1, p2, q1, d3) || on(p1, p2, q2, d4)
}

fn point_in_triangle(p: DVec2, t: [DVec2; 3]) -> bool {
    let d = [orient(t[0], t[1], p), orient(t[1], t[2], p), orient(t[2], t[0], p)];
    let has_neg = d.iter().any(|&x| x < 0.0);
    let has_pos = d.iter().any(|&x| x > 0.0);
    !(has_neg && has_pos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Independent reference for triangles in general position: two
    /// triangles meet exactly when an edge of one pierces the other.
    fn segment_pierces_triangle(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
        let vol = |x: DVec3, y: DVec3, z: DVec3, w: DVec3| (y - x).cross(z - x).dot(w - x);
        let (sp, sq) = (vol(a, b, c, p), vol(a, b, c, q));
        if sp * sq > 0.0 {
            return false;
        }
        let (s1, s2, s3) = (vol(p, q, a, b), vol(p, q, b, c), vol(p, q, c, a));
        (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0)
    }

    fn edge_reference(t1: [DVec3; 3], t2: [DVec3; 3]) -> bool {
        (0..3).any(|e| segment_pierces_triangle(t1[e], t1[(e + 1) % 3], t2))
            || (0..3).any(|e| segment_pierces_triangle(t2[e], t2[(e + 1) % 3], t1))
    }

    fn tri(c: [f64; 9]) -> [DVec3; 3] {
        [0, 3, 6].map(|k| DVec3::new(c[k], c[k + 1], c[k + 2]))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// C3: the Moller test agrees with the edge-piercing reference on
        /// random triangle pairs, whichever order they are given in.
        #[test]
        fn c3_agrees_with_edge_piercing(a in prop::array::uniform9(-1.0f64..1.0),
                                        b in prop::array::uniform9(-1.0f64..1.0)) {
            let (t1, t2) = (tri(a), tri(b));
            let expected = edge_reference(t1, t2);
            prop_assert_eq!(triangles_intersect(t1, t2), expected);
            prop_assert_eq!(triangles_intersect(t2, t1), expected);
            prop_assert_eq!(triangles_intersect([t1[1], t1[2], t1[0]], [t2[2], t2[1], t2[0]]), expected);
        }

        /// Coplanar pairs (both in z = 0 after a rotation) against the 2-D reference.
        #[test]
        fn coplanar_pairs(a in prop::array::uniform6(-1.0f64..1.0),
                          b in prop::array::uniform6(-1.0f64..1.0),
                          angle in 0.0f64..3.0) {
            let flat = |c: [f64; 6]| [0, 2, 4].map(|k| DVec2::new(c[k], c[k + 1]));
            let (p, q) = (flat(a), flat(b));
            let expected = (0..3).any(|e| (0..3).any(|f| segments_intersect(p[e], p[(e + 1) % 3], q[f], q[(f + 1) % 3])))
                || point_in_triangle(p[0], q) || point_in_triangle(q[0], p);
            let rot = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), angle);
            let lift = |t: [DVec2; 3]| t.map(|v| rot * DVec3::new(v.x, v.y, 0.0));
            // Rotation rounding leaves the pair coplanar to ~1e-16, inside the snap tolerance.
            prop_assert_eq!(triangles_intersect(lift(p), lift(q)), expected);
        }
    }

    #[test]
    fn touching_and_separate_cases() {
        let base = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Shares one vertex, otherwise above the plane: touches.
        assert!(triangles_intersect(base, [DVec3::ZERO, DVec3::new(0.0, 0.0, 1.0), DVec3::new(1.0, 1.0, 1.0)]));
        // Lifted clear of the plane.
        let lifted = base.map(|p| p + DVec3::new(0.0, 0.0, 1e-3));
        assert!(!triangles_intersect(base, lifted));
        // Coplanar, disjoint.
        assert!(!triangles_intersect(base, base.map(|p| p + DVec3::new(2.0, 0.0, 0.0))));
        // Coplanar, one inside the other.
        assert!(triangles_intersect(base, base.map(|p| 0.1 * p + DVec3::splat(0.1).with_z(0.0))));
        // A vertical triangle piercing the middle.
        assert!(triangles_intersect(
            base,
            [DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.3, 0.2, 1.0), DVec3::new(0.2, 0.3, 1.0)]
        ));
    }
}
