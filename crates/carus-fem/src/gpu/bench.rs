//! `carus bench tled --backend gpu`: the CPU bench's figures for a run on a
//! GPU device, plus the memory bandwidth it achieved (bytes the kernels
//! move per element-step, [`super::Traffic`], times element-steps per
//! second) against the device's peak where that is known.

use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::generate::{box_h8, box_t4};
use crate::loads::{BoundaryConditions, ImposedDisplacement, LoadShape};
use crate::material::Material;
use crate::mesh::ElementKind;
use crate::model::{MaterialRegion, ModelOptions, Precision, TledModel};
use crate::solver::StepControl;

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

/// The bench cube: edge 0.1 m, n^3 H8 (or 6 n^3 T4), the V3 tissue
/// (VALIDATION.md: mu = 1006.711409 Pa, kappa = 50 kPa, 1000 kg/m^3,
/// damping 5 1/s), x = 0 fixed, x = L pulled 0.03 m over 1 s; dt is the
/// critical step, as in the CPU bench.
fn cube(element: ElementKind, n: usize) -> Result<(Arc<TledModel>, BoundaryConditions), GpuError> {
    let mesh = match element {
        ElementKind::H8 => box_h8([0.1; 3], [n; 3]),
        ElementKind::T4 => box_t4([0.1; 3], [n; 3]),
    };
    let region = MaterialRegion { element_set: None, material: Material::neo_hookean(1006.711409, 50_000.0), density_kg_m3: 1000.0 };
    let options = ModelOptions { damping_per_s: 5.0, precision: Precision::F32, ..ModelOptions::default() };
    let model = Arc::new(TledModel::new(&mesh, &[region], &options)?);
    let mut bcs = BoundaryConditions::default();
    bcs.fix_nodes(&mesh.node_sets["x0"]);
    bcs.displacements.push(ImposedDisplacement {
        nodes: mesh.node_sets["x1"].clone(),
        components: [Some(0.03), None, None],
        shape: LoadShape::RampHold { ramp_s: 1.0 },
    });
    Ok((model, bcs))
}

/// Times `steps` steps of the n-cube on `gpu`, after a short warm-up;
/// the model upload is not timed, the wait for the GPU to finish is.
pub fn bench_tled(gpu: &GpuDevice, element: ElementKind, n: usize, steps: u64, peak_gbs: Option<f64>) -> Result<GpuBenchReport, GpuError> {
    let (model, bcs) = cube(element, n)?;
    let dt = model.critical_time_step();
    let (elements, nodes) = (model.element_count(), model.node_count());
    let mut solver = GpuSolver::new(gpu, model, &bcs, dt, StepControl::Refuse, GpuOptions::default())?;
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
