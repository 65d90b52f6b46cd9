//! Choosing where the solver runs: `cpu`, `gpu`, or `auto` (a real GPU
//! when there is one, else the CPU with a notice for the caller to show).

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::fields::{ElementFields, Energies};
use crate::loads::BoundaryConditions;
use crate::model::TledModel;
use crate::solver::{SolverSnapshot, StepControl, TledSolver};

use super::device::{AdapterChoice, GpuDevice};
use super::error::GpuError;
use super::solver::{GpuOptions, GpuSolver};

/// Which backend runs the TLED step loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// The multi-threaded CPU solver.
    Cpu,
    /// A GPU adapter: a real GPU if present, else a software one such as
    /// lavapipe (correct, but slower than the CPU backend); an error if none.
    Gpu,
    /// A real (non-CPU) GPU when present, else the CPU with a notice.
    #[default]
    Auto,
}

impl Backend {
    pub const fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
            Backend::Auto => "auto",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "cpu" => Ok(Backend::Cpu),
            "gpu" => Ok(Backend::Gpu),
            "auto" => Ok(Backend::Auto),
            other => Err(format!("unknown backend `{other}`: use cpu, gpu or auto")),
        }
    }
}

/// A TLED run on either backend, with the API both share.
pub enum BackendSolver {
    Cpu(Box<TledSolver>),
    Gpu(Box<GpuSolver>),
}

/// A solver and, when `auto` fell back to the CPU, why.
pub struct OpenedSolver {
    pub solver: BackendSolver,
    pub notice: Option<String>,
}

/// Opens a run on the chosen backend. `Gpu` fails with
/// [`GpuError::NoAdapter`] (naming what was tried and the fix) when no
/// adapter is usable; `Auto` then runs on the CPU and says so in `notice`.
pub fn open_solver(
    backend: Backend,
    model: Arc<TledModel>,
    bcs: &BoundaryConditions,
    dt_s: f64,
    control: StepControl,
    options: GpuOptions,
) -> Result<OpenedSolver, GpuError> {
    let cpu = |model, notice| -> Result<OpenedSolver, GpuError> {
        Ok(OpenedSolver {
            solver: BackendSolver::Cpu(Box::new(TledSolver::new(model, bcs, dt_s, control)?)),
            notice,
        })
    };
    match backend {
        Backend::Cpu => cpu(model, None),
        Backend::Gpu => {
            let gpu = GpuDevice::headless(AdapterChoice::BestAvailable)?;
            Ok(OpenedSolver {
                solver: BackendSolver::Gpu(Box::new(GpuSolver::new(
                    &gpu, model, bcs, dt_s, control, options,
                )?)),
                notice: None,
            })
        }
        Backend::Auto => match GpuDevice::headless(AdapterChoice::RealGpuOnly) {
            Ok(gpu) => {
                match GpuSolver::new(&gpu, Arc::clone(&model), bcs, dt_s, control, options) {
                    Ok(s) => Ok(OpenedSolver {
                        solver: BackendSolver::Gpu(Box::new(s)),
                        notice: None,
                    }),
                    // Model errors are the caller's to fix on either backend.
                    Err(GpuError::Solver(e)) => Err(e.into()),
                    Err(e) => cpu(
                        model,
                        Some(format!(
                            "the GPU backend could not run this model ({e}); running on the CPU"
                        )),
                    ),
                }
            }
            Err(e) => cpu(model, Some(format!("{}; running on the CPU", GpuError::from(e)))),
        },
    }
}

impl BackendSolver {
    /// `cpu` or `gpu`.
    pub fn backend(&self) -> Backend {
        match self {
            BackendSolver::Cpu(_) => Backend::Cpu,
            BackendSolver::Gpu(_) => Backend::Gpu,
        }
    }

    /// The GPU adapter's name (None on the CPU).
    pub fn adapter_name(&self) -> Option<String> {
        match self {
            BackendSolver::Cpu(_) => None,
            BackendSolver::Gpu(g) => Some(g.device().adapter_info().name.clone()),
        }
    }

    pub fn model(&self) -> &Arc<TledModel> {
        match self {
            BackendSolver::Cpu(s) => s.model(),
            BackendSolver::Gpu(g) => g.model(),
        }
    }

    pub fn step(&mut self) -> Result<(), GpuError> {
        self.advance_steps(1)
    }

    /// `n` steps of dt (on the GPU, many per submission).
    pub fn advance_steps(&mut self, n: u64) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => (0..n).try_for_each(|_| s.step()).map_err(Into::into),
            BackendSolver::Gpu(g) => g.advance_steps(n),
        }
    }

    pub fn advance_to(&mut self, t_s: f64) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.advance_to(t_s)?),
            BackendSolver::Gpu(g) => g.advance_to(t_s),
        }
    }

    pub fn time_s(&self) -> f64 {
        match self {
            BackendSolver::Cpu(s) => s.time_s(),
            BackendSolver::Gpu(g) => g.time_s(),
        }
    }

    pub fn steps(&self) -> u64 {
        match self {
            BackendSolver::Cpu(s) => s.steps(),
            BackendSolver::Gpu(g) => g.steps(),
        }
    }

    pub fn displacements(&self) -> Result<Vec<[f64; 3]>, GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.displacements()),
            BackendSolver::Gpu(g) => g.displacements(),
        }
    }

    pub fn impose_displacements(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
    ) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.impose_displacements(nodes, displacements_m)?),
            BackendSolver::Gpu(g) => g.impose_displacements(nodes, displacements_m),
        }
    }

    pub fn impose_sliding(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
        normals: &[[f64; 3]],
    ) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.impose_sliding(nodes, displacements_m, normals)?),
            BackendSolver::Gpu(g) => g.impose_sliding(nodes, displacements_m, normals),
        }
    }

    pub fn release_imposed(&mut self) {
        match self {
            BackendSolver::Cpu(s) => s.release_imposed(),
            BackendSolver::Gpu(g) => g.release_imposed(),
        }
    }

    pub fn update_internal_forces(&mut self) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.update_internal_forces()?),
            BackendSolver::Gpu(g) => g.update_internal_forces(),
        }
    }

    pub fn internal_forces(&mut self, nodes: &[u32]) -> Result<Vec<[f64; 3]>, GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.internal_forces(nodes)?),
            BackendSolver::Gpu(g) => g.internal_forces(nodes),
        }
    }

    pub fn reaction_force(&mut self, nodes: &[u32]) -> Result<[f64; 3], GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.reaction_force(nodes)?),
            BackendSolver::Gpu(g) => g.reaction_force(nodes),
        }
    }

    pub fn element_fields(&self) -> Result<ElementFields, GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.element_fields()),
            BackendSolver::Gpu(g) => g.element_fields(),
        }
    }

    pub fn energies(&self) -> Result<Energies, GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.energies()),
            BackendSolver::Gpu(g) => g.energies(),
        }
    }

    pub fn snapshot(&self) -> Result<SolverSnapshot, GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.snapshot()),
            BackendSolver::Gpu(g) => g.snapshot(),
        }
    }

    pub fn restore(&mut self, snap: &SolverSnapshot) -> Result<(), GpuError> {
        match self {
            BackendSolver::Cpu(s) => Ok(s.restore(snap)?),
            BackendSolver::Gpu(g) => g.restore(snap),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backend_names_round_trip() {
        for b in [Backend::Cpu, Backend::Gpu, Backend::Auto] {
            assert_eq!(b.name().parse::<Backend>(), Ok(b));
        }
        assert!("cuda"
            .parse::<Backend>()
            .unwrap_err()
            .contains("cpu, gpu or auto"));
    }
}
