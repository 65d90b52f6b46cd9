//! `carus bench tled --backend gpu`: the CPU bench's figures for a run on a
//! GPU device, plus the memory bandwidth it achieved (bytes the kernels
//! move per element-step, [`super::Traffic`], times element-steps per
//! second) against the device's peak where that is known.

use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::loads::BoundaryConditions;
use crate::mesh::ElementKind;
use crate::model::TledModel;
use crate::solver::StepControl;
use crate::validation::cube::{CubeElement, CubeSetup, CubeVariant};
use crate::validation::tissue_model;

use super::device::GpuDevice;
use super::error::GpuError;
use super::kernels::WORKGROUP;
use super::solver::{GpuOptions, GpuSolver};
use super::traffic::known_peak_bandwidth;

/// Sub-steps run before timing (first submissions include driver-side
/// shader compilation on some drivers).
const WARM_UP_STEPS: u64 = 4;

/// The figures of one GPU bench run; the first eight keys are the CPU
/// bench's (issue 2), spelled the same.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GpuBenchReport {
    pub elements: usize,
    pub nodes: usize,
    pub steps: u64,
    pub wall_s: f64,
    pub us_per_element_step: f64,
    pub element_steps_per_s: f64,
    /// GPU invocations of the element kernel per step (elements rounded up
    /// to whole workgroups of 64); the CPU bench reports its threads here.
    pub threads: u64,
    pub backend: String,
    pub adapter: String,
    /// Bytes the kernels read and write per element-step.
    pub bytes_per_element_step: f64,
    pub achieved_bandwidth_gbs: f64,
    /// The device's peak bandwidth, GB/s, from `--peak-gbs` or the table of
    /// known devices; None when neither gives one.
    pub peak_bandwidth_gbs: Option<f64>,
    /// Where the peak comes from.
    pub peak_source: Option<String>,
    pub fraction_of_peak: Option<f64>,
}

/// The CPU bench's cube: VALIDATION.md V3 (free-lateral variant) at size
/// n, dt the critical step.
fn cube(element: ElementKind, n: usize) -> Result<(Arc<TledModel>, BoundaryConditions), GpuError> {
    let element = match element {
        ElementKind::H8 => CubeElement::H8,
        ElementKind::T4 => CubeElement::T4,
    };
    let setup = CubeSetup::miller(n, element, CubeVariant::FreeLateral);
    let mesh = setup.mesh();
    Ok((
        tissue_model(&mesh, &setup.options())?,
        setup.boundary_conditions(&mesh),
    ))
}

/// Times `steps` steps of the n-cube on `gpu`, after a short warm-up;
/// the model upload is not timed, the wait for the GPU to finish is.
pub fn bench_tled(
    gpu: &GpuDevice,
    element: ElementKind,
    n: usize,
    steps: u64,
    peak_gbs: Option<f64>,
) -> Result<GpuBenchReport, GpuError> {
    let (model, bcs) = cube(element, n)?;
    let dt = model.critical_time_step();
    let (elements, nodes) = (model.element_count(), model.node_count());
    let mut solver = GpuSolver::new(
        gpu,
        model,
        &bcs,
        dt,
        StepControl::Refuse,
        GpuOptions::default(),
    )?;
    solver.advance_steps(WARM_UP_STEPS)?;
    let start = Instant::now();
    solver.advance_steps(steps)?;
    let wall_s = start.elapsed().as_secs_f64();
    let element_steps = (elements as u64 * steps) as f64;
    let element_steps_per_s = element_steps / wall_s;
    let bytes_per_element_step = solver.traffic().bytes_per_element_step();
    let achieved_bandwidth_gbs = bytes_per_element_step * element_steps_per_s / 1e9;
    let adapter = gpu.adapter_info().name.clone();
    let (peak_bandwidth_gbs, peak_source) = match peak_gbs {
        Some(p) => (Some(p), Some("--peak-gbs".to_string())),
        None => match known_peak_bandwidth(&adapter) {
            Some((p, source)) => (Some(p), Some(source.to_string())),
            None => (None, None),
        },
    };
    Ok(GpuBenchReport {
        elements,
        nodes,
        steps,
        wall_s,
        us_per_element_step: wall_s * 1e6 / element_steps,
        element_steps_per_s,
        threads: (elements as u64).div_ceil(WORKGROUP as u64) * WORKGROUP as u64,
        backend: "gpu".into(),
        adapter,
        bytes_per_element_step,
        achieved_bandwidth_gbs,
        fraction_of_peak: peak_bandwidth_gbs.map(|p| achieved_bandwidth_gbs / p),
        peak_bandwidth_gbs,
        peak_source,
    })
}
