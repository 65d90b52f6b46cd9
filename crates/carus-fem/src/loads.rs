//! Boundary conditions and load shapes.
//!
//! A load shape scales a load over time to a value in [0, 1]. Conditions are
//! applied in this order every step: fixed dofs, imposed displacements,
//! then displacements imposed through the coupling API (the last wins).

use serde::{Deserialize, Serialize};

use crate::error::FemError;

/// Time history of a load, value(t) in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum LoadShape {
    /// Full load from t = 0.
    Step,
    /// Linear rise over the loading period `duration_s`, full load after it
    /// (NiftySim's RAMP over the whole run when duration = run length).
    Ramp { duration_s: f64 },
    /// Linear rise over `ramp_s`, then held (NiftySim's RAMPHOLD; VALIDATION.md V3).
    RampHold { ramp_s: f64 },
    /// Smooth 3-4-5 polynomial 10 s^3 - 15 s^4 + 6 s^5 with s = t / duration:
    /// zero velocity and acceleration at both ends.
    Smooth345 { duration_s: f64 },
}

impl LoadShape {
    /// Load factor at time `t_s`.
    pub fn value(&self, t_s: f64) -> f64 {
        let ramp = |d: f64| {
            if d > 0.0 {
                (t_s / d).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        match *self {
            LoadShape::Step => 1.0,
            LoadShape::Ramp { duration_s } => ramp(duration_s),
            LoadShape::RampHold { ramp_s } => ramp(ramp_s),
            LoadShape::Smooth345 { duration_s } => {
                let s = ramp(duration_s);
                s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
            }
        }
    }

    pub(crate) fn validate(&self) -> Result<(), String> {
        let d = match *self {
            LoadShape::Step => return Ok(()),
            LoadShape::Ramp { duration_s } | LoadShape::Smooth345 { duration_s } => duration_s,
            LoadShape::RampHold { ramp_s } => ramp_s,
        };
        if d.is_finite() && d >= 0.0 {
            Ok(())
        } else {
            Err(format!(
                "load shape duration must be finite and >= 0, got {d} s"
            ))
        }
    }
}

/// Degrees of freedom held at zero displacement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FixedDofs {
    pub nodes: Vec<u32>,
    /// Which of x, y, z are fixed.
    pub components: [bool; 3],
}

/// Displacements imposed on nodes, scaled by a load shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImposedDisplacement {
    pub nodes: Vec<u32>,
    /// Displacement at full load, m; None leaves the component free.
    pub components: [Option<f64>; 3],
    pub shape: LoadShape,
}

/// The same force on each listed node, scaled by a load shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NodalForce {
    pub nodes: Vec<u32>,
    /// Force per node at full load, N.
    pub force_n: [f64; 3],
    pub shape: LoadShape,
}

/// Pressure on surface triangles. A follower load: it acts along the
/// current (deformed) normal on the current area, each triangle giving
/// -p A n / 3 to each of its nodes; positive pressure pushes against the
/// right-hand-rule normal (into the body for outward-facing triangles).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfacePressure {
    pub triangles: Vec<[u32; 3]>,
    pub pressure_pa: f64,
    pub shape: LoadShape,
}

/// A boundary condition's node must exist (the coupling and both backends ask).
pub(crate) fn check_node(what: &'static str, n: u32, nn: usize) -> Result<(), FemError> {
    if (n as usize) < nn {
        Ok(())
    } else {
        Err(FemError::BoundaryNodeOutOfRange {
            what,
            node: n,
            node_count: nn,
        })
    }
}

/// All boundary conditions and loads of a run.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct BoundaryConditions {
    pub fixed: Vec<FixedDofs>,
    pub displacements: Vec<ImposedDisplacement>,
    pub forces: Vec<NodalForce>,
    pub pressures: Vec<SurfacePressure>,
    /// Gravitational acceleration, m/s^2 (acts on the lumped masses).
    pub gravity_m_s2: Option<[f64; 3]>,
}

impl BoundaryConditions {
    /// Fixes all components of the given nodes.
    pub fn fix_nodes(&mut self, nodes: &[u32]) -> &mut Self {
        self.fixed.push(FixedDofs {
            nodes: nodes.to_vec(),
            components: [true; 3],
        });
        self
    }

    /// Refuses what no backend can run on a mesh of `node_count` nodes: a
    /// node that does not exist, a value that is not finite, a load shape
    /// that is not valid. The CPU and GPU backends call it alike, so they
    /// refuse the same conditions with the same errors.
    pub fn validate(&self, node_count: usize) -> Result<(), FemError> {
        let bad = |reason: String| FemError::InvalidBoundaryCondition { reason };
        for f in &self.fixed {
            for &n in &f.nodes {
                check_node("a fixed-dof set", n, node_count)?;
            }
        }
        for d in &self.displacements {
            d.shape.validate().map_err(bad)?;
            for &n in &d.nodes {
                check_node("an imposed displacement", n, node_count)?;
                if d.components.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(bad(format!("imposed displacement of node {n} is not finite")));
                }
            }
        }
        for f in &self.forces {
            f.shape.validate().map_err(bad)?;
            if !f.force_n.iter().all(|v| v.is_finite()) {
                return Err(bad(format!("nodal force {:?} N is not finite", f.force_n)));
            }
            for &n in &f.nodes {
                check_node("a nodal force", n, node_count)?;
            }
        }
        for p in &self.pressures {
            p.shape.validate().map_err(bad)?;
            if !p.pressure_pa.is_finite() {
                return Err(bad(format!("surface pressure {} Pa is not finite", p.pressure_pa)));
            }
            for &n in p.triangles.iter().flatten() {
                check_node("a pressure triangle", n, node_count)?;
            }
        }
        match self.gravity_m_s2 {
            Some(g) if !g.iter().all(|v| v.is_finite()) => Err(bad(format!("gravity {g:?} m/s^2 is not finite"))),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn shapes_at_key_times() {
        assert_eq!(LoadShape::Step.value(0.0), 1.0);
        let r = LoadShape::RampHold { ramp_s: 1.0 };
        assert_eq!(r.value(0.0), 0.0);
        assert_eq!(r.value(0.25), 0.25);
        assert_eq!(r.value(5.0), 1.0);
        assert_eq!(LoadShape::Ramp { duration_s: 2.0 }.value(1.0), 0.5);
        let s = LoadShape::Smooth345 { duration_s: 2.0 };
        assert_eq!(s.value(0.0), 0.0);
        assert_eq!(s.value(1.0), 0.5);
        assert_eq!(s.value(2.0), 1.0);
        assert_eq!(s.value(3.0), 1.0);
        assert!(LoadShape::Ramp { duration_s: -1.0 }.validate().is_err());
    }

    proptest! {
        #[test]
        fn shapes_are_monotone_in_unit_interval(t0 in 0.0f64..3.0, dt in 0.0f64..1.0, d in 0.01f64..2.0) {
            for shape in [LoadShape::Ramp { duration_s: d }, LoadShape::RampHold { ramp_s: d }, LoadShape::Smooth345 { duration_s: d }] {
                let (a, b) = (shape.value(t0), shape.value(t0 + dt));
                prop_assert!((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b));
                prop_assert!(b >= a);
            }
        }

        /// The 3-4-5 polynomial starts and ends with zero slope.
        #[test]
        fn smooth_shape_has_flat_ends(d in 0.1f64..10.0) {
            let s = LoadShape::Smooth345 { duration_s: d };
            let h = 1e-4 * d;
            prop_assert!(s.value(h) / h < 1e-6 / d);
            prop_assert!((1.0 - s.value(d - h)) / h < 1e-6 / d);
        }
    }
}
