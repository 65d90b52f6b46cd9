//! Curves the canal is built from: cubic Hermite (Catmull-Rom)
//! interpolation through control points at non-uniform knots, periodic
//! (around the canal) or open (down the canal), and superellipse rings.

use glam::DVec3;

/// Positions round the canal are in 1/64 turns: signed `s` positive towards
/// the mother's left, `da = |s|` the distance from the front midline (0 front,
/// 16 side, 32 back).
pub(crate) const HALF_TURN: f64 = 32.0;

/// A closed ring through four points: `front` and `back` on the antero-
/// posterior line, `left` and `right` at the sides, a superellipse of
/// `exponent` in between (2 is an ellipse; larger is boxier). With the sides
/// at (+-w, y_l, z_l) it is x = w cos^(2/n), (y, z) moving from the sides'
/// midpoint towards front or back by sin^(2/n).
pub(crate) struct SuperRing {
    pub front: DVec3,
    pub back: DVec3,
    pub left: DVec3,
    pub right: DVec3,
    pub exponent: f64,
}

impl SuperRing {
    /// Point at signed turn position `s` (see [`HALF_TURN`]).
    pub fn at(&self, s: f64) -> DVec3 {
        let theta = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * s / HALF_TURN;
        let (sin, cos) = theta.sin_cos();
        let power = |c: f64| c.abs().powf(2.0 / self.exponent);
        let middle = 0.5 * (self.left + self.right);
        let side = if cos < 0.0 { self.left } else { self.right };
        let end = if sin > 0.0 { self.front } else { self.back };
        middle + power(cos) * (side - middle) + power(sin) * (end - middle)
    }
}

/// Hermite basis between two control points `h` apart.
fn hermite(p0: DVec3, m0: DVec3, p1: DVec3, m1: DVec3, h: f64, s: f64) -> DVec3 {
    let s2 = s * s;
    let s3 = s2 * s;
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0) + m0 * (h * (s3 - 2.0 * s2 + s)) + p1 * (-2.0 * s3 + 3.0 * s2) + m1 * (h * (s3 - s2))
}

/// Interpolates `points` at increasing `knots`; `period` makes it closed.
/// Tangents are central differences over the neighbouring knots (one-sided
/// at the ends of an open curve), so the curve passes through every point.
pub(crate) fn catmull_rom(knots: &[f64], points: &[DVec3], period: Option<f64>, t: f64) -> DVec3 {
    let n = knots.len();
    debug_assert!(n >= 2 && points.len() == n);
    let knot = |k: isize| -> (f64, DVec3) {
        match period {
            Some(p) => {
                let wraps = k.div_euclid(n as isize);
                let idx = k.rem_euclid(n as isize) as usize;
                (knots[idx] + wraps as f64 * p, points[idx])
            }
            None => {
                let idx = k.clamp(0, n as isize - 1) as usize;
                (knots[idx], points[idx])
            }
        }
    };
    let tangent = |k: isize| -> DVec3 {
        let (lo, hi) = match period {
            Some(_) => (k - 1, k + 1),
            None => ((k - 1).max(0), (k + 1).min(n as isize - 1)),
        };
        let (t0, p0) = knot(lo);
        let (t1, p1) = knot(hi);
        (p1 - p0) / (t1 - t0)
    };
    let t = match period {
        Some(p) => knots[0] + (t - knots[0]).rem_euclid(p),
        None => t.clamp(knots[0], knots[n - 1]),
    };
    let last = if period.is_some() { n } else { n - 1 };
    let k = (0..last as isize).rfind(|&k| knot(k).0 <= t).unwrap_or(0);
    let (t0, p0) = knot(k);
    let (t1, p1) = knot(k + 1);
    let h = t1 - t0;
    hermite(p0, tangent(k), p1, tangent(k + 1), h, (t - t0) / h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_its_points_open_and_closed() {
        let knots = [0.0, 1.0, 2.5, 4.0];
        let points = [DVec3::X, DVec3::Y, DVec3::new(-1.0, 0.2, 0.0), DVec3::NEG_Y];
        for period in [None, Some(6.0)] {
            for (k, p) in knots.iter().zip(points) {
                assert!((catmull_rom(&knots, &points, period, *k) - p).length() < 1e-12);
            }
        }
        let closed = |t| catmull_rom(&knots, &points, Some(6.0), t);
        assert!((closed(5.999_999_9) - closed(0.0)).length() < 1e-5);
        assert!((closed(7.0) - points[1]).length() < 1e-12);
    }

    #[test]
    fn reproduces_a_straight_line_at_uniform_knots() {
        let knots = [0.0, 1.0, 2.0, 3.0];
        let points = knots.map(|k| DVec3::new(k, 2.0 * k, 0.0));
        let p = catmull_rom(&knots, &points, None, 1.3);
        assert!((p - DVec3::new(1.3, 2.6, 0.0)).length() < 1e-12);
    }
}
