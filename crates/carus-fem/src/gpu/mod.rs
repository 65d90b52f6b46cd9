//! The TLED solver on the GPU (cargo feature `gpu`): wgpu compute shaders
//! in WGSL, running on Vulkan, Metal and DX12 GPUs and on Mesa's lavapipe
//! CPU driver in CI. Same model, boundary conditions and results as the
//! CPU backend (VALIDATION.md V5), in f32. Design: docs/GPU.md.
//!
//! ```no_run
//! # use std::sync::Arc;
//! # use carus_fem::gpu::{open_solver, Backend, GpuOptions};
//! # use carus_fem::{BoundaryConditions, StepControl, TledModel};
//! # fn run(model: Arc<TledModel>, bcs: BoundaryConditions) -> Result<(), carus_fem::gpu::GpuError> {
//! let opened = open_solver(Backend::Auto, model, &bcs, 1e-3, StepControl::Refuse, GpuOptions::default())?;
//! if let Some(notice) = &opened.notice {
//!     eprintln!("{notice}"); // auto fell back to the CPU
//! }
//! let mut solver = opened.solver;
//! solver.advance_steps(1000)?;
//! let u = solver.displacements()?;
//! # Ok(()) }
//! ```
//!
//! A device opened elsewhere (the viewer's) is used with
//! [`GpuDevice::from_device`] and [`GpuSolver::new`].

mod backend;
mod bench;
mod buffers;
mod device;
mod error;
mod kernels;
mod loads;
mod solver;
mod traffic;

pub use backend::{open_solver, Backend, BackendSolver, OpenedSolver};
pub use bench::{bench_tled, GpuBenchReport, MIN_TIMED_S};
pub use device::{AdapterChoice, DeviceError, GpuDevice};
pub use error::{GpuError, LAVAPIPE_HINT};
pub use loads::MAX_LOAD_SHAPES;
pub use solver::{GpuOptions, GpuSolver};
pub use traffic::{known_peak_bandwidth, Traffic};
