//! Imposed and hybrid motion of the fetal head, for teaching: way-points of
//! station, occiput position (theta) and attitude (phi), the coordinates a
//! clinician reads and the detector reports (CARDINAL_MOVEMENTS.md).
//!
//! - `imposed`: the head follows the way-points exactly; the trunk, the
//!   floor and the contacts respond to it by the physics, so a run shows
//!   what the mechanism a teacher draws asks of the tissue and the neck.
//! - `hybrid`: the forward physics, with a guide (a spring and damper, the
//!   teacher's hand) pulling the head towards the way-points; the guide's
//!   force and moment are recorded, so a run shows how much help the
//!   physics needed.
//!
//! Forward mode (the default) builds no [`Trajectory`]: the forward step
//! never reads a way-point (CARDINAL_MOVEMENTS.md, "What the forward mode
//! may use").

use serde::{Deserialize, Serialize};

/// How the fetal head is moved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Physics only: the expulsion force, contact, friction and elasticity.
    #[default]
    Forward,
    /// The head follows the way-points; everything else responds.
    Imposed,
    /// The physics, with the head guided towards the way-points.
    Hybrid,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Forward => "forward",
            Mode::Imposed => "imposed",
            Mode::Hybrid => "hybrid",
        }
    }
}

/// Where the head should be at one time: the station of its leading point,
/// the occiput's angle theta in the canal's cross-section and the attitude
/// phi (flexion positive) about its biparietal axis, measured from the
/// canal's tangent at the head (with the trunk along the canal, the
/// detector's phi).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    pub time_s: f64,
    /// mm, negative above the ischial spines.
    pub station_mm: f64,
    /// Degrees from anterior, positive to the mother's right: OA 0, LOT
    /// -90, ROT +90, OP 180. Taken as written, so -180 and 180 turn
    /// different ways from -90.
    pub theta_deg: f64,
    /// Degrees, positive flexed.
    pub phi_deg: f64,
    /// How far the head's centre lies off the pelvic axis towards the
    /// symphysis (negative: towards the sacrum), mm; 0 when left out. The
    /// head extends under the pubic arch off the axis, its occiput close
    /// to the symphysis.
    #[serde(default)]
    pub anterior_mm: f64,
}

/// `[trajectory]`: the mode, the way-points, and the hybrid guide.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectorySection {
    pub mode: Mode,
    /// Hybrid guide on the head's centre, N/m: 20000 N/m pulls with 200 N
    /// when the head is 10 mm off its path, more than the default push's
    /// 120 N peak, so the push moves the head some millimetres off it and
    /// the bone can still turn it aside. A teaching choice, not
    /// physiology: it stands for a hand.
    pub guide_stiffness_n_per_m: f64,
    /// Hybrid guide on the head's orientation, N m/rad: 10 degrees off
    /// gives 1.7 N m, more than the bone's or the floor's moment on the
    /// head in the normal run (up to 1.5 N m, docs/LABOUR.md). A teaching
    /// choice, not physiology.
    pub guide_torsion_nm_per_rad: f64,
    /// After the start (`[start]`, at t = 0), in time order.
    pub waypoints: Vec<Waypoint>,
}

impl Default for TrajectorySection {
    fn default() -> Self {
        TrajectorySection {
            mode: Mode::Forward,
            guide_stiffness_n_per_m: 20000.0,
            guide_torsion_nm_per_rad: 10.0,
            waypoints: Vec::new(),
        }
    }
}

impl TrajectorySection {
    /// A note for way-points whose angles, not all zero, all lie within a
    /// full turn in radians (under 6.28 in size): the keys are degrees, and
    /// angles written in radians (1.57 for a quarter turn) would put the
    /// head within a few degrees of occiput anterior and of phi 0.
    pub fn radians_note(&self) -> Option<String> {
        use std::f64::consts::TAU;
        let angles = || self.waypoints.iter().flat_map(|w| [w.theta_deg, w.phi_deg]);
        let small = angles().all(|a| a.abs() < TAU) && angles().any(|a| a != 0.0);
        small.then(|| {
            format!(
                "every way-point's theta_deg and phi_deg is under {TAU:.2} in size; they are degrees: if they \
                 were written in radians, multiply them by 57.3 (a quarter turn is 90 deg, not 1.57)"
            )
        })
    }
}

/// The guide is critically damped, so the head settles on its path
/// without ringing (engineering choice).
pub const GUIDE_DAMPING_RATIO: f64 = 1.0;

/// The station, theta and phi of a way-point, or of the trajectory at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadCoordinates {
    pub station_mm: f64,
    pub theta_deg: f64,
    pub phi_deg: f64,
    pub anterior_mm: f64,
}

/// Where the trajectory has the head at a time: its centre's arc length
/// along the pelvic axis (the way-points' stations, placed once at each
/// way-point), and theta, phi and the offset towards the symphysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryPoint {
    pub centre_sigma_m: f64,
    pub theta_deg: f64,
    pub phi_deg: f64,
    pub anterior_mm: f64,
}

/// A checked trajectory: knots at increasing times, each coordinate joined
/// by a monotone cubic (Fritsch & Carlson 1980, SIAM J. Numer. Anal. 17:238),
/// which passes through every knot, is smooth in time and never overshoots
/// a knot between two (a head told to stop at +40 mm does not dip past it).
///
/// The station names the leading point, which jumps from one part of the
/// skull to another as the head turns; the head's centre does not. So each
/// way-point's station is turned into its centre's arc length once, and
/// the centre is what moves smoothly between them.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    times: Vec<f64>,
    channels: [Channel; 4],
}

/// One coordinate's knot values and slopes.
#[derive(Debug, Clone, PartialEq)]
struct Channel {
    values: Vec<f64>,
    slopes: Vec<f64>,
}

impl Channel {
    fn new(times: &[f64], values: Vec<f64>) -> Channel {
        let n = values.len();
        let secant: Vec<f64> = (0..n.saturating_sub(1))
            .map(|i| (values[i + 1] - values[i]) / (times[i + 1] - times[i]))
            .collect();
        let mut slopes = vec![0.0; n];
        // Interior knots: the weighted harmonic mean of the neighbouring
        // secants where they agree in sign, zero at a turning point
        // (Fritsch & Butland 1984's form of the Fritsch-Carlson
        // condition). The ends are at rest: the head starts and finishes still.
        for i in 1..n.saturating_sub(1) {
            let (a, b) = (secant[i - 1], secant[i]);
            if a * b > 0.0 {
                let (ha, hb) = (times[i] - times[i - 1], times[i + 1] - times[i]);
                let (wa, wb) = (2.0 * hb + ha, hb + 2.0 * ha);
                slopes[i] = (wa + wb) / (wa / a + wb / b);
            }
        }
        Channel { values, slopes }
    }

    fn at(&self, times: &[f64], i: usize, t: f64) -> f64 {
        let h = times[i + 1] - times[i];
        let s = (t - times[i]) / h;
        let (s2, s3) = (s * s, s * s * s);
        let (y0, y1) = (self.values[i], self.values[i + 1]);
        let (m0, m1) = (self.slopes[i] * h, self.slopes[i + 1] * h);
        (2.0 * s3 - 3.0 * s2 + 1.0) * y0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * y1 + (s3 - s2) * m1
    }
}

impl Trajectory {
    /// The trajectory from `start` at t = 0 through `waypoints`, whose
    /// times must rise from above 0 ([`TrajectorySection`] is checked with
    /// the scenario); `centre_sigma` places a head at given coordinates
    /// (the scene's anatomy knows where its leading point lies).
    pub fn new(
        start: HeadCoordinates,
        waypoints: &[Waypoint],
        centre_sigma: impl Fn(&HeadCoordinates) -> f64,
    ) -> Trajectory {
        let knots: Vec<HeadCoordinates> = std::iter::once(start)
            .chain(waypoints.iter().map(|w| HeadCoordinates {
                station_mm: w.station_mm,
                theta_deg: w.theta_deg,
                phi_deg: w.phi_deg,
                anterior_mm: w.anterior_mm,
            }))
            .collect();
        let times: Vec<f64> = std::iter::once(0.0).chain(waypoints.iter().map(|w| w.time_s)).collect();
        let channel = |of: &dyn Fn(&HeadCoordinates) -> f64| Channel::new(&times, knots.iter().map(of).collect());
        let channels = [
            channel(&centre_sigma),
            channel(&|k| k.theta_deg),
            channel(&|k| k.phi_deg),
            channel(&|k| k.anterior_mm),
        ];
        Trajectory { times, channels }
    }

    /// Where the head should be at `t`: held at the start before 0 and at
    /// the last way-point after it.
    pub fn at(&self, t: f64) -> TrajectoryPoint {
        let last = self.times.len() - 1;
        let value = |c: &Channel| {
            if t <= self.times[0] || last == 0 {
                c.values[0]
            } else if t >= self.times[last] {
                c.values[last]
            } else {
                let i = self.times.partition_point(|&k| k <= t) - 1;
                c.at(&self.times, i, t)
            }
        };
        let [sigma, theta, phi, anterior] = &self.channels;
        TrajectoryPoint {
            centre_sigma_m: value(sigma),
            theta_deg: value(theta),
            phi_deg: value(phi),
            anterior_mm: value(anterior),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn start() -> HeadCoordinates {
        HeadCoordinates { station_mm: -55.0, theta_deg: -90.0, phi_deg: 5.0, anterior_mm: 0.0 }
    }

    /// A stand-in placement: the centre's arc length is the station, in metres.
    fn path(points: &[Waypoint]) -> Trajectory {
        Trajectory::new(start(), points, |k| k.station_mm * 1e-3)
    }

    fn waypoint(time_s: f64, station_mm: f64, theta_deg: f64, phi_deg: f64) -> Waypoint {
        Waypoint { time_s, station_mm, theta_deg, phi_deg, anterior_mm: 0.0 }
    }

    /// Angles that read as radians get a note; degrees, and a path that
    /// keeps the start's angles (all zero), do not.
    #[test]
    fn way_point_angles_in_radians_are_noted() {
        let section = |points: Vec<Waypoint>| TrajectorySection { waypoints: points, ..TrajectorySection::default() };
        let radians = section(vec![waypoint(5.0, 0.0, -1.57, 0.35), waypoint(9.0, 40.0, 0.0, -0.5)]);
        let note = radians.radians_note().expect("a note");
        assert!(note.contains("multiply them by 57.3"), "{note}");
        assert_eq!(section(vec![waypoint(5.0, 0.0, -45.0, 20.0), waypoint(9.0, 40.0, 0.0, 3.0)]).radians_note(), None);
        assert_eq!(section(vec![waypoint(5.0, 0.0, 0.0, 0.0)]).radians_note(), None);
        assert_eq!(section(Vec::new()).radians_note(), None);
        assert_eq!(crate::Scenario::builtin("textbook").unwrap().trajectory.radians_note(), None);
    }

    #[test]
    fn passes_through_every_way_point_and_holds_at_the_ends() {
        let points = [waypoint(4.0, 0.0, -90.0, 30.0), waypoint(10.0, 40.0, 0.0, 30.0), waypoint(16.0, 90.0, 0.0, -40.0)];
        let path = path(&points);
        let first = path.at(0.0);
        assert_eq!(first.centre_sigma_m, -0.055);
        assert_eq!((first.theta_deg, first.phi_deg), (-90.0, 5.0));
        assert_eq!(path.at(-1.0), first);
        for w in points {
            let at = path.at(w.time_s);
            assert!((at.centre_sigma_m - w.station_mm * 1e-3).abs() < 1e-12, "{at:?} at {w:?}");
            assert!((at.theta_deg - w.theta_deg).abs() < 1e-12);
            assert!((at.phi_deg - w.phi_deg).abs() < 1e-12);
        }
        assert_eq!(path.at(30.0).centre_sigma_m, 0.09);
        // Smooth: no jump either side of a way-point.
        let (before, after) = (path.at(10.0 - 1e-6), path.at(10.0 + 1e-6));
        assert!((before.centre_sigma_m - after.centre_sigma_m).abs() < 1e-7);
    }

    #[test]
    fn a_flat_stretch_stays_flat() {
        // theta holds at -90 until 4 s, then at 0 from 10 s: no wobble.
        let path = path(&[waypoint(4.0, 0.0, -90.0, 5.0), waypoint(10.0, 40.0, 0.0, 5.0), waypoint(16.0, 60.0, 0.0, 5.0)]);
        for k in 0..=160 {
            let at = path.at(k as f64 * 0.1);
            assert!((at.phi_deg - 5.0).abs() < 1e-12);
            if k <= 40 {
                assert!((at.theta_deg + 90.0).abs() < 1e-12, "{at:?}");
            }
            if k >= 100 {
                assert!(at.theta_deg.abs() < 1e-12, "{at:?}");
            }
        }
    }

    proptest! {
        /// Between two way-points every coordinate stays between their
        /// values (monotone: no overshoot), whatever the way-points.
        #[test]
        fn never_overshoots_between_way_points(
            steps in proptest::collection::vec((0.1f64..10.0, -80.0f64..80.0, -180.0f64..180.0, -60.0f64..60.0), 1..8),
            u in 0.0f64..1.0,
        ) {
            let mut t = 0.0;
            let points: Vec<Waypoint> = steps.iter().map(|&(dt, s, th, ph)| { t += dt; waypoint(t, s, th, ph) }).collect();
            let path = path(&points);
            let knots: Vec<(f64, HeadCoordinates)> = std::iter::once((0.0, start()))
                .chain(points.iter().map(|w| (w.time_s, HeadCoordinates { station_mm: w.station_mm, theta_deg: w.theta_deg, phi_deg: w.phi_deg, anterior_mm: 0.0 })))
                .collect();
            for pair in knots.windows(2) {
                let (t0, a) = pair[0];
                let (t1, b) = pair[1];
                let at = path.at(t0 + u * (t1 - t0));
                for (x, lo, hi) in [
                    (at.centre_sigma_m * 1e3, a.station_mm, b.station_mm),
                    (at.theta_deg, a.theta_deg, b.theta_deg),
                    (at.phi_deg, a.phi_deg, b.phi_deg),
                ] {
                    prop_assert!(x >= lo.min(hi) - 1e-9 && x <= lo.max(hi) + 1e-9, "{x} outside [{lo}, {hi}]");
                }
            }
        }
    }
}
