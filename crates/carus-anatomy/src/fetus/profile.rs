//! The midline (sagittal) profile of the fetal head: a closed convex curve in
//! the (o, v) plane through the midline landmarks.
//!
//! Each presenting diameter must equal the head's extent across it, so both
//! of its end landmarks must be extreme points of the head along the
//! diameter: the curve passes through each landmark with its tangent
//! perpendicular to the diameter. Neighbouring landmarks are joined by
//! quadratic Bezier arcs whose control point is where their tangent lines
//! meet, which keeps the curve convex and tangent-continuous. The bregma ends
//! both the suboccipitobregmatic and the submentobregmatic diameters, two
//! directions apart, so the curve has a corner (a ridge across the head)
//! there: no smooth head can present both diameters exactly.
//!
//! The landmark placement left free by the diameters (three angles, the
//! menton and the height of the occipitofrontal line) is chosen to make the
//! curve as robustly convex as possible: a deterministic random search
//! maximises the smallest clearance between each landmark and the tangent
//! lines of its neighbours.

use std::f64::consts::PI;

use glam::DVec2;

use super::diameters::{HeadDiameters, HeadError};

/// Names of the arcs between neighbouring landmarks, for error messages.
const ARC_NAMES: [&str; 7] = [
    "forehead (glabella to bregma)",
    "crown (bregma to vertex)",
    "back of the vault (vertex to occiput)",
    "occiput to the suboccipital point",
    "skull base (suboccipital to submental point)",
    "jaw (submental point to menton)",
    "face (menton to glabella)",
];

/// Polygon samples per arc; landmarks sit on samples.
const SAMPLES_PER_ARC: usize = 96;
/// Lambda lies halfway along the back of the vault.
const LAMBDA_SAMPLE: usize = SAMPLES_PER_ARC / 2;
/// The nasion lies on the face arc, a fifth of the way down from the glabella.
const NASION_SAMPLE: usize = SAMPLES_PER_ARC * 4 / 5;
/// Smallest clearance accepted between a landmark and a neighbour's tangent, metres.
const MIN_CLEARANCE: f64 = 1.0e-3;

/// Free placement of the midline landmarks, bregma at the origin: the
/// directions of the suboccipitobregmatic diameter (from the occiput side
/// towards the bregma), the crease at the bregma (angle from that direction
/// to the submentobregmatic one), the mentovertical direction (menton to
/// vertex), the menton and the glabella.
#[derive(Debug, Clone, Copy)]
struct Design {
    sob_angle: f64,
    crease: f64,
    mv_angle: f64,
    menton: DVec2,
    glabella: DVec2,
}

/// The diameters the profile must meet, metres.
#[derive(Debug, Clone, Copy)]
struct Midline {
    occipitofrontal: f64,
    suboccipitobregmatic: f64,
    mentovertical: f64,
    submentobregmatic: f64,
}

/// A landmark where the curve passes with outward normal at `angle` from o.
#[derive(Debug, Clone, Copy)]
struct Support {
    point: DVec2,
    angle: f64,
}

fn direction(angle: f64) -> DVec2 {
    DVec2::new(angle.cos(), angle.sin())
}

impl Design {
    /// The midline supports in counter-clockwise order: glabella, bregma
    /// (twice: both sides of its corner), vertex, occiput, suboccipital
    /// point, submental point, menton.
    fn supports(&self, m: &Midline) -> [Support; 8] {
        let smb_angle = self.sob_angle + self.crease;
        let bregma = DVec2::ZERO;
        let vertex = self.menton + m.mentovertical * direction(self.mv_angle);
        let occiput = self.glabella - DVec2::new(m.occipitofrontal, 0.0);
        [
            Support {
                point: self.glabella,
                angle: 0.0,
            },
            Support {
                point: bregma,
                angle: self.sob_angle,
            },
            Support {
                point: bregma,
                angle: smb_angle,
            },
            Support {
                point: vertex,
                angle: self.mv_angle,
            },
            Support {
                point: occiput,
                angle: PI,
            },
            Support {
                point: bregma - m.suboccipitobregmatic * direction(self.sob_angle),
                angle: self.sob_angle + PI,
            },
            Support {
                point: bregma - m.submentobregmatic * direction(smb_angle),
                angle: smb_angle + PI,
            },
            Support {
                point: self.menton,
                angle: self.mv_angle + PI,
            },
        ]
    }

    /// The smallest clearance of the design and the arc where it occurs.
    /// Positive clearance on every arc means a convex curve exists with
    /// every landmark extreme along its diameter.
    fn clearance(&self, m: &Midline) -> (f64, usize) {
        let s = self.supports(m);
        // Angles are weighed as arc length on a head of occipitofrontal size.
        let radius = 0.5 * m.occipitofrontal;
        let mut worst = (f64::MAX, 0);
        for (arc, (i, j)) in ARCS.iter().copied().enumerate() {
            let (a, b) = (s[i], s[j]);
            // The last arc closes the curve: the glabella's normal comes round to 2 pi.
            let turn = b.angle - a.angle + if j == 0 { 2.0 * PI } else { 0.0 };
            let angular = radius * turn.min(PI - turn);
            let from_a = -(b.point - a.point).dot(direction(a.angle));
            let from_b = -(a.point - b.point).dot(direction(b.angle));
            let c = angular.min(from_a).min(from_b);
            if c < worst.0 {
                worst = (c, arc);
            }
        }
        worst
    }
}

/// Pairs of support indices joined by an arc (the bregma corner has none).
const ARCS: [(usize, usize); 7] = [(0, 1), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 0)];

/// SplitMix64: a small deterministic generator for the design search, so
/// that the same diameters always give the same head.
struct SplitMix(u64);

impl SplitMix {
    fn next_unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal deviate (Box-Muller).
    fn next_normal(&mut self) -> f64 {
        let u1 = self.next_unit().max(f64::MIN_POSITIVE);
        let u2 = self.next_unit();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// Maximises the smallest clearance, starting from the best design found
/// for the default term head, scaled to the requested size.
fn search(m: &Midline) -> (Design, f64, usize) {
    let scale = (m.occipitofrontal + m.suboccipitobregmatic + m.mentovertical + m.submentobregmatic) / 0.445;
    let mm = 1.0e-3 * scale;
    let mut best = Design {
        sob_angle: 50.7_f64.to_radians(),
        crease: 26.9_f64.to_radians(),
        mv_angle: 134.8_f64.to_radians(),
        menton: DVec2::new(15.6, -90.2) * mm,
        glabella: DVec2::new(25.8, -34.4) * mm,
    };
    let (mut best_clearance, mut best_arc) = best.clearance(m);
    let mut rng = SplitMix(0x0CA2_05FE_7A15);
    for (trials, step_deg, step_mm) in [(12_000, 3.0, 3.0), (12_000, 0.5, 0.5), (6_000, 0.08, 0.08)] {
        let (da, dx) = (f64::to_radians(step_deg), step_mm * mm);
        for _ in 0..trials {
            let trial = Design {
                sob_angle: best.sob_angle + da * rng.next_normal(),
                crease: best.crease + da * rng.next_normal(),
                mv_angle: best.mv_angle + da * rng.next_normal(),
                menton: best.menton + dx * DVec2::new(rng.next_normal(), rng.next_normal()),
                glabella: best.glabella + dx * DVec2::new(rng.next_normal(), rng.next_normal()),
            };
            let (clearance, arc) = trial.clearance(m);
            if clearance > best_clearance {
                (best, best_clearance, best_arc) = (trial, clearance, arc);
            }
        }
    }
    (best, best_clearance, best_arc)
}

/// The convex midline curve of the head, metres, in the sagittal (o, v)
/// plane with its origin at the head centre (midpoint of the
/// occipitofrontal diameter).
#[derive(Debug, Clone)]
pub(crate) struct SagittalProfile {
    pub glabella: DVec2,
    pub nasion: DVec2,
    pub bregma: DVec2,
    pub vertex: DVec2,
    pub lambda: DVec2,
    pub occiput: DVec2,
    pub suboccipital: DVec2,
    pub submental: DVec2,
    pub menton: DVec2,
    /// Counter-clockwise convex polygon inscribed in the curve, every
    /// landmark above among its vertices, starting at the smallest polar angle.
    polygon: Vec<DVec2>,
    /// Polar angle of each polygon vertex, increasing, in [-pi, pi).
    angles: Vec<f64>,
}

impl SagittalProfile {
    pub fn new(d: &HeadDiameters) -> Result<Self, HeadError> {
        let m = Midline {
            occipitofrontal: d.occipitofrontal_mm * 1e-3,
            suboccipitobregmatic: d.suboccipitobregmatic_mm * 1e-3,
            mentovertical: d.mentovertical_mm * 1e-3,
            submentobregmatic: d.submentobregmatic_mm * 1e-3,
        };
        let (design, clearance, arc) = search(&m);
        if clearance < MIN_CLEARANCE {
            return Err(HeadError::Unshapeable {
                region: ARC_NAMES[arc],
                shortfall_mm: (MIN_CLEARANCE - clearance) * 1e3,
            });
        }
        let mut s = design.supports(&m);
        let centre = s[0].point - DVec2::new(0.5 * m.occipitofrontal, 0.0);
        for support in &mut s {
            support.point -= centre;
        }

        let mut polygon = Vec::with_capacity(ARCS.len() * SAMPLES_PER_ARC);
        let (mut lambda, mut nasion) = (DVec2::ZERO, DVec2::ZERO);
        for (arc, (i, j)) in ARCS.iter().copied().enumerate() {
            let (a, b) = (s[i], s[j]);
            let control = tangent_meet(a, b);
            for k in 0..SAMPLES_PER_ARC {
                let t = k as f64 / SAMPLES_PER_ARC as f64;
                let p = (1.0 - t) * (1.0 - t) * a.point + 2.0 * t * (1.0 - t) * control + t * t * b.point;
                if arc == 2 && k == LAMBDA_SAMPLE {
                    lambda = p;
                }
                if arc == 6 && k == NASION_SAMPLE {
                    nasion = p;
                }
                polygon.push(p);
            }
        }
        let start = (0..polygon.len())
            .min_by(|&a, &b| polar(polygon[a]).total_cmp(&polar(polygon[b])))
            .unwrap_or(0);
        polygon.rotate_left(start);
        let angles = polygon.iter().map(|&p| polar(p)).collect();

        Ok(SagittalProfile {
            glabella: s[0].point,
            nasion,
            bregma: s[1].point,
            vertex: s[3].point,
            lambda,
            occiput: s[4].point,
            suboccipital: s[5].point,
            submental: s[6].point,
            menton: s[7].point,
            polygon,
            angles,
        })
    }

    /// Distance from the head centre to the curve along the unit direction
    /// at polar angle `angle` (radians from o towards v).
    pub fn radius(&self, angle: f64) -> f64 {
        let angle = wrap(angle);
        let n = self.polygon.len();
        // Edge from vertex i to i + 1 (cyclic) spans the query angle.
        let i = match self.angles.partition_point(|&a| a <= angle) {
            0 => n - 1,
            k => k - 1,
        };
        let (a, b) = (self.polygon[i], self.polygon[(i + 1) % n]);
        let ray = DVec2::new(angle.cos(), angle.sin());
        // Solve t * ray = a + s (b - a) for t.
        let edge = b - a;
        let denominator = ray.perp_dot(edge);
        a.perp_dot(edge) / denominator
    }

    /// The polygon vertices (for drawing and tests).
    #[cfg(test)]
    pub fn polygon(&self) -> &[DVec2] {
        &self.polygon
    }
}

/// Where the tangent lines at two supports meet: the Bezier control point.
fn tangent_meet(a: Support, b: Support) -> DVec2 {
    let (na, nb) = (direction(a.angle), direction(b.angle));
    let (ra, rb) = (a.point.dot(na), b.point.dot(nb));
    let det = na.perp_dot(nb);
    DVec2::new(ra * nb.y - na.y * rb, na.x * rb - ra * nb.x) / det
}

fn polar(p: DVec2) -> f64 {
    wrap(p.y.atan2(p.x))
}

/// Maps an angle into [-pi, pi).
fn wrap(angle: f64) -> f64 {
    let a = (angle + PI).rem_euclid(2.0 * PI) - PI;
    if a >= PI {
        -PI
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_polygon_is_convex_and_counter_clockwise() {
        let p = SagittalProfile::new(&HeadDiameters::default()).unwrap();
        let poly = p.polygon();
        let n = poly.len();
        for i in 0..n {
            let (a, b, c) = (poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
            assert!((b - a).perp_dot(c - b) >= -1e-15, "reflex turn at {i}");
        }
        for w in p.angles.windows(2) {
            assert!(w[1] > w[0]);
        }
    }

    #[test]
    fn radius_meets_the_polygon_vertices() {
        let p = SagittalProfile::new(&HeadDiameters::default()).unwrap();
        for &q in [p.glabella, p.bregma, p.occiput, p.menton, p.submental, p.lambda].iter() {
            let r = p.radius(q.y.atan2(q.x));
            assert!((r - q.length()).abs() < 1e-12, "{r} vs {}", q.length());
        }
    }

    #[test]
    fn landmarks_are_extreme_along_their_diameters() {
        let p = SagittalProfile::new(&HeadDiameters::default()).unwrap();
        let extreme = |a: DVec2, b: DVec2| {
            let u = (b - a).normalize();
            let (lo, hi) = p
                .polygon()
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), q| (lo.min(q.dot(u)), hi.max(q.dot(u))));
            assert!((hi - b.dot(u)).abs() < 1e-12 && (lo - a.dot(u)).abs() < 1e-12);
        };
        extreme(p.occiput, p.glabella);
        extreme(p.suboccipital, p.bregma);
        extreme(p.submental, p.bregma);
        extreme(p.menton, p.vertex);
    }
}
