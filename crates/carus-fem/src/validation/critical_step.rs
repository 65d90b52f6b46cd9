//! V6: a time step above the critical one. The solver must refuse it with
//! an error naming the critical step, and, when told to sub-step, give the
//! same motion as a run at a stable step (VALIDATION.md).
//!
//! Model: the V3 cube (clamped), its face pulled 0.03 m with a smooth 3-4-5
//! ramp over 1 s (no velocity jump, so no high-frequency ringing whose phase
//! would depend on the step), compared at 1.5 s. The sub-stepped run at 2.5
//! critical steps is compared node by node with a run at half the critical
//! step; both integrate the same dynamics, so they agree to the
//! time-discretisation error, under 0.1 % of the edge.

use serde::Serialize;

use super::cube::{CubeElement, CubeSetup, CubeVariant};
use super::{max_distance, tissue_model, CaseSize, ValidationError, CUBE_EDGE_M};
use crate::error::FemError;
use crate::loads::LoadShape;
use crate::solver::{StepControl, TledSolver};

/// The oversized step, in critical steps.
pub const OVERSIZED_STEP: f64 = 2.5;
/// The stable reference step, at most this many critical steps.
pub const STABLE_STEP: f64 = 0.5;
/// Compared at this time, s (the cube is still moving).
pub const COMPARE_AT_S: f64 = 1.5;
/// Duration of the smooth ramp, s.
const RAMP_S: f64 = 1.0;
/// Sub-stepped and stable runs agree within this fraction of the edge.
pub const TOLERANCE_OF_EDGE: f64 = 1e-3;

/// One element type.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalStepResult {
    pub element: CubeElement,
    pub critical_time_step_s: f64,
    /// The refusal's message (empty if the step was wrongly accepted).
    pub refusal: String,
    /// The refusal names the critical step the model reports.
    pub refusal_names_critical_step: bool,
    pub substeps_per_step: u32,
    /// Largest node difference, sub-stepped against stable, over the edge.
    pub substep_difference_of_edge: f64,
    pub pass: bool,
}

/// The V6 report.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalStepReport {
    pub elements_per_edge: usize,
    pub results: Vec<CriticalStepResult>,
    pub pass: bool,
}

/// Runs V6 for one element type.
pub fn check_element(element: CubeElement, n: usize) -> Result<CriticalStepResult, ValidationError> {
    let setup = CubeSetup::miller(n, element, CubeVariant::Clamped);
    let mesh = setup.mesh();
    let model = tissue_model(&mesh, &setup.options())?;
    let critical = model.critical_time_step();
    let mut bcs = setup.boundary_conditions(&mesh);
    for imposed in &mut bcs.displacements {
        imposed.shape = LoadShape::Smooth345 { duration_s: RAMP_S };
    }
    let oversized = OVERSIZED_STEP * critical;

    let (refusal, refusal_names_critical_step) =
        match TledSolver::new(model.clone(), &bcs, oversized, StepControl::Refuse) {
            Ok(_) => (String::new(), false),
            Err(error) => {
                let names = matches!(error, FemError::TimeStepAboveCritical { critical_s, .. } if critical_s == critical);
                let message = error.to_string();
                let shown = format!("{critical:.6e}");
                (message.clone(), names && message.contains(&shown))
            }
        };

    let mut substepped = TledSolver::new(model.clone(), &bcs, oversized, StepControl::SubStep)?;
    substepped.advance_to(COMPARE_AT_S)?;
    // The stable run: at most half the critical step, ending at exactly the
    // sub-stepped run's time.
    let end = substepped.time_s();
    let stable_steps = (end / (STABLE_STEP * critical)).ceil() as u64;
    let mut stable = TledSolver::new(model, &bcs, end / stable_steps as f64, StepControl::Refuse)?;
    for _ in 0..stable_steps {
        stable.step()?;
    }
    let difference = max_distance(&substepped.displacements(), &stable.displacements());
    let substep_difference_of_edge = difference / CUBE_EDGE_M;
    let substeps_per_step = substepped.substeps_per_step();
    let pass = refusal_names_critical_step && substeps_per_step >= 3 && substep_difference_of_edge <= TOLERANCE_OF_EDGE;
    Ok(CriticalStepResult {
        element,
        critical_time_step_s: critical,
        refusal,
        refusal_names_critical_step,
        substeps_per_step,
        substep_difference_of_edge,
        pass,
    })
}

/// Runs V6 for H8, T4 and T4ANP.
pub fn run(size: CaseSize) -> Result<CriticalStepReport, ValidationError> {
    let n = match size {
        CaseSize::Full => 10,
        CaseSize::Small => 4,
    };
    let results = CubeElement::ALL.iter().map(|&e| check_element(e, n)).collect::<Result<Vec<_>, _>>()?;
    let pass = results.iter().all(|r| r.pass);
    Ok(CriticalStepReport { elements_per_edge: n, results, pass })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_critical_step_case_passes() {
        let report = run(CaseSize::Small).unwrap();
        for r in &report.results {
            assert!(r.pass, "{r:?}");
            assert_eq!(r.substeps_per_step, 3);
        }
    }
}
