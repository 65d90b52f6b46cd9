//! Nodes held through the coupling API (contact with a rigid body), shared
//! by the CPU and GPU backends.
//!
//! A node is held either at a target displacement in all three directions,
//! or only along a unit normal: it then stays on the plane through its
//! target square to the normal and moves freely along that plane under the
//! tissue's own forces. The second is frictionless contact, a Dirichlet
//! condition in the normal direction and a traction-free (Neumann) one in
//! the tangent plane (the partial Dirichlet-Neumann condition; a
//! frictionless contact carries normal traction only, Johnson 1985,
//! "Contact Mechanics", ch. 1).

use serde::{Deserialize, Serialize};

use crate::error::FemError;
use crate::loads::check_node;

/// The held nodes, sorted by node.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CoupledNodes {
    /// Target displacement of every held node, m.
    pub held: Vec<(u32, [f64; 3])>,
    /// Unit normal of the nodes that slide on their plane (a subset of `held`).
    #[serde(default)]
    pub sliding: Vec<(u32, [f64; 3])>,
}

/// Sets `value` for `node` in a list sorted by node.
fn upsert(list: &mut Vec<(u32, [f64; 3])>, node: u32, value: [f64; 3]) {
    match list.binary_search_by_key(&node, |&(m, _)| m) {
        Ok(i) => list[i].1 = value,
        Err(i) => list.insert(i, (node, value)),
    }
}

fn check_lengths(what: &str, nodes: usize, values: usize) -> Result<(), FemError> {
    if nodes == values {
        Ok(())
    } else {
        Err(FemError::InvalidBoundaryCondition {
            reason: format!("{nodes} nodes but {values} {what} given to the coupling"),
        })
    }
}

/// Every node exists and every target displacement is finite.
fn check_targets(nodes: &[u32], displacements_m: &[[f64; 3]], node_count: usize) -> Result<(), FemError> {
    check_lengths("displacements", nodes.len(), displacements_m.len())?;
    for (&n, d) in nodes.iter().zip(displacements_m) {
        check_node("impose_displacements", n, node_count)?;
        if !d.iter().all(|v| v.is_finite()) {
            return Err(FemError::InvalidBoundaryCondition {
                reason: format!("imposed displacement of node {n} is not finite"),
            });
        }
    }
    Ok(())
}

impl CoupledNodes {
    /// Holds `nodes` at `displacements_m` in every direction (a node given
    /// again takes its new value and stops sliding).
    pub fn hold(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
        node_count: usize,
    ) -> Result<(), FemError> {
        check_targets(nodes, displacements_m, node_count)?;
        for (&n, d) in nodes.iter().zip(displacements_m) {
            upsert(&mut self.held, n, *d);
            if let Ok(i) = self.sliding.binary_search_by_key(&n, |&(m, _)| m) {
                self.sliding.remove(i);
            }
        }
        Ok(())
    }

    /// Holds `nodes` on the planes through `displacements_m` square to
    /// `normals` (normalised here), free to slide along them.
    pub fn hold_sliding(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
        normals: &[[f64; 3]],
        node_count: usize,
    ) -> Result<(), FemError> {
        check_targets(nodes, displacements_m, node_count)?;
        check_lengths("normals", nodes.len(), normals.len())?;
        let mut units = Vec::with_capacity(normals.len());
        for (&n, v) in nodes.iter().zip(normals) {
            let length = v.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(length.is_finite() && length > 0.0) {
                return Err(FemError::InvalidBoundaryCondition {
                    reason: format!(
                        "the sliding normal of node {n} is {v:?}: give a finite, non-zero vector"
                    ),
                });
            }
            units.push(v.map(|c| c / length));
        }
        for ((&n, d), u) in nodes.iter().zip(displacements_m).zip(units) {
            upsert(&mut self.held, n, *d);
            upsert(&mut self.sliding, n, u);
        }
        Ok(())
    }

    /// Frees every node.
    pub fn clear(&mut self) {
        self.held.clear();
        self.sliding.clear();
    }

    /// Whether no node is held.
    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }

    /// The sliding normal of a held node, if it slides.
    pub fn normal_of(&self, node: u32) -> Option<[f64; 3]> {
        self.sliding
            .binary_search_by_key(&node, |&(m, _)| m)
            .ok()
            .map(|i| self.sliding[i].1)
    }

    /// The displacement a held node takes after an unconstrained update to
    /// `free`: its target, or for a sliding node `free` moved back onto its
    /// plane along the normal.
    pub fn constrain(target: [f64; 3], normal: Option<[f64; 3]>, free: [f64; 3]) -> [f64; 3] {
        match normal {
            None => target,
            Some(n) => {
                let off: f64 = (0..3).map(|c| (free[c] - target[c]) * n[c]).sum();
                [0, 1, 2].map(|c| free[c] - off * n[c])
            }
        }
    }

    /// Every node of a restored snapshot's lists in range, every target
    /// finite, every sliding normal of unit length (what [`Self::hold`]
    /// and [`Self::hold_sliding`] ensure), and every sliding node also held.
    pub(crate) fn check_restored(&self, node_count: usize) -> Result<(), FemError> {
        for &(n, _) in self.held.iter().chain(&self.sliding) {
            check_node("a snapshot's coupled displacement", n, node_count)?;
        }
        let bad = |what: &str, n: u32, v: [f64; 3]| FemError::InvalidBoundaryCondition {
            reason: format!("a snapshot's {what} of node {n} is {v:?}; the snapshot is damaged"),
        };
        if let Some(&(n, d)) = self.held.iter().find(|(_, d)| !d.iter().all(|v| v.is_finite())) {
            return Err(bad("held displacement", n, d));
        }
        let unit = |v: &[f64; 3]| (v.iter().map(|c| c * c).sum::<f64>().sqrt() - 1.0).abs() <= 1e-9;
        if let Some(&(n, v)) = self.sliding.iter().find(|(_, v)| !unit(v)) {
            return Err(bad("sliding normal (not of unit length)", n, v));
        }
        if let Some(&(n, _)) = self
            .sliding
            .iter()
            .find(|(n, _)| self.held.binary_search_by_key(n, |&(m, _)| m).is_err())
        {
            return Err(FemError::InvalidBoundaryCondition {
                reason: format!("a snapshot's sliding node {n} has no held displacement"),
            });
        }
        Ok(())
    }

}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_full_hold_replaces_a_sliding_one() {
        let mut c = CoupledNodes::default();
        c.hold_sliding(&[3, 1], &[[0.0; 3], [1.0, 0.0, 0.0]], &[[0.0, 0.0, 2.0], [1.0, 0.0, 0.0]], 5)
            .unwrap();
        assert_eq!(c.normal_of(3), Some([0.0, 0.0, 1.0]));
        c.hold(&[3], &[[0.5, 0.0, 0.0]], 5).unwrap();
        assert_eq!(c.normal_of(3), None);
        assert_eq!(c.held, vec![(1, [1.0, 0.0, 0.0]), (3, [0.5, 0.0, 0.0])]);
        assert!(c.check_restored(5).is_ok());
        c.clear();
        assert!(c.is_empty() && c.sliding.is_empty());
    }

    #[test]
    fn bad_holds_are_refused_by_name() {
        let mut c = CoupledNodes::default();
        let e = c.hold_sliding(&[0], &[[0.0; 3]], &[[0.0; 3]], 2).unwrap_err();
        assert!(e.to_string().contains("sliding normal of node 0"), "{e}");
        assert!(c.hold(&[2], &[[0.0; 3]], 2).is_err());
        assert!(c.hold(&[0, 1], &[[0.0; 3]], 2).is_err());
        assert!(c.hold(&[0], &[[f64::NAN, 0.0, 0.0]], 2).is_err());
        assert!(c.is_empty());
    }

    proptest! {
        /// A sliding node ends on its plane, and moves from its free
        /// position only along the normal.
        #[test]
        fn constrain_projects_onto_the_plane(
            t in prop::array::uniform3(-1.0f64..1.0),
            n in prop::array::uniform3(-1.0f64..1.0),
            free in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let length = n.iter().map(|c| c * c).sum::<f64>().sqrt();
            prop_assume!(length > 1e-3);
            let n = n.map(|c| c / length);
            let u = CoupledNodes::constrain(t, Some(n), free);
            let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            prop_assert!(dot(sub(u, t), n).abs() < 1e-12);
            let moved = sub(u, free);
            let along = dot(moved, n);
            prop_assert!(sub(moved, n.map(|c| c * along)).iter().all(|c| c.abs() < 1e-12));
            prop_assert_eq!(CoupledNodes::constrain(t, None, free), t);
        }
    }
}
