//! V2: patch test. An affine displacement u = A X + b is imposed on the
//! boundary of a distorted mesh (interior nodes moved off the grid); once at
//! rest the interior must carry the same affine field, to 1e-6 relative in
//! f64 and 1e-4 in f32 (VALIDATION.md). A homogeneous deformation is an
//! exact solution of the continuum problem, so a consistent element
//! reproduces it on any mesh; the static solution is reached by running to
//! rest with damping.

use serde::Serialize;

use super::cube::CubeElement;
use super::{boundary_nodes, interior_nodes, tissue_model, CaseSize, ValidationError, CUBE_EDGE_M};
use crate::generate::{box_h8, box_t4};
use crate::loads::{BoundaryConditions, ImposedDisplacement, LoadShape};
use crate::mesh::Mesh;
use crate::model::{ModelOptions, Precision, TetFormulation};
use crate::solver::{StepControl, TledSolver};

/// VALIDATION.md V2 tolerance in f64.
pub const TOLERANCE_F64: f64 = 1e-6;
/// VALIDATION.md V2 tolerance in f32.
pub const TOLERANCE_F32: f64 = 1e-4;
/// The affine gradient A: 10 % stretch, shear and compression mixed.
const GRADIENT: [[f64; 3]; 3] = [[0.10, 0.03, -0.02], [0.02, -0.05, 0.04], [-0.03, 0.01, 0.08]];
/// The translation b, m.
const TRANSLATION_M: [f64; 3] = [0.002, -0.001, 0.003];
/// Interior nodes move up to this fraction of the spacing per component.
const DISTORTION: f64 = 0.2;
/// Near-critical damping of the slowest interior mode (about 50-100 rad/s
/// for the 0.1 m V3 tissue block).
const DAMPING_PER_S: f64 = 150.0;
const RAMP_S: f64 = 0.1;
/// Long enough at this damping to settle to round-off.
const END_S: f64 = 2.0;

/// One element type in one precision.
#[derive(Debug, Clone, Serialize)]
pub struct PatchResult {
    pub element: CubeElement,
    pub precision: Precision,
    /// Largest interior node error over the largest exact displacement.
    pub relative_error: f64,
    pub tolerance: f64,
    pub pass: bool,
}

/// The V2 report.
#[derive(Debug, Clone, Serialize)]
pub struct PatchReport {
    pub elements_per_edge: usize,
    pub interior_nodes: usize,
    pub results: Vec<PatchResult>,
    pub pass: bool,
}

/// The exact affine displacement at a reference point.
pub fn affine_displacement(x: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| TRANSLATION_M[i] + (0..3).map(|j| GRADIENT[i][j] * x[j]).sum::<f64>())
}

/// A box mesh with every interior node moved by a fixed pseudo-random
/// offset of up to `DISTORTION` of the spacing per component.
pub fn distorted_box(element: CubeElement, n: usize) -> Mesh {
    let lengths = [CUBE_EDGE_M; 3];
    let mut mesh = match element {
        CubeElement::H8 => box_h8(lengths, [n; 3]),
        CubeElement::T4 | CubeElement::T4anp => box_t4(lengths, [n; 3]),
    };
    let spacing = CUBE_EDGE_M / n as f64;
    for node in interior_nodes(&mesh) {
        let p = &mut mesh.nodes[node as usize];
        for (i, coordinate) in p.iter_mut().enumerate() {
            // A hash-like phase: reproducible and uncorrelated between nodes.
            let phase = ((3 * node as usize + i) as f64 * 12.9898).sin() * 43_758.545;
            *coordinate += DISTORTION * spacing * (2.0 * phase.fract().abs() - 1.0);
        }
    }
    mesh
}

/// The box mesh mapped by a shear, so every element is a parallelepiped
/// (where centre-point and uniform-gradient H8 derivatives coincide).
pub fn sheared_box(element: CubeElement, n: usize) -> Mesh {
    let lengths = [CUBE_EDGE_M; 3];
    let mut mesh = match element {
        CubeElement::H8 => box_h8(lengths, [n; 3]),
        CubeElement::T4 | CubeElement::T4anp => box_t4(lengths, [n; 3]),
    };
    for p in &mut mesh.nodes {
        *p = [p[0] + 0.2 * p[1] + 0.1 * p[2], p[1] + 0.15 * p[2], p[2]];
    }
    mesh
}

/// Runs one patch test on `mesh` (a box mesh with its face sets); returns
/// the relative interior error.
pub fn patch_error(mesh: &Mesh, element: CubeElement, precision: Precision) -> Result<f64, ValidationError> {
    let options = ModelOptions {
        tet_formulation: if element == CubeElement::T4anp { TetFormulation::T4Anp } else { TetFormulation::T4 },
        hourglass_coefficient: super::cube::HOURGLASS_COEFFICIENT,
        damping_per_s: DAMPING_PER_S,
        precision,
        ..ModelOptions::default()
    };
    let model = tissue_model(mesh, &options)?;
    let dt = 0.9 * model.critical_time_step();
    let exact: Vec<[f64; 3]> = mesh.nodes.iter().map(|x| affine_displacement(*x)).collect();
    let displacements = boundary_nodes(mesh)
        .into_iter()
        .map(|node| ImposedDisplacement {
            nodes: vec![node],
            components: exact[node as usize].map(Some),
            shape: LoadShape::RampHold { ramp_s: RAMP_S },
        })
        .collect();
    let bcs = BoundaryConditions { displacements, ..BoundaryConditions::default() };
    let mut solver = TledSolver::new(model, &bcs, dt, StepControl::Refuse)?;
    solver.advance_to(END_S)?;
    let u = solver.displacements();
    let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = interior_nodes(mesh)
        .iter()
        .map(|&node| super::distance(u[node as usize], exact[node as usize]))
        .fold(0.0, f64::max);
    Ok(error / scale)
}

/// Runs V2 for H8, T4 and T4ANP in f64 and f32.
pub fn run(size: CaseSize) -> Result<PatchReport, ValidationError> {
    let n = match size {
        CaseSize::Full => 4,
        CaseSize::Small => 3,
    };
    let mut results = Vec::new();
    for element in CubeElement::ALL {
        for (precision, tolerance) in [(Precision::F64, TOLERANCE_F64), (Precision::F32, TOLERANCE_F32)] {
            let relative_error = patch_error(&distorted_box(element, n), element, precision)?;
            results.push(PatchResult { element, precision, relative_error, tolerance, pass: relative_error <= tolerance });
        }
    }
    let interior = interior_nodes(&distorted_box(CubeElement::H8, n)).len();
    let pass = results.iter().all(|r| r.pass);
    Ok(PatchReport { elements_per_edge: n, interior_nodes: interior, results, pass })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::baseline::{BaselineParameters, BaselineSolver, NodeConstraint};

    #[test]
    fn distortion_moves_only_interior_nodes_and_keeps_elements_valid() {
        for element in [CubeElement::H8, CubeElement::T4] {
            let mesh = distorted_box(element, 3);
            let regular = match element {
                CubeElement::H8 => box_h8([CUBE_EDGE_M; 3], [3; 3]),
                _ => box_t4([CUBE_EDGE_M; 3], [3; 3]),
            };
            let interior = interior_nodes(&mesh);
            assert_eq!(interior.len(), 8);
            for n in 0..mesh.node_count() as u32 {
                let moved = mesh.nodes[n as usize] != regular.nodes[n as usize];
                assert_eq!(moved, interior.contains(&n));
            }
            // The baseline refuses non-positive volumes.
            let params = BaselineParameters {
                shear_modulus_pa: 1.0,
                bulk_modulus_pa: 1.0,
                density_kg_m3: 1.0,
                hourglass_coefficient: 0.0,
                damping_per_s: 0.0,
                dt_s: 1.0,
            };
            BaselineSolver::new(&mesh, params, vec![]).unwrap();
        }
    }

    /// H8, T4 and T4ANP pass the patch test on the randomly distorted mesh.
    #[test]
    fn small_patch_test_passes() {
        let report = run(CaseSize::Small).unwrap();
        assert_eq!(report.results.len(), 6);
        for r in &report.results {
            assert!(r.pass, "{r:?}");
        }
    }

    /// Every element passes on a mesh of parallelepipeds, in f64 and f32.
    #[test]
    fn patch_test_passes_on_sheared_mesh() {
        for element in CubeElement::ALL {
            for (precision, tolerance) in [(Precision::F64, TOLERANCE_F64), (Precision::F32, TOLERANCE_F32)] {
                let error = patch_error(&sheared_box(element, 3), element, precision).unwrap();
                assert!(error <= tolerance, "{element:?} {precision:?}: {error:e}");
            }
        }
    }

    /// The baseline's uniform-gradient H8 passes on the distorted mesh: the
    /// test's mesh and tolerance are attainable by a consistent H8.
    #[test]
    fn uniform_gradient_h8_passes_on_distorted_mesh() {
        let mesh = distorted_box(CubeElement::H8, 3);
        let exact: Vec<[f64; 3]> = mesh.nodes.iter().map(|x| affine_displacement(*x)).collect();
        let constraints = boundary_nodes(&mesh)
            .into_iter()
            .map(|node| NodeConstraint { node, displacement_m: exact[node as usize].map(Some) })
            .collect();
        let params = BaselineParameters {
            shear_modulus_pa: crate::validation::CUBE_SHEAR_MODULUS_PA,
            bulk_modulus_pa: crate::validation::CUBE_BULK_MODULUS_PA,
            density_kg_m3: crate::validation::CUBE_DENSITY_KG_M3,
            hourglass_coefficient: crate::validation::cube::HOURGLASS_COEFFICIENT,
            damping_per_s: DAMPING_PER_S,
            dt_s: 1e-3,
        };
        let mut solver = BaselineSolver::new(&mesh, params, constraints).unwrap();
        let shape = LoadShape::RampHold { ramp_s: RAMP_S };
        for step in 1..=2000 {
            solver.step(shape.value(step as f64 * 1e-3)).unwrap();
        }
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for node in interior_nodes(&mesh) {
            let error = crate::validation::distance(solver.displacements()[node as usize], exact[node as usize]);
            assert!(error / scale <= TOLERANCE_F64, "node {node}: {:e}", error / scale);
        }
    }
}
