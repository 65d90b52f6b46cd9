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
use crate::validation::cube::{CubeElement, CubeSetup, CubeVariant, RAMP_S};
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
    /// The time step (the cube's critical step), as the CPU bench reports it.
    pub dt_s: f64,
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

/// The shortest timed run when the bench chooses its own step count. A
/// step on a small mesh takes microseconds on a GPU, a submission's latency
/// is milliseconds, and the clocks take a while to rise: on an H100 the
/// million-element cube read 1.7e9 element-steps/s over 20 steps (12 ms),
/// 2.7e9 over 847 (0.31 s) and 4.1e9 over 4 000 (1 s; docs/PERFORMANCE.md).
pub const MIN_TIMED_S: f64 = 1.0;
/// The most steps a self-sized run times.
const MAX_STEPS: u64 = 100_000;

/// Times `steps` steps of the n-cube on `gpu`, after a short warm-up;
/// the model upload is not timed, the wait for the GPU to finish is. With
/// `min_wall_s`, `steps` is a first try: a run shorter than that is
/// scaled up (to at most 100 000 steps, and no further than half the
/// load's ramp) and timed again from the warmed-up state, and repeated
/// until the runs together last that long; `steps` and `wall_s` are then
/// their totals.
pub fn bench_tled(
    gpu: &GpuDevice,
    element: ElementKind,
    n: usize,
    steps: u64,
    min_wall_s: Option<f64>,
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
    // Every try starts from the same state (restoring it is not timed), so
    // the cube is never driven further than one try's steps.
    let warm = solver.snapshot()?;
    let mut timed = |steps: u64| -> Result<f64, GpuError> {
        solver.restore(&warm)?;
        let start = Instant::now();
        solver.advance_steps(steps)?;
        Ok(start.elapsed().as_secs_f64())
    };
    let mut wall_s = timed(steps)?;
    let mut run = steps;
    if let Some(min_wall_s) = min_wall_s {
        // A run stays in the first half of the load ramp: at the critical
        // step the finest cubes invert near its end (H8 n = 100 at t = 0.92
        // s on an H100). Each try aims a fifth past the mark, since the
        // next run's rate is higher than the last's.
        let most = ((0.5 * RAMP_S / dt) as u64).min(MAX_STEPS).max(run);
        while wall_s < min_wall_s && run < most {
            run = ((1.2 * run as f64 * min_wall_s / wall_s.max(1e-9)).ceil() as u64).clamp(run + 1, most);
            wall_s = timed(run)?;
        }
    }
    // A run that the ramp keeps short is repeated until the time is reached.
    let mut steps = run;
    while min_wall_s.is_some_and(|t| wall_s < t) {
        wall_s += timed(run)?;
        steps += run;
    }
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
        dt_s: dt,
    })
}
