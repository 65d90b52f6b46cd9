//! The TLED run on the GPU: the mutable state in device buffers, many
//! sub-steps recorded into one command encoder per submission, and small
//! transfers for the coupling hooks. Mirrors [`crate::solver::TledSolver`].
//!
//! One sub-step is a fixed sequence of dispatches (each a full barrier in
//! wgpu's usage tracking): [surface pressure], [T4ANP volume shares, nodal
//! dilatation], element forces, node update, [coupled nodes]. The
//! three displacement buffers rotate with the sub-step count (previous,
//! current, next), so no copies are made inside the loop. Per sub-step
//! values (the load-shape values at t_n and t_n+1) are written for the whole
//! submission into one uniform buffer read at a dynamic offset.
//!
//! Failure handling matches the CPU solver: the kernels flag the first
//! sub-step with an inverted element or a runaway node in a 16-byte status
//! buffer, read once per submission. The state at the submission's start is
//! kept in three backup buffers; on a flag it is restored and the good
//! sub-steps are replayed (the kernels are deterministic), so the solver
//! ends at the last good sub-step and names the element or node.

use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::error::FemError;
use crate::fields::{self, ElementFields, Energies};
use crate::kernel::blocks::KernelData;
use crate::kernel::lanes::Real;
use crate::loads::BoundaryConditions;
use crate::model::{KernelModel, TledModel};
use crate::coupling::CoupledNodes;
use crate::solver::{substeps_for, ClockOrigin, SolverSnapshot, StepControl};

use super::buffers::{check_limits, storage, ModelArrays, ModelBuffers, Planned};
use super::device::GpuDevice;
use super::error::GpuError;
use super::kernels::{workgroups, Kernels, PARAMS_BYTES, STEP_BYTES};
use super::loads::{CompiledLoads, MAX_LOAD_SHAPES};
use super::traffic::Traffic;

/// How the solver batches and waits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuOptions {
    /// Most sub-steps recorded into one submission.
    pub max_steps_per_submission: u32,
    /// Submissions are sized from the measured time per sub-step to last
    /// about this long, s (short enough for prompt failure checks and
    /// coupling, long enough that the launch overhead is negligible).
    pub target_submission_s: f64,
    /// Longest wait for one submission or readback before giving up with
    /// [`GpuError::Timeout`] instead of hanging.
    pub wait_timeout: Duration,
}

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions {
            max_steps_per_submission: 512,
            target_submission_s: 0.25,
            wait_timeout: Duration::from_secs(120),
        }
    }
}

/// What the status buffer reported for a submission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Status {
    first_bad_substep: u32,
    element: u32,
    node: u32,
}

const CLEAR_STATUS: [u32; 4] = [u32::MAX; 4];

/// Bind groups for the three rotations of the displacement buffers.
type Rotations = [wgpu::BindGroup; 3];

/// The mutable device buffers of a run.
struct StateBuffers {
    /// Displacements; at sub-step k, current = k % 3, next = (k + 1) % 3, previous = (k + 2) % 3.
    u: [wgpu::Buffer; 3],
    /// Current and previous displacement at the start of a submission, and
    /// the one before them (the third slot, for going back a sub-step).
    backup: [wgpu::Buffer; 3],
    /// Element force copies, then the triangle force copies of surface pressure.
    forces: wgpu::Buffer,
    status: wgpu::Buffer,
    /// T4ANP: J_e V_e / 4 per element and J per node (1-word placeholders otherwise).
    shares: wgpu::Buffer,
    nodal_j: wgpu::Buffer,
    node_loads: wgpu::Buffer,
    triangles: wgpu::Buffer,
    params: wgpu::Buffer,
    steps: wgpu::Buffer,
    coupled: wgpu::Buffer,
    probe_nodes: wgpu::Buffer,
    probed: wgpu::Buffer,
}

struct BindGroups {
    element: Rotations,
    volume_shares: Option<Rotations>,
    nodal_dilatation: Option<wgpu::BindGroup>,
    node: Rotations,
    pressure: Rotations,
    coupled: Rotations,
    probe: wgpu::BindGroup,
}

/// A TLED run on a GPU device. The model is shared with the CPU backend;
/// its arrays are uploaded once, in f32.
pub struct GpuSolver {
    gpu: GpuDevice,
    model: Arc<TledModel>,
    options: GpuOptions,
    loads: CompiledLoads,
    kernels: Kernels,
    model_buffers: ModelBuffers,
    state: StateBuffers,
    groups: BindGroups,
    traffic: Traffic,
    element_count: u32,
    node_count: u32,
    anp: bool,
    slots_at: u32,
    triangle_forces_at: u32,
    step_stride: u64,
    /// The device's max_compute_workgroups_per_dimension.
    max_workgroups: u32,
    dt_s: f64,
    substeps_per_step: u32,
    h_s: f64,
    time_s: f64,
    steps: u64,
    substeps: u64,
    /// Whether the third displacement slot holds the state one sub-step
    /// back: after a committed sub-step, not after a restore (the CPU's rule).
    can_roll_back: bool,
    coupled: CoupledNodes,
    coupled_uploaded: bool,
    probe_nodes: Vec<u32>,
    /// Measured wall time of one sub-step (submit to finish), s.
    substep_wall_s: Option<f64>,
}

fn words(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn vec3s(v: &[f32]) -> Vec<[f64; 3]> {
    v.chunks_exact(3)
        .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64])
        .collect()
}

impl GpuSolver {
    /// A run at rest at t = 0 on `gpu`. Refuses what the CPU solver refuses
    /// (time step above critical unless sub-stepping, bad boundary
    /// conditions), and a model whose buffers exceed the device's limits.
    pub fn new(
        gpu: &GpuDevice,
        model: Arc<TledModel>,
        bcs: &BoundaryConditions,
        dt_s: f64,
        control: StepControl,
        options: GpuOptions,
    ) -> Result<GpuSolver, GpuError> {
        let substeps_per_step = substeps_for(dt_s, model.critical_time_step(), control)?;
        let h_s = dt_s / substeps_per_step as f64;
        let arrays = ModelArrays::new(&model);
        let triangle_forces_at = arrays.force_copy_len as u32;
        let loads = CompiledLoads::new(bcs, model.node_count(), triangle_forces_at)?;
        let limits = gpu.device().limits();
        let step_stride =
            STEP_BYTES.next_multiple_of(limits.min_uniform_buffer_offset_alignment as u64);
        let options = GpuOptions {
            max_steps_per_submission: options.max_steps_per_submission.max(1),
            ..options
        };
        let (ne, nn) = (model.element_count(), model.node_count());
        let force_words = arrays.force_copy_len + 9 * loads.triangle_count();
        let mut planned = arrays.planned();
        planned.extend([
            Planned {
                name: "displacement",
                bytes: 12 * nn as u64,
            },
            Planned {
                name: "element force copy",
                bytes: 4 * force_words as u64,
            },
            Planned {
                name: "boundary condition",
                bytes: 4 * loads.node_loads.len() as u64,
            },
            Planned {
                name: "pressure triangle",
                bytes: 4 * loads.triangles.len().max(1) as u64,
            },
            Planned {
                name: "T4ANP volume share",
                bytes: 4 * ne as u64,
            },
        ]);
        check_limits(gpu, &planned, ne, nn)?;
        let kernels = Kernels::new(gpu, arrays.nodes_per_element, arrays.hourglass, arrays.anp)?;
        let model_buffers = ModelBuffers::upload(gpu, &arrays)?;
        let state = gpu.scoped("allocating the solver state", || {
            let none = wgpu::BufferUsages::empty();
            let zeros = |label: &str, words: usize| storage(gpu, label, &vec![0f32; words], none);
            // Displacements double as vertex data for a viewer on the same device.
            let field =
                |label: &str| storage(gpu, label, &vec![0f32; 3 * nn], wgpu::BufferUsages::VERTEX);
            let uniform = |label: &str, bytes: u64| {
                gpu.device().create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: bytes,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            StateBuffers {
                u: std::array::from_fn(|_| field("displacement")),
                backup: std::array::from_fn(|_| field("displacement backup")),
                forces: zeros("force copies", force_words),
                status: storage(gpu, "status", &CLEAR_STATUS, none),
                shares: zeros("volume shares", if arrays.anp { ne } else { 1 }),
                nodal_j: storage(
                    gpu,
                    "nodal dilatation",
                    &vec![1f32; if arrays.anp { nn } else { 1 }],
                    none,
                ),
                node_loads: storage(gpu, "boundary conditions", &loads.node_loads, none),
                triangles: storage(gpu, "pressure triangles", &loads.triangles, none),
                params: uniform("run parameters", PARAMS_BYTES),
                steps: uniform(
                    "sub-step records",
                    step_stride * options.max_steps_per_submission as u64,
                ),
                coupled: storage::<u32>(gpu, "coupled nodes", &[], none),
                probe_nodes: storage::<u32>(gpu, "probed nodes", &[], none),
                probed: storage::<f32>(gpu, "probed forces", &[], none),
            }
        })?;
        let traffic = Traffic::new(&arrays, &loads);
        let solver = GpuSolver {
            gpu: gpu.clone(),
            groups: Self::bind_groups(gpu, &kernels, &model_buffers, &state)?,
            model,
            options,
            loads,
            kernels,
            model_buffers,
            state,
            traffic,
            element_count: arrays.element_count,
            node_count: arrays.node_count,
            anp: arrays.anp,
            slots_at: arrays.node_count + 1,
            triangle_forces_at,
            step_stride,
            max_workgroups: limits.max_compute_workgroups_per_dimension,
            dt_s,
            substeps_per_step,
            h_s,
            time_s: 0.0,
            steps: 0,
            substeps: 0,
            can_roll_back: false,
            coupled: CoupledNodes::default(),
            coupled_uploaded: true,
            probe_nodes: Vec::new(),
            substep_wall_s: None,
        };
        solver.write_params();
        Ok(solver)
    }

    fn bind_groups(
        gpu: &GpuDevice,
        k: &Kernels,
        m: &ModelBuffers,
        s: &StateBuffers,
    ) -> Result<BindGroups, GpuError> {
        Ok(gpu.scoped("binding the solver buffers", || {
            let bind = |kernel: &super::kernels::Kernel, storage: &[(u32, &wgpu::Buffer)]| {
                let mut entries = vec![
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: s.params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &s.steps,
                            offset: 0,
                            size: std::num::NonZeroU64::new(STEP_BYTES),
                        }),
                    },
                ];
                entries.extend(
                    storage
                        .iter()
                        .map(|&(binding, buffer)| wgpu::BindGroupEntry {
                            binding,
                            resource: buffer.as_entire_binding(),
                        }),
                );
                gpu.device().create_bind_group(&wgpu::BindGroupDescriptor {
                    label: None,
                    layout: &kernel.layout,
                    entries: &entries,
                })
            };
            let anp = k.volume_shares.is_some();
            let extra = if anp {
                &s.nodal_j
            } else {
                &m.hourglass_vectors
            };
            let rot = |r: usize| (&s.u[r % 3], &s.u[(r + 1) % 3], &s.u[(r + 2) % 3]);
            BindGroups {
                element: std::array::from_fn(|r| {
                    let (curr, _, _) = rot(r);
                    bind(
                        &k.element,
                        &[
                            (2, &m.connectivity),
                            (3, &m.shape_derivatives),
                            (4, &m.weight),
                            (5, &m.coefficients),
                            (6, extra),
                            (7, curr),
                            (8, &s.forces),
                            (9, &s.status),
                        ],
                    )
                }),
                volume_shares: k.volume_shares.as_ref().map(|vs| {
                    std::array::from_fn(|r| {
                        let (curr, _, _) = rot(r);
                        bind(
                            vs,
                            &[
                                (2, &m.connectivity),
                                (3, &m.shape_derivatives),
                                (4, &m.quarter_volume),
                                (5, curr),
                                (6, &s.shares),
                                (7, &s.status),
                            ],
                        )
                    })
                }),
                nodal_dilatation: k.nodal_dilatation.as_ref().map(|nd| {
                    bind(
                        nd,
                        &[
                            (4, &m.inv_nodal_volume),
                            (6, &s.shares),
                            (8, &m.node_table),
                            (9, &s.nodal_j),
                        ],
                    )
                }),
                node: std::array::from_fn(|r| {
                    let (curr, next, prev) = rot(r);
                    bind(
                        &k.node,
                        &[
                            (2, &m.node_table),
                            (3, &m.node_mass),
                            (4, &s.node_loads),
                            (5, &s.forces),
                            (6, prev),
                            (7, curr),
                            (8, next),
                            (9, &s.status),
                        ],
                    )
                }),
                pressure: std::array::from_fn(|r| {
                    let (curr, _, _) = rot(r);
                    bind(
                        &k.pressure,
                        &[
                            (2, &s.triangles),
                            (3, &m.reference),
                            (4, curr),
                            (5, &s.forces),
                        ],
                    )
                }),
                coupled: std::array::from_fn(|r| {
                    let (_, next, _) = rot(r);
                    bind(&k.coupled, &[(2, &s.coupled), (7, next)])
                }),
                probe: bind(
                    &k.probe,
                    &[
                        (2, &s.probe_nodes),
                        (5, &s.forces),
                        (6, &m.node_table),
                        (8, &s.probed),
                    ],
                ),
            }
        })?)
    }

    /// Writes the run parameters (after a change of the coupled or probed node lists).
    fn write_params(&self) {
        let it = |v: f64| (v as f32).to_bits();
        let h = self.h_s;
        let half = 0.5 * self.model.options().damping_per_s * h;
        let g = self.loads.gravity_m_s2;
        let words: [u32; 16] = [
            self.element_count,
            self.node_count,
            self.loads.triangle_count() as u32,
            self.coupled.held.len() as u32,
            self.probe_nodes.len() as u32,
            self.slots_at,
            self.triangle_forces_at,
            0,
            it(g[0]),
            it(g[1]),
            it(g[2]),
            it(h * h),
            it(1.0 - half),
            it(1.0 / (1.0 + half)),
            // A displacement a hundred times the body's size is a runaway (as on the CPU).
            it(100.0 * self.model.size_m()),
            0,
        ];
        self.gpu
            .queue()
            .write_buffer(&self.state.params, 0, bytemuck::cast_slice(&words));
    }

    /// The per-sub-step records of a submission starting at sub-step `k0`.
    fn write_step_records(&self, k0: u64, n: u32) {
        let stride = self.step_stride as usize;
        let mut bytes = vec![0u8; stride * n as usize];
        for i in 0..n as u64 {
            let k = k0 + i;
            let t = if i == 0 {
                self.time_s
            } else {
                k as f64 * self.h_s
            };
            let now = self.loads.shape_values(t);
            let next = self.loads.shape_values((k + 1) as f64 * self.h_s);
            let record = &mut bytes[i as usize * stride..];
            record[..4].copy_from_slice(&(i as u32).to_le_bytes());
            let values: Vec<u8> = now
                .iter()
                .chain(&next)
                .flat_map(|v| v.to_le_bytes())
                .collect();
            record[16..16 + 8 * MAX_LOAD_SHAPES].copy_from_slice(&values);
        }
        self.gpu.queue().write_buffer(&self.state.steps, 0, &bytes);
    }

    fn dispatch(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        kernel: &super::kernels::Kernel,
        group: &wgpu::BindGroup,
        offset: u32,
        count: u32,
    ) {
        let (x, y) = workgroups(count, self.max_workgroups);
        pass.set_pipeline(&kernel.pipeline);
        pass.set_bind_group(0, group, &[offset]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// The internal-force stage (T4ANP passes, element kernel) at rotation `r`.
    fn encode_forces(&self, pass: &mut wgpu::ComputePass<'_>, r: usize, offset: u32) {
        if let (Some(vs), Some(vsg), Some(nd), Some(ndg)) = (
            &self.kernels.volume_shares,
            &self.groups.volume_shares,
            &self.kernels.nodal_dilatation,
            &self.groups.nodal_dilatation,
        ) {
            self.dispatch(pass, vs, &vsg[r], offset, self.element_count);
            self.dispatch(pass, nd, ndg, offset, self.node_count);
        }
        self.dispatch(
            pass,
            &self.kernels.element,
            &self.groups.element[r],
            offset,
            self.element_count,
        );
    }

    /// Records `n` sub-steps from sub-step `k0` into one compute pass.
    fn encode_substeps(&self, encoder: &mut wgpu::CommandEncoder, k0: u64, n: u32) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tled sub-steps"),
            timestamp_writes: None,
        });
        let triangles = self.loads.triangle_count() as u32;
        for i in 0..n {
            let r = ((k0 + i as u64) % 3) as usize;
            let offset = (i as u64 * self.step_stride) as u32;
            if triangles > 0 {
                self.dispatch(
                    &mut pass,
                    &self.kernels.pressure,
                    &self.groups.pressure[r],
                    offset,
                    triangles,
                );
            }
            self.encode_forces(&mut pass, r, offset);
            self.dispatch(
                &mut pass,
                &self.kernels.node,
                &self.groups.node[r],
                offset,
                self.node_count,
            );
            if !self.coupled.is_empty() {
                self.dispatch(
                    &mut pass,
                    &self.kernels.coupled,
                    &self.groups.coupled[r],
                    offset,
                    self.coupled.held.len() as u32,
                );
            }
        }
    }

    /// Rotation slots (current, previous) at sub-step k.
    fn current_slots(k: u64) -> (usize, usize) {
        ((k % 3) as usize, ((k + 2) % 3) as usize)
    }

    /// Uploads the coupled nodes if they changed: only those nodes travel.
    fn upload_coupled(&mut self) -> Result<(), GpuError> {
        if self.coupled_uploaded {
            return Ok(());
        }
        // [node, target xyz, normal xyz (zero: held in every direction), unused].
        let records: Vec<u32> = self
            .coupled
            .held
            .iter()
            .flat_map(|&(n, u)| {
                let normal = self.coupled.normal_of(n).unwrap_or([0.0; 3]);
                let bits = |v: f64| (v as f32).to_bits();
                [
                    n,
                    bits(u[0]),
                    bits(u[1]),
                    bits(u[2]),
                    bits(normal[0]),
                    bits(normal[1]),
                    bits(normal[2]),
                    0,
                ]
            })
            .collect();
        let bytes = 4 * records.len() as u64;
        if bytes > self.state.coupled.size() {
            self.state.coupled = self.gpu.scoped("growing the coupled-node buffer", || {
                storage::<u32>(
                    &self.gpu,
                    "coupled nodes",
                    &vec![0; records.len().next_power_of_two()],
                    wgpu::BufferUsages::empty(),
                )
            })?;
            self.groups =
                Self::bind_groups(&self.gpu, &self.kernels, &self.model_buffers, &self.state)?;
        }
        if !records.is_empty() {
            self.gpu
                .queue()
                .write_buffer(&self.state.coupled, 0, bytemuck::cast_slice(&records));
        }
        self.write_params();
        self.coupled_uploaded = true;
        Ok(())
    }

    fn read_status(&self) -> Result<Status, GpuError> {
        let bytes = self.gpu.read_buffer(
            &self.state.status,
            0,
            16,
            "reading the step status",
            self.options.wait_timeout,
        )?;
        let w: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        Ok(Status {
            first_bad_substep: w[0],
            element: w[1],
            node: w[2],
        })
    }

    /// Submits `n` sub-steps from the current state and waits for them;
    /// returns the status flags (the counters are not advanced here).
    fn submit_substeps(&mut self, n: u32, backup: bool) -> Result<Status, GpuError> {
        self.upload_coupled()?;
        let k0 = self.substeps;
        self.write_step_records(k0, n);
        self.gpu
            .queue()
            .write_buffer(&self.state.status, 0, bytemuck::cast_slice(&CLEAR_STATUS));
        let started = Instant::now();
        self.gpu.scoped("recording the TLED steps", || {
            let mut encoder =
                self.gpu
                    .device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("tled steps"),
                    });
            if backup {
                let bytes = self.state.u[0].size();
                for (slot, backup) in Self::rotation(k0).into_iter().zip(&self.state.backup) {
                    encoder.copy_buffer_to_buffer(&self.state.u[slot], 0, backup, 0, bytes);
                }
            }
            self.encode_substeps(&mut encoder, k0, n);
            self.gpu.queue().submit([encoder.finish()]);
        })?;
        self.gpu
            .wait(None, "running the TLED steps", self.options.wait_timeout)?;
        let status = self.read_status()?;
        self.substep_wall_s = Some(started.elapsed().as_secs_f64() / n as f64);
        Ok(status)
    }

    /// The slots of sub-step `k`: current, previous, and the one before
    /// (the slot the sub-step writes next into).
    fn rotation(k: u64) -> [usize; 3] {
        let (curr, prev) = Self::current_slots(k);
        [curr, prev, ((k + 1) % 3) as usize]
    }

    /// Puts the submission-start state back into the rotation of sub-step `k0`.
    fn restore_backup(&self, k0: u64) -> Result<(), GpuError> {
        self.gpu.scoped("restoring the last good state", || {
            let mut encoder =
                self.gpu
                    .device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("tled restore"),
                    });
            let bytes = self.state.u[0].size();
            for (backup, slot) in self.state.backup.iter().zip(Self::rotation(k0)) {
                encoder.copy_buffer_to_buffer(backup, 0, &self.state.u[slot], 0, bytes);
            }
            self.gpu.queue().submit([encoder.finish()]);
        })?;
        Ok(self
            .gpu
            .wait(None, "restoring the last good state", self.options.wait_timeout)?)
    }

    /// Moves the counters to sub-step `k` (forwards or back).
    fn set_substeps(&mut self, k: u64) {
        let sps = self.substeps_per_step as u64;
        let (before, after) = (self.substeps / sps, k / sps);
        self.steps = (self.steps as i64 + after as i64 - before as i64) as u64;
        self.substeps = k;
        self.time_s = k as f64 * self.h_s;
    }

    fn commit(&mut self, n: u32) {
        self.set_substeps(self.substeps + n as u64);
    }

    /// Back to the submission that started at `start` (its counters), and
    /// `n` of its sub-steps replayed (the kernels are deterministic).
    fn replay(&mut self, start: (u64, f64, u64), n: u32) -> Result<(), GpuError> {
        (self.substeps, self.time_s, self.steps) = start;
        self.restore_backup(self.substeps)?;
        if n > 0 {
            self.submit_substeps(n, false)?;
            self.commit(n);
        }
        Ok(())
    }

    /// Runs `n` sub-steps in submissions sized to the measured speed.
    fn run_substeps(&mut self, mut n: u64) -> Result<(), GpuError> {
        while n > 0 {
            let fitted = match self.substep_wall_s {
                Some(s) if s > 0.0 => {
                    (self.options.target_submission_s / s).clamp(1.0, u32::MAX as f64) as u64
                }
                _ => 4,
            };
            let batch = n
                .min(fitted)
                .min(self.options.max_steps_per_submission as u64) as u32;
            let status = self.submit_substeps(batch, true)?;
            if status.first_bad_substep != u32::MAX {
                return Err(self.recover(status.first_bad_substep));
            }
            self.commit(batch);
            self.can_roll_back = true;
            n -= batch as u64;
        }
        Ok(())
    }

    /// Rewinds to the submission's start, replays the good sub-steps and
    /// names the element or node of the first bad one, with the CPU's
    /// semantics: the state kept is the last good sub-step's, one before
    /// the state that held an inverted element.
    fn recover(&mut self, good: u32) -> GpuError {
        let start = (self.substeps, self.time_s, self.steps);
        let could_roll_back = self.can_roll_back;
        let attempt = (|| -> Result<GpuError, GpuError> {
            self.replay(start, good)?;
            // Run alone, the failing sub-step names its element or node.
            let status = self.submit_substeps(1, false)?;
            self.replay(start, good)?;
            let t = self.time_s;
            if status.element != u32::MAX {
                let element = status.element as usize;
                let jacobian = self.element_fields()?.jacobian[element];
                // The state at t made the bad element: go back to the
                // sub-step before, whose elements were all checked.
                if good > 0 {
                    self.replay(start, good - 1)?;
                } else if could_roll_back {
                    self.set_substeps(self.substeps - 1);
                }
                self.can_roll_back = false;
                if jacobian.is_finite() {
                    return Ok(FemError::ElementInvertedDuringRun {
                        element,
                        jacobian,
                        time_s: t,
                    }
                    .into());
                }
                return Ok(FemError::Diverged {
                    time_s: t,
                    last_good_time_s: self.time_s,
                    what: format!("element {element} has a non-finite deformation"),
                }
                .into());
            }
            Ok(FemError::Diverged {
                time_s: t + self.h_s,
                last_good_time_s: t,
                what: format!(
                    "node {} displacement is non-finite or beyond 100 x the model size",
                    status.node
                ),
            }
            .into())
        })();
        attempt.unwrap_or_else(|e| e)
    }

    /// Advances by one dt (all of its sub-steps), in one submission.
    pub fn step(&mut self) -> Result<(), GpuError> {
        self.advance_steps(1)
    }

    /// Advances by `n` steps of dt, many sub-steps per submission, with no
    /// readback but a 16-byte status word per submission.
    pub fn advance_steps(&mut self, n: u64) -> Result<(), GpuError> {
        self.run_substeps(n * self.substeps_per_step as u64)
    }

    /// Steps until the time reaches `t_s` (within half a step).
    pub fn advance_to(&mut self, t_s: f64) -> Result<(), GpuError> {
        crate::solver::check_end_time(t_s)?;
        let (mut k, mut t, mut n) = (self.substeps, self.time_s, 0u64);
        while t + 0.5 * self.dt_s < t_s {
            k += self.substeps_per_step as u64;
            t = k as f64 * self.h_s;
            n += 1;
        }
        self.advance_steps(n)
    }

    pub fn model(&self) -> &Arc<TledModel> {
        &self.model
    }

    pub fn device(&self) -> &GpuDevice {
        &self.gpu
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    pub fn substep_s(&self) -> f64 {
        self.h_s
    }

    pub fn substeps_per_step(&self) -> u32 {
        self.substeps_per_step
    }

    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn substeps(&self) -> u64 {
        self.substeps
    }

    /// Bytes the kernels move per element and sub-step (for the bench).
    pub fn traffic(&self) -> &Traffic {
        &self.traffic
    }

    /// The buffer holding the current displacements (xyz f32 per node,
    /// usable as a vertex buffer on the same device). It changes with
    /// every sub-step: ask again after stepping.
    pub fn displacement_buffer(&self) -> &wgpu::Buffer {
        &self.state.u[Self::current_slots(self.substeps).0]
    }

    /// Reference coordinates, xyz f32 per node (usable as a vertex buffer).
    pub fn reference_buffer(&self) -> &wgpu::Buffer {
        &self.model_buffers.reference
    }

    fn read_slot(&self, slot: usize, during: &'static str) -> Result<Vec<f32>, GpuError> {
        let bytes = self.state.u[slot].size();
        Ok(words(&self.gpu.read_buffer(
            &self.state.u[slot],
            0,
            bytes,
            during,
            self.options.wait_timeout,
        )?))
    }

    /// Current displacement of every node, m (reads the whole field back:
    /// for output every N steps, not every step).
    pub fn displacements(&self) -> Result<Vec<[f64; 3]>, GpuError> {
        Ok(vec3s(&self.read_slot(
            Self::current_slots(self.substeps).0,
            "reading the displacements back",
        )?))
    }

    /// Holds the given displacements on those nodes from the next sub-step
    /// on, until [`Self::release_imposed`]; only these nodes are uploaded.
    pub fn impose_displacements(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
    ) -> Result<(), GpuError> {
        self.coupled
            .hold(nodes, displacements_m, self.node_count as usize)?;
        self.coupled_uploaded = false;
        Ok(())
    }

    /// Holds the given nodes on the planes through the given displacements
    /// square to `normals`, free to slide along them (as
    /// [`crate::TledSolver::impose_sliding`]); only these nodes are uploaded.
    pub fn impose_sliding(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
        normals: &[[f64; 3]],
    ) -> Result<(), GpuError> {
        self.coupled
            .hold_sliding(nodes, displacements_m, normals, self.node_count as usize)?;
        self.coupled_uploaded = false;
        Ok(())
    }

    /// Frees every node held by [`Self::impose_displacements`].
    pub fn release_imposed(&mut self) {
        self.coupled.clear();
        self.coupled_uploaded = false;
    }

    /// Nodes currently held through the coupling API.
    pub fn imposed(&self) -> &CoupledNodes {
        &self.coupled
    }

    /// Recomputes the internal forces at the current displacement (the step
    /// computes them at the start of each sub-step, one sub-step behind).
    pub fn update_internal_forces(&mut self) -> Result<(), GpuError> {
        let k = self.substeps;
        self.write_step_records(k, 1);
        self.gpu
            .queue()
            .write_buffer(&self.state.status, 0, bytemuck::cast_slice(&CLEAR_STATUS));
        self.gpu.scoped("evaluating the internal forces", || {
            let mut encoder =
                self.gpu
                    .device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("tled forces"),
                    });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("tled forces"),
                    timestamp_writes: None,
                });
                self.encode_forces(&mut pass, Self::current_slots(k).0, 0);
            }
            self.gpu.queue().submit([encoder.finish()]);
        })?;
        self.gpu
            .wait(None, "evaluating the internal forces", self.options.wait_timeout)?;
        let status = self.read_status()?;
        if status.element != u32::MAX {
            let element = status.element as usize;
            let jacobian = self.element_fields()?.jacobian[element];
            return Err(FemError::ElementInvertedDuringRun {
                element,
                jacobian,
                time_s: self.time_s,
            }
            .into());
        }
        Ok(())
    }

    /// Internal nodal forces F(u) at the given nodes, N (the force needed to
    /// hold them), at the displacement of the last force evaluation. A
    /// small kernel gathers them on the GPU: 4 bytes up and 12 bytes down
    /// per node.
    pub fn internal_forces(&mut self, nodes: &[u32]) -> Result<Vec<[f64; 3]>, GpuError> {
        if let Some(&n) = nodes.iter().find(|&&n| n >= self.node_count) {
            return Err(FemError::BoundaryNodeOutOfRange {
                what: "internal_forces",
                node: n,
                node_count: self.node_count as usize,
            }
            .into());
        }
        if nodes.is_empty() {
            return Ok(Vec::new());
        }
        if self.probe_nodes != nodes {
            let bytes = 4 * nodes.len() as u64;
            if bytes > self.state.probe_nodes.size() {
                let capacity = nodes.len().next_power_of_two();
                let (probe_nodes, probed) = self.gpu.scoped("growing the probe buffers", || {
                    let none = wgpu::BufferUsages::empty();
                    (
                        storage::<u32>(&self.gpu, "probed nodes", &vec![0; capacity], none),
                        storage::<f32>(&self.gpu, "probed forces", &vec![0.0; 3 * capacity], none),
                    )
                })?;
                self.state.probe_nodes = probe_nodes;
                self.state.probed = probed;
                self.groups =
                    Self::bind_groups(&self.gpu, &self.kernels, &self.model_buffers, &self.state)?;
            }
            self.gpu
                .queue()
                .write_buffer(&self.state.probe_nodes, 0, bytemuck::cast_slice(nodes));
            self.probe_nodes = nodes.to_vec();
            self.write_params();
        }
        self.gpu.scoped("gathering the probed forces", || {
            let mut encoder =
                self.gpu
                    .device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("tled probe"),
                    });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("tled probe"),
                    timestamp_writes: None,
                });
                self.dispatch(
                    &mut pass,
                    &self.kernels.probe,
                    &self.groups.probe,
                    0,
                    nodes.len() as u32,
                );
            }
            self.gpu.queue().submit([encoder.finish()]);
        })?;
        let bytes = self.gpu.read_buffer(
            &self.state.probed,
            0,
            12 * nodes.len() as u64,
            "reading the probed forces",
            self.options.wait_timeout,
        )?;
        Ok(vec3s(&words(&bytes)))
    }

    /// Sum of the internal forces over a node set, N.
    pub fn reaction_force(&mut self, nodes: &[u32]) -> Result<[f64; 3], GpuError> {
        let f = self.internal_forces(nodes)?;
        Ok(f.iter().fold([0.0; 3], |acc, v| {
            [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]
        }))
    }

    /// Von Mises stress, maximum principal stretch and J per element,
    /// computed by the CPU fields code from the downloaded displacements.
    pub fn element_fields(&self) -> Result<ElementFields, GpuError> {
        let u = self.read_slot(
            Self::current_slots(self.substeps).0,
            "reading the displacements back",
        )?;
        let anp = self.anp;
        Ok(match self.model.kernel() {
            KernelModel::F32(k) => fields::evaluate(k, anp, &u).0,
            KernelModel::F64(k) => fields::evaluate(k, anp, &widen(&u)).0,
        })
    }

    /// Kinetic, strain and hourglass energies (downloads both displacement fields).
    pub fn energies(&self) -> Result<Energies, GpuError> {
        let (curr, prev) = Self::current_slots(self.substeps);
        let u = self.read_slot(curr, "reading the displacements back")?;
        let u_prev = self.read_slot(prev, "reading the displacements back")?;
        fn energies<T: Real>(
            k: &KernelData<T>,
            anp: bool,
            u: &[T],
            u_prev: &[T],
            h: f64,
        ) -> Energies {
            let (_, strain_j, hourglass_j) = fields::evaluate(k, anp, u);
            Energies {
                kinetic_j: fields::kinetic_energy(k, u, u_prev, h),
                strain_j,
                hourglass_j,
            }
        }
        Ok(match self.model.kernel() {
            KernelModel::F32(k) => energies(k, self.anp, &u, &u_prev, self.h_s),
            KernelModel::F64(k) => energies(k, self.anp, &widen(&u), &widen(&u_prev), self.h_s),
        })
    }

    /// A copy of the whole mutable state (downloaded).
    pub fn snapshot(&self) -> Result<SolverSnapshot, GpuError> {
        let (curr, prev) = Self::current_slots(self.substeps);
        Ok(SolverSnapshot {
            time_s: self.time_s,
            steps: self.steps,
            substeps: self.substeps,
            displacements_m: vec3s(&self.read_slot(curr, "reading the state back")?),
            previous_displacements_m: vec3s(&self.read_slot(prev, "reading the state back")?),
            coupled: self.coupled.held.clone(),
            sliding: self.coupled.sliding.clone(),
            clock: ClockOrigin::default(),
            substep_s: Some(self.h_s),
        })
    }

    /// Puts the solver into a snapshot's state (uploads both displacement fields).
    pub fn restore(&mut self, snap: &SolverSnapshot) -> Result<(), GpuError> {
        let nn = self.node_count as usize;
        for len in [
            snap.displacements_m.len(),
            snap.previous_displacements_m.len(),
        ] {
            if len != nn {
                return Err(FemError::SnapshotMismatch {
                    got: len,
                    expected: nn,
                }
                .into());
            }
        }
        if snap.clock != ClockOrigin::default() {
            return Err(FemError::InvalidOption {
                option: "snapshot",
                reason: "it was taken after a change of step (TledSolver::set_step), which this backend does not make; restore it on the CPU solver".into(),
            }
            .into());
        }
        snap.check_clock(self.h_s)?;
        let coupled = snap.coupling();
        coupled.check_restored(nn)?;
        let (curr, prev) = Self::current_slots(snap.substeps);
        let flat =
            |v: &[[f64; 3]]| -> Vec<f32> { v.iter().flat_map(|p| p.map(|c| c as f32)).collect() };
        self.gpu.queue().write_buffer(
            &self.state.u[curr],
            0,
            bytemuck::cast_slice(&flat(&snap.displacements_m)),
        );
        self.gpu.queue().write_buffer(
            &self.state.u[prev],
            0,
            bytemuck::cast_slice(&flat(&snap.previous_displacements_m)),
        );
        self.gpu
            .wait(None, "uploading a snapshot", self.options.wait_timeout)?;
        self.time_s = snap.time_s;
        self.steps = snap.steps;
        self.substeps = snap.substeps;
        self.can_roll_back = false;
        self.coupled = coupled;
        self.coupled_uploaded = false;
        Ok(())
    }
}

fn widen(u: &[f32]) -> Vec<f64> {
    u.iter().map(|&v| v as f64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substeps_follow_the_cpu_rule() {
        assert_eq!(substeps_for(1e-3, 2e-3, StepControl::Refuse), Ok(1));
        assert_eq!(substeps_for(2.5e-3, 1e-3, StepControl::SubStep), Ok(3));
        assert!(matches!(
            substeps_for(2.5e-3, 1e-3, StepControl::Refuse),
            Err(FemError::TimeStepAboveCritical { .. })
        ));
        assert!(matches!(
            substeps_for(-1.0, 1e-3, StepControl::SubStep),
            Err(FemError::InvalidTimeStep { .. })
        ));
    }
}
