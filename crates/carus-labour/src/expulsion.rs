//! The expulsion force: the seed's generator, a sinusoid between a minimum
//! and a maximum magnitude with a set period, directed along the fetal
//! spine from the breech towards the head (-k, CARDINAL_MOVEMENTS.md) or,
//! as the scenario chooses, along a direction fixed in the pelvis.

use glam::DVec3;

use crate::scenario::{ExpulsionDirection, ExpulsionSection, NamedDirection};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expulsion {
    pub min_n: f64,
    pub max_n: f64,
    pub period_s: f64,
    pub direction: ExpulsionDirection,
}

impl Expulsion {
    pub fn new(s: &ExpulsionSection) -> Self {
        Expulsion {
            min_n: s.force_min_n,
            max_n: s.force_max_n,
            period_s: s.period_s,
            direction: s.direction,
        }
    }

    /// Magnitude at time `t`: f_min + (f_max - f_min) (1 - cos(2 pi t / T)) / 2,
    /// starting from the resting minimum.
    pub fn magnitude(&self, t_s: f64) -> f64 {
        let phase = std::f64::consts::TAU * t_s / self.period_s;
        self.min_n + (self.max_n - self.min_n) * 0.5 * (1.0 - phase.cos())
    }

    /// The force at `t` for spine axis `k` (unit, pivot towards the breech).
    pub fn force(&self, t_s: f64, spine: DVec3) -> DVec3 {
        self.magnitude(t_s) * self.push(spine)
    }

    /// The unit direction of the push, pelvis frame.
    fn push(&self, spine: DVec3) -> DVec3 {
        match self.direction {
            ExpulsionDirection::Named(NamedDirection::FetalSpine) => -spine,
            ExpulsionDirection::Named(NamedDirection::InletAxis) => DVec3::NEG_Z,
            ExpulsionDirection::Fixed(v) => DVec3::from_array(v).normalize(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sinusoid_runs_between_its_bounds_along_minus_k() {
        let e = Expulsion {
            min_n: -10.0,
            max_n: 120.0,
            period_s: 8.0,
            direction: ExpulsionDirection::Named(NamedDirection::FetalSpine),
        };
        assert_eq!(e.magnitude(0.0), -10.0);
        assert!((e.magnitude(4.0) - 120.0).abs() < 1e-12);
        assert!((e.magnitude(8.0) + 10.0).abs() < 1e-9);
        assert!((e.magnitude(2.0) - 55.0).abs() < 1e-9);
        let f = e.force(4.0, DVec3::Z);
        assert!((f - DVec3::new(0.0, 0.0, -120.0)).length() < 1e-9);
    }

    #[test]
    fn a_fixed_direction_ignores_the_spine() {
        let along = |direction| Expulsion { min_n: 0.0, max_n: 100.0, period_s: 8.0, direction };
        let spine = DVec3::new(0.6, 0.0, 0.8);
        let f = along(ExpulsionDirection::Named(NamedDirection::InletAxis)).force(4.0, spine);
        assert!((f - DVec3::new(0.0, 0.0, -100.0)).length() < 1e-9);
        let f = along(ExpulsionDirection::Fixed([0.0, 3.0, -4.0])).force(4.0, spine);
        assert!((f - DVec3::new(0.0, 60.0, -80.0)).length() < 1e-9);
        let f = along(ExpulsionDirection::Named(NamedDirection::FetalSpine)).force(4.0, spine);
        assert!((f + 100.0 * spine).length() < 1e-9);
    }
}
