//! Verification cases V1-V7 of VALIDATION.md (soft-tissue solver table).
//!
//! Each case is a library function that builds its model, runs the solver
//! and returns a serialisable report with its figures and a pass flag; the
//! size is a parameter so the tests run small versions of the very same
//! cases that `carus validate` runs at full size. V5 (CPU against GPU
//! backend) is built with the `gpu` feature and runs where an adapter
//! opens; [`backend_comparison`] says why it did not run otherwise.

pub mod closed_form;
pub mod critical_step;
pub mod cube;
pub mod free_vibration;
pub mod patch;
pub mod refinement;
pub mod uniaxial;
#[cfg(feature = "gpu")]
pub mod v5;

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::baseline::BaselineError;
use crate::error::FemError;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::model::{MaterialRegion, ModelOptions, TledModel};

/// How large a case runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CaseSize {
    /// The sizes VALIDATION.md specifies (`carus validate`).
    Full,
    /// Small meshes and few stretches, seconds in release (the tests).
    Small,
}

/// Why a case could not produce its figures.
#[derive(Debug, Error)]
pub enum ValidationError {
    #[error(transparent)]
    Solver(#[from] FemError),
    #[error("baseline solver: {0}")]
    Baseline(#[from] BaselineError),
    #[error("the {n} x {n} x {n} cube has no node at {point_m:?} m; use an even n so the named points are nodes")]
    MissingNode { point_m: [f64; 3], n: usize },
    #[error("invalid case setting: {0}")]
    InvalidSetting(String),
}

/// VALIDATION.md V3 tissue: shear modulus mu = 1006.711409 Pa.
pub const CUBE_SHEAR_MODULUS_PA: f64 = 1006.711409;
/// VALIDATION.md V3 tissue: bulk modulus kappa = 50 000 Pa (E = 3000 Pa, nu = 0.49).
pub const CUBE_BULK_MODULUS_PA: f64 = 50_000.0;
/// VALIDATION.md V3 tissue: density 1000 kg/m^3.
pub const CUBE_DENSITY_KG_M3: f64 = 1000.0;
/// VALIDATION.md V3: cube edge L = 0.1 m.
pub const CUBE_EDGE_M: f64 = 0.1;

/// A model of one neo-Hookean material with the V3 tissue parameters.
pub fn tissue_model(mesh: &Mesh, options: &ModelOptions) -> Result<Arc<TledModel>, FemError> {
    let region = MaterialRegion {
        element_set: None,
        material: Material::neo_hookean(CUBE_SHEAR_MODULUS_PA, CUBE_BULK_MODULUS_PA),
        density_kg_m3: CUBE_DENSITY_KG_M3,
    };
    Ok(Arc::new(TledModel::new(mesh, &[region], options)?))
}

/// The node at `point_m` (within a millionth of the mesh spacing `h_m`).
pub(crate) fn node_at(mesh: &Mesh, point_m: [f64; 3], h_m: f64) -> Option<u32> {
    mesh.nodes
        .iter()
        .position(|p| (0..3).all(|i| (p[i] - point_m[i]).abs() <= 1e-6 * h_m))
        .map(|n| n as u32)
}

/// Largest Euclidean distance between matching vectors.
pub(crate) fn max_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| distance(*p, *q)).fold(0.0, f64::max)
}

pub(crate) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Nodes on no face of a box mesh (its six face sets).
pub(crate) fn interior_nodes(mesh: &Mesh) -> Vec<u32> {
    let mut on_face = vec![false; mesh.node_count()];
    for set in mesh.node_sets.values() {
        for n in set {
            on_face[*n as usize] = true;
        }
    }
    (0..mesh.node_count() as u32).filter(|n| !on_face[*n as usize]).collect()
}

/// The union of the six face node sets of a box mesh, sorted.
pub(crate) fn boundary_nodes(mesh: &Mesh) -> Vec<u32> {
    let mut nodes: Vec<u32> = mesh.node_sets.values().flatten().copied().collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// V5's outcome in this build.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum BackendComparison {
    /// Both backends ran; the report says whether they agree.
    #[cfg(feature = "gpu")]
    Ran(v5::V5Report),
    /// The comparison failed part way (a device or solver error).
    #[cfg(feature = "gpu")]
    Failed { error: String },
    /// No GPU backend to compare with: not a pass, not a failure.
    NotRun { reason: String },
}

impl BackendComparison {
    /// Some(pass) when the comparison ran or failed, None when it did not run.
    pub fn verdict(&self) -> Option<bool> {
        match self {
            #[cfg(feature = "gpu")]
            BackendComparison::Ran(report) => Some(report.passed),
            #[cfg(feature = "gpu")]
            BackendComparison::Failed { .. } => Some(false),
            BackendComparison::NotRun { .. } => None,
        }
    }

    /// One line with the headline figure or the reason.
    pub fn summary(&self) -> String {
        match self {
            #[cfg(feature = "gpu")]
            BackendComparison::Ran(report) => {
                let worst = report.cases.iter().map(|c| c.max_difference_cpu_f64_m.max(c.max_difference_cpu_f32_m)).fold(0.0, f64::max);
                format!("on {}: largest node difference {:.2e} m (tolerance {:.1e} m)", report.adapter, worst, report.tolerance_m)
            }
            #[cfg(feature = "gpu")]
            BackendComparison::Failed { error } => format!("error: {error}"),
            BackendComparison::NotRun { reason } => format!("not run: {reason}"),
        }
    }
}

/// Runs V5 where this build has a GPU backend and an adapter opens.
pub fn backend_comparison(size: CaseSize) -> BackendComparison {
    #[cfg(feature = "gpu")]
    {
        match v5::run(size) {
            Ok(report) => BackendComparison::Ran(report),
            Err(error @ crate::gpu::GpuError::NoAdapter { .. }) => BackendComparison::NotRun { reason: error.to_string() },
            Err(error) => BackendComparison::Failed { error: error.to_string() },
        }
    }
    #[cfg(not(feature = "gpu"))]
    {
        let _ = size;
        BackendComparison::NotRun { reason: "no GPU backend in this build (build with the `gpu` feature)".to_string() }
    }
}
