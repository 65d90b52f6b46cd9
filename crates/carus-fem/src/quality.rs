//! Mesh quality: the scaled Jacobian of every element (Knupp 2000,
//! "Achieving finite element mesh quality via optimization of the Jacobian
//! matrix norm and associated quantities"; the Verdict library's
//! definitions). 1 is a perfect cube or regular tetrahedron, values <= 0 are
//! inverted or degenerate corners.

use serde::{Deserialize, Serialize};

use crate::error::FemError;
use crate::mesh::{ElementKind, Mesh};
use crate::model::sub;

/// Quality of a whole mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QualityReport {
    /// Scaled Jacobian per element.
    pub scaled_jacobian: Vec<f64>,
    /// Element with the lowest scaled Jacobian, and that value.
    pub worst_element: usize,
    pub worst_scaled_jacobian: f64,
    /// Elements with a non-positive scaled Jacobian (inverted or degenerate).
    pub inverted: Vec<usize>,
    /// The threshold the report was made against, and the elements below it.
    pub threshold: f64,
    pub below_threshold: Vec<usize>,
}

impl QualityReport {
    /// Whether every element is valid and at or above the threshold.
    pub fn passes(&self) -> bool {
        self.inverted.is_empty() && self.below_threshold.is_empty()
    }

    /// An error naming the worst element when the mesh does not pass.
    pub fn require(&self) -> Result<(), FemError> {
        if let Some(&e) = self.inverted.first() {
            return Err(FemError::InvertedElement {
                element: e,
                jacobian: self.scaled_jacobian[e],
            });
        }
        if !self.below_threshold.is_empty() {
            return Err(FemError::InvalidOption {
                option: "min_scaled_jacobian",
                reason: format!(
                    "{} elements are below scaled Jacobian {}; the worst is element {} at {:.4}: remesh there",
                    self.below_threshold.len(),
                    self.threshold,
                    self.worst_element,
                    self.worst_scaled_jacobian
                ),
            });
        }
        Ok(())
    }
}

/// det[e1 e2 e3] / (|e1| |e2| |e3|) of three edge vectors from one corner.
fn corner(e1: [f64; 3], e2: [f64; 3], e3: [f64; 3]) -> f64 {
    let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let l = len(e1) * len(e2) * len(e3);
    if l <= 0.0 {
        return 0.0;
    }
    crate::model::det3(&[e1, e2, e3]) / l
}

/// Scaled Jacobian of one element (minimum over its corners; for T4 scaled
/// by sqrt(2) so the regular tetrahedron gives 1).
pub fn scaled_jacobian(kind: ElementKind, x: &[[f64; 3]]) -> f64 {
    match kind {
        ElementKind::H8 => {
            // Corner a with its three neighbours, ordered right-handed (VTK hex).
            const NB: [[usize; 3]; 8] = [
                [1, 3, 4],
                [2, 0, 5],
                [3, 1, 6],
                [0, 2, 7],
                [7, 5, 0],
                [4, 6, 1],
                [5, 7, 2],
                [6, 4, 3],
            ];
            (0..8)
                .map(|a| {
                    corner(
                        sub(x[NB[a][0]], x[a]),
                        sub(x[NB[a][1]], x[a]),
                        sub(x[NB[a][2]], x[a]),
                    )
                })
                .fold(f64::INFINITY, f64::min)
        }
        ElementKind::T4 => {
            const NB: [[usize; 3]; 4] = [[1, 2, 3], [2, 0, 3], [0, 1, 3], [0, 2, 1]];
            let m = (0..4)
                .map(|a| {
                    corner(
                        sub(x[NB[a][0]], x[a]),
                        sub(x[NB[a][1]], x[a]),
                        sub(x[NB[a][2]], x[a]),
                    )
                })
                .fold(f64::INFINITY, f64::min);
            (m * std::f64::consts::SQRT_2).min(1.0)
        }
    }
}

/// Scaled Jacobian of every element, with the elements at or below zero and
/// those below `min_scaled_jacobian` listed. Errors only on a malformed mesh.
pub fn check_quality(mesh: &Mesh, min_scaled_jacobian: f64) -> Result<QualityReport, FemError> {
    let npe = mesh.kind.nodes_per_element();
    if !mesh.connectivity.len().is_multiple_of(npe) {
        return Err(FemError::RaggedConnectivity {
            len: mesh.connectivity.len(),
            per_element: npe,
        });
    }
    if mesh.element_count() == 0 {
        return Err(FemError::EmptyMesh);
    }
    let mut values = Vec::with_capacity(mesh.element_count());
    for (e, el) in mesh.elements().enumerate() {
        let mut x = [[0.0; 3]; 8];
        for (a, &n) in el.iter().enumerate() {
            x[a] = *mesh.nodes.get(n as usize).ok_or(FemError::NodeOutOfRange {
                element: e,
                node: n,
                node_count: mesh.node_count(),
            })?;
        }
        let q = scaled_jacobian(mesh.kind, &x[..npe]);
        values.push(if q.is_finite() { q } else { 0.0 });
    }
    let (worst_element, worst) = values.iter().enumerate().fold(
        (0, f64::INFINITY),
        |acc, (e, &v)| if v < acc.1 { (e, v) } else { acc },
    );
    Ok(QualityReport {
        inverted: (0..values.len()).filter(|&e| values[e] <= 0.0).collect(),
        below_threshold: (0..values.len())
            .filter(|&e| values[e] > 0.0 && values[e] < min_scaled_jacobian)
            .collect(),
        scaled_jacobian: values,
        worst_element,
        worst_scaled_jacobian: worst,
        threshold: min_scaled_jacobian,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_hex() -> Vec<[f64; 3]> {
        crate::model::H8_CORNERS
            .iter()
            .map(|s| [(s[0] + 1.0) / 2.0, (s[1] + 1.0) / 2.0, (s[2] + 1.0) / 2.0])
            .collect()
    }

    #[test]
    fn perfect_shapes_score_one() {
        assert!((scaled_jacobian(ElementKind::H8, &unit_hex()) - 1.0).abs() < 1e-12);
        let s = 1.0 / 2f64.sqrt();
        let regular = [
            [1.0, 0.0, -s],
            [-1.0, 0.0, -s],
            [0.0, 1.0, s],
            [0.0, -1.0, s],
        ];
        let q = scaled_jacobian(ElementKind::T4, &regular);
        assert!((q.abs() - 1.0).abs() < 1e-9, "{q}");
    }

    #[test]
    fn inverted_element_is_named() {
        let mut nodes = unit_hex();
        nodes.extend(unit_hex().iter().map(|p| [p[0] + 1.0, p[1], p[2]]));
        // Second hex with top and bottom swapped: inverted.
        let mut mesh = Mesh::new(
            ElementKind::H8,
            nodes,
            (0..8).chain([12, 13, 14, 15, 8, 9, 10, 11]).collect(),
        );
        let r = check_quality(&mesh, 0.2).unwrap();
        assert_eq!(r.inverted, vec![1]);
        assert_eq!(r.worst_element, 1);
        assert!(matches!(
            r.require(),
            Err(FemError::InvertedElement { element: 1, .. })
        ));
        mesh.connectivity = (0..16).collect();
        let r = check_quality(&mesh, 0.2).unwrap();
        assert!(r.passes());
        assert!(r.require().is_ok());
    }

    #[test]
    fn flattened_element_is_below_threshold() {
        let mut nodes = unit_hex();
        for p in nodes.iter_mut().skip(4) {
            p[0] += 0.95; // heavy shear
        }
        let mesh = Mesh::new(ElementKind::H8, nodes, (0..8).collect());
        let r = check_quality(&mesh, 0.8).unwrap();
        assert_eq!(r.below_threshold, vec![0]);
        assert!(r.require().is_err());
    }
}
