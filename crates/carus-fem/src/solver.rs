//! The TLED time loop: mutable state apart from the constant [`TledModel`].
//!
//! One (sub-)step is a fixed sequence of stages:
//! 1. `apply_loads`: external nodal forces R(t_n) (nodal forces, follower pressure);
//! 2. `element_forces`: per-element internal forces into force copies
//!    (T4ANP first averages the dilatation per node);
//! 3. `advance_nodes`: gather per node + central difference with damping;
//! 4. `enforce_constraints`: fixed, imposed and coupled displacements at t_{n+1}
//!    (a sliding coupled node only along its normal);
//! 5. `commit`: rotate the displacement buffers, advance time.
//!
//! A failing stage returns before the commit, so the state stays the last
//! good one. No stage allocates.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::coupling::CoupledNodes;
use crate::error::FemError;
use crate::fields::{self, ElementFields, Energies};
use crate::kernel::blocks::KernelData;
use crate::kernel::lanes::{Real, LANES};
use crate::kernel::passes::{self, Integrator};
use crate::loads::{check_node, BoundaryConditions, LoadShape};
use crate::model::{KernelModel, TledModel};

/// What to do with a time step above the critical one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StepControl {
    /// Refuse it with an error naming the critical step.
    #[default]
    Refuse,
    /// Split every step into the fewest equal sub-steps at or below the critical step.
    SubStep,
}

/// A complete copy of the mutable state: enough to write a frame or to
/// resume bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverSnapshot {
    pub time_s: f64,
    pub steps: u64,
    pub substeps: u64,
    pub displacements_m: Vec<[f64; 3]>,
    pub previous_displacements_m: Vec<[f64; 3]>,
    /// Displacements held through the coupling API, by node.
    pub coupled: Vec<(u32, [f64; 3])>,
    /// The normals of the held nodes that slide (absent in snapshots
    /// written before sliding holds existed).
    #[serde(default)]
    pub sliding: Vec<(u32, [f64; 3])>,
    /// Where the clock last changed step ([`TledSolver::set_step`]); zero
    /// for a solver that never did. A snapshot is restored at the step it
    /// was taken at.
    #[serde(default)]
    pub clock: ClockOrigin,
    /// The sub-step the state was taken at, s (absent in snapshots written
    /// before it was recorded): a state with its previous displacement one
    /// sub-step behind resumes only at that sub-step.
    #[serde(default)]
    pub substep_s: Option<f64>,
}

/// Where the clock last changed step: time runs from here in whole
/// sub-steps of the current length, so a long run accumulates no drift
/// and a change of step keeps the time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ClockOrigin {
    pub time_s: f64,
    pub steps: u64,
    pub substeps: u64,
}

/// How far, relative, a sub-step read back off an older snapshot's clock
/// may lie from the solver's (the rounding of a time summed in steps).
const SUBSTEP_READ_BACK: f64 = 1e-9;

impl SolverSnapshot {
    /// Refuses a snapshot whose clock a solver stepping `substep_s` cannot
    /// continue: a time that is not finite, a clock origin after the state,
    /// or another sub-step.
    pub(crate) fn check_clock(&self, substep_s: f64) -> Result<(), FemError> {
        let refuse = |reason: String| Err(FemError::InvalidOption { option: "snapshot", reason });
        if !self.time_s.is_finite() || !self.clock.time_s.is_finite() {
            return refuse(format!("its time ({} s, clock origin {} s) is not finite", self.time_s, self.clock.time_s));
        }
        if self.clock.substeps > self.substeps || self.clock.steps > self.steps {
            return refuse(format!(
                "its clock origin (step {}, sub-step {}) lies after its state (step {}, sub-step {}); the file is damaged",
                self.clock.steps, self.clock.substeps, self.steps, self.substeps
            ));
        }
        // Snapshots from before the sub-step was recorded: read it off the
        // clock, which runs in whole sub-steps from its origin.
        let taken_at = match (self.substep_s, self.substeps - self.clock.substeps) {
            (Some(h), _) => h,
            (None, 0) => return Ok(()),
            (None, n) => (self.time_s - self.clock.time_s) / n as f64,
        };
        if (taken_at - substep_s).abs() > SUBSTEP_READ_BACK * substep_s {
            return refuse(format!(
                "it was taken at a sub-step of {taken_at:e} s and this solver steps {substep_s:e} s; restore it into a \
                 solver built with the step it was taken at"
            ));
        }
        Ok(())
    }

    pub(crate) fn coupling(&self) -> CoupledNodes {
        CoupledNodes {
            held: self.coupled.clone(),
            sliding: self.sliding.clone(),
        }
    }
}

/// Boundary conditions resolved to degree-of-freedom lists.
#[derive(Debug, Clone, Default)]
struct CompiledLoads {
    fixed_dofs: Vec<u32>,
    imposed: Vec<(LoadShape, Vec<(u32, f64)>)>,
    forces: Vec<(LoadShape, Vec<u32>, [f64; 3])>,
    pressures: Vec<(LoadShape, f64, Vec<[u32; 3]>)>,
    /// Nodes whose external force changes in time (zeroed every step).
    load_nodes: Vec<u32>,
    gravity: [f64; 3],
}

/// Sub-steps per step: 1 at or below the critical step, else the fewest
/// equal sub-steps at or below it (shared with the GPU backend).
pub(crate) fn substeps_for(
    dt_s: f64,
    critical: f64,
    control: StepControl,
) -> Result<u32, FemError> {
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(FemError::InvalidTimeStep { dt_s });
    }
    if dt_s <= critical {
        return Ok(1);
    }
    match control {
        StepControl::Refuse => Err(FemError::TimeStepAboveCritical {
            dt_s,
            critical_s: critical,
        }),
        StepControl::SubStep => {
            let n = (dt_s / critical).ceil();
            if n > u32::MAX as f64 {
                return Err(FemError::TimeStepAboveCritical {
                    dt_s,
                    critical_s: critical,
                });
            }
            // Guard against rounding leaving dt / n a hair above critical.
            let mut n = n as u32;
            while dt_s / n as f64 > critical {
                n += 1;
            }
            Ok(n)
        }
    }
}


/// An `advance_to` time the steps can reach: a time that is not finite
/// would step for ever (shared with the GPU backend).
pub(crate) fn check_end_time(t_s: f64) -> Result<(), FemError> {
    if t_s.is_finite() {
        return Ok(());
    }
    Err(FemError::InvalidOption { option: "advance_to", reason: format!("the end time is {t_s}; give a finite time, s") })
}

impl CompiledLoads {
    fn new(bc: &BoundaryConditions, nn: usize) -> Result<Self, FemError> {
        bc.validate(nn)?;
        let mut out = CompiledLoads::default();
        for f in &bc.fixed {
            for &n in &f.nodes {
                for c in 0..3 {
                    if f.components[c] {
                        out.fixed_dofs.push(n * 3 + c as u32);
                    }
                }
            }
        }
        for d in &bc.displacements {
            let mut dofs = Vec::new();
            for &n in &d.nodes {
                for c in 0..3 {
                    if let Some(v) = d.components[c] {
                        dofs.push((n * 3 + c as u32, v));
                    }
                }
            }
            out.imposed.push((d.shape, dofs));
        }
        for f in &bc.forces {
            out.load_nodes.extend(&f.nodes);
            out.forces.push((f.shape, f.nodes.clone(), f.force_n));
        }
        for p in &bc.pressures {
            out.load_nodes.extend(p.triangles.iter().flatten());
            out.pressures
                .push((p.shape, p.pressure_pa, p.triangles.clone()));
        }
        out.load_nodes.sort_unstable();
        out.load_nodes.dedup();
        if let Some(g) = bc.gravity_m_s2 {
            out.gravity = g;
        }
        Ok(out)
    }
}

/// Mutable arrays of the step loop in the kernel precision.
#[derive(Debug, Clone)]
struct State<T> {
    u_prev: Vec<T>,
    u_curr: Vec<T>,
    u_next: Vec<T>,
    external: Vec<T>,
    forces: Vec<T>,
    /// T4ANP: J_e V_e / 4 per element and J per node; empty otherwise.
    volume_shares: Vec<T>,
    nodal_j: Vec<T>,
    integrator: Integrator<T>,
}

#[derive(Debug, Clone)]
enum StateData {
    F32(State<f32>),
    F64(State<f64>),
}

/// Why a sub-step failed, before it is turned into a [`FemError`] with times.
enum Failure {
    Element(usize, f64),
    Node(usize),
}

impl<T: Real> State<T> {
    fn new(
        k: &KernelData<T>,
        anp: bool,
        h: f64,
        damping: f64,
        gravity: [f64; 3],
        runaway_m: f64,
    ) -> Self {
        let nn = k.nodes.mass.len();
        let mut state = State {
            u_prev: vec![T::default(); 3 * nn],
            u_curr: vec![T::default(); 3 * nn],
            u_next: vec![T::default(); 3 * nn],
            external: vec![T::default(); 3 * nn],
            forces: vec![T::default(); k.elements.force_copy_len()],
            volume_shares: if anp {
                vec![T::default(); k.elements.block_count * LANES]
            } else {
                Vec::new()
            },
            nodal_j: if anp {
                vec![T::from_f64(1.0); nn]
            } else {
                Vec::new()
            },
            integrator: Integrator {
                h2: T::default(),
                previous_factor: T::default(),
                inv_denominator: T::default(),
                gravity: gravity.map(T::from_f64),
                runaway_m: T::from_f64(runaway_m),
            },
        };
        state.set_substep(h, damping);
        state
    }

    /// The central difference's coefficients for a sub-step h with
    /// mass-proportional damping.
    fn set_substep(&mut self, h: f64, damping: f64) {
        let half = 0.5 * damping * h;
        let it = &mut self.integrator;
        it.h2 = T::from_f64(h * h);
        it.previous_factor = T::from_f64(1.0 - half);
        it.inv_denominator = T::from_f64(1.0 / (1.0 + half));
    }

    /// Moves the previous displacement to `ratio` sub-steps behind the
    /// current one along the same velocity, for a sub-step `ratio` times
    /// the last.
    fn rescale_previous(&mut self, ratio: f64) {
        let ratio = T::from_f64(ratio);
        for (prev, &curr) in self.u_prev.iter_mut().zip(&self.u_curr) {
            *prev = curr - ratio * (curr - *prev);
        }
    }

    /// Stage 1: external forces at time t.
    fn apply_loads(&mut self, loads: &CompiledLoads, reference: &[[f64; 3]], t: f64) {
        for &n in &loads.load_nodes {
            for c in 0..3 {
                self.external[3 * n as usize + c] = T::default();
            }
        }
        for (shape, nodes, f) in &loads.forces {
            let s = shape.value(t);
            for &n in nodes {
                for c in 0..3 {
                    self.external[3 * n as usize + c] += T::from_f64(s * f[c]);
                }
            }
        }
        for (shape, p, tris) in &loads.pressures {
            let p = p * shape.value(t);
            for tri in tris {
                let x: [[f64; 3]; 3] = std::array::from_fn(|a| {
                    let n = tri[a] as usize;
                    std::array::from_fn(|c| reference[n][c] + self.u_curr[3 * n + c].to_f64())
                });
                let e1 = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
                let e2 = [x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]];
                // Area vector A n = (e1 x e2) / 2; each node takes -p A n / 3.
                let an = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                for &n in tri {
                    for c in 0..3 {
                        self.external[3 * n as usize + c] += T::from_f64(-p * an[c] / 6.0);
                    }
                }
            }
        }
    }

    /// Stage 2: internal forces of the current displacement into the force copies.
    fn element_forces(&mut self, k: &KernelData<T>, anp: bool) -> Result<(), (usize, f64)> {
        let nodal_j = if anp {
            if let Some(bad) =
                passes::element_volume_shares(&k.elements, &self.u_curr, &mut self.volume_shares)
            {
                return Err(bad);
            }
            passes::nodal_dilatation(
                &k.elements,
                &k.nodes,
                &self.volume_shares,
                &mut self.nodal_j,
            );
            Some(self.nodal_j.as_slice())
        } else {
            None
        };
        match passes::element_forces(&k.elements, &self.u_curr, nodal_j, &mut self.forces) {
            Some(bad) => Err(bad),
            None => Ok(()),
        }
    }

    /// Stage 3: gather and central-difference update into u_next.
    fn advance_nodes(&mut self, k: &KernelData<T>) -> Result<(), Failure> {
        match passes::advance_nodes(
            &k.nodes,
            &self.forces,
            &self.external,
            &self.integrator,
            &self.u_prev,
            &self.u_curr,
            &mut self.u_next,
        ) {
            Some(n) => Err(Failure::Node(n)),
            None => Ok(()),
        }
    }

    /// Stage 4: displacement constraints at t_{n+1}.
    fn enforce_constraints(
        &mut self,
        loads: &CompiledLoads,
        coupled: &CoupledNodes,
        t_next: f64,
    ) {
        for &d in &loads.fixed_dofs {
            self.u_next[d as usize] = T::default();
        }
        for (shape, dofs) in &loads.imposed {
            let s = shape.value(t_next);
            for &(d, v) in dofs {
                self.u_next[d as usize] = T::from_f64(s * v);
            }
        }
        for &(n, target) in &coupled.held {
            let b = 3 * n as usize;
            let free = [0, 1, 2].map(|c| self.u_next[b + c].to_f64());
            let u = CoupledNodes::constrain(target, coupled.normal_of(n), free);
            for c in 0..3 {
                self.u_next[b + c] = T::from_f64(u[c]);
            }
        }
    }

    /// Stage 5: u_{n-1} <- u_n <- u_{n+1}.
    fn commit(&mut self) {
        std::mem::swap(&mut self.u_prev, &mut self.u_curr);
        std::mem::swap(&mut self.u_curr, &mut self.u_next);
    }

    /// Undoes the last commit: the third buffer still holds u_{n-2}.
    fn roll_back(&mut self) {
        std::mem::swap(&mut self.u_curr, &mut self.u_next);
        std::mem::swap(&mut self.u_prev, &mut self.u_curr);
    }

    #[allow(clippy::too_many_arguments)]
    fn substep(
        &mut self,
        k: &KernelData<T>,
        anp: bool,
        loads: &CompiledLoads,
        coupled: &CoupledNodes,
        reference: &[[f64; 3]],
        t: f64,
        t_next: f64,
    ) -> Result<(), Failure> {
        self.apply_loads(loads, reference, t);
        self.element_forces(k, anp)
            .map_err(|(e, j)| Failure::Element(e, j))?;
        self.advance_nodes(k)?;
        self.enforce_constraints(loads, coupled, t_next);
        self.commit();
        Ok(())
    }

    fn to_vec3(v: &[T]) -> Vec<[f64; 3]> {
        v.chunks_exact(3)
            .map(|c| [c[0].to_f64(), c[1].to_f64(), c[2].to_f64()])
            .collect()
    }

    fn from_vec3(dst: &mut [T], src: &[[f64; 3]]) {
        for (d, s) in dst.chunks_exact_mut(3).zip(src) {
            for c in 0..3 {
                d[c] = T::from_f64(s[c]);
            }
        }
    }
}

/// Runs `$body` with `$s` bound to the state and `$k` to the kernel data of
/// the model's precision.
macro_rules! with_state {
    ($self:expr, |$k:ident, $s:ident| $body:expr) => {
        match (&mut $self.state, $self.model.kernel()) {
            (StateData::F64($s), KernelModel::F64($k)) => $body,
            (StateData::F32($s), KernelModel::F32($k)) => $body,
            _ => unreachable!("state precision follows the model's"),
        }
    };
}

macro_rules! with_state_ref {
    ($self:expr, |$k:ident, $s:ident| $body:expr) => {
        match (&$self.state, $self.model.kernel()) {
            (StateData::F64($s), KernelModel::F64($k)) => $body,
            (StateData::F32($s), KernelModel::F32($k)) => $body,
            _ => unreachable!("state precision follows the model's"),
        }
    };
}

/// A TLED run: the shared constant model plus this run's state.
#[derive(Debug, Clone)]
pub struct TledSolver {
    model: Arc<TledModel>,
    loads: CompiledLoads,
    dt_s: f64,
    substeps_per_step: u32,
    h_s: f64,
    time_s: f64,
    steps: u64,
    substeps: u64,
    clock: ClockOrigin,
    coupled: CoupledNodes,
    /// Whether the buffers still hold the state before the last commit.
    can_roll_back: bool,
    state: StateData,
}

impl TledSolver {
    /// A solver at rest (zero displacement and velocity) at t = 0.
    /// `dt_s` above the model's critical step is refused, or split into
    /// sub-steps with [`StepControl::SubStep`].
    pub fn new(
        model: Arc<TledModel>,
        bcs: &BoundaryConditions,
        dt_s: f64,
        control: StepControl,
    ) -> Result<Self, FemError> {
        let substeps_per_step = substeps_for(dt_s, model.critical_time_step(), control)?;
        let h = dt_s / substeps_per_step as f64;
        let loads = CompiledLoads::new(bcs, model.node_count())?;
        let damping = model.options().damping_per_s;
        let anp = model.uses_anp();
        // A displacement a hundred times the body's size is a runaway.
        let runaway = 100.0 * model.size_m();
        let state = match model.kernel() {
            KernelModel::F64(k) => {
                StateData::F64(State::new(k, anp, h, damping, loads.gravity, runaway))
            }
            KernelModel::F32(k) => {
                StateData::F32(State::new(k, anp, h, damping, loads.gravity, runaway))
            }
        };
        Ok(TledSolver {
            model,
            loads,
            dt_s,
            substeps_per_step,
            h_s: h,
            time_s: 0.0,
            steps: 0,
            substeps: 0,
            clock: ClockOrigin::default(),
            coupled: CoupledNodes::default(),
            can_roll_back: false,
            state,
        })
    }

    pub fn model(&self) -> &Arc<TledModel> {
        &self.model
    }

    /// Requested step, s.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Step actually integrated (dt / substeps_per_step), s.
    pub fn substep_s(&self) -> f64 {
        self.h_s
    }

    pub fn substeps_per_step(&self) -> u32 {
        self.substeps_per_step
    }

    /// The time after `substeps` sub-steps in all.
    fn clock_at(&self, substeps: u64) -> f64 {
        self.clock.time_s + (substeps - self.clock.substeps) as f64 * self.h_s
    }

    /// The steps completed after `substeps` sub-steps in all.
    fn steps_at(&self, substeps: u64) -> u64 {
        self.clock.steps + (substeps - self.clock.substeps) / self.substeps_per_step as u64
    }

    /// Takes steps of `dt_s` from the next one on, split as `control` says,
    /// keeping the time and the velocity: the previous displacement is
    /// moved to one new sub-step behind along the last sub-step's velocity
    /// (central differences with a variable step, first order at the
    /// switch: the half-step velocity is kept, not re-centred). For a mesh deformed so
    /// far that the stable step has shrunk below the one it was built with
    /// ([`TledModel::critical_time_step_at`]). Call it between steps; the
    /// same step again changes nothing. A failure in the first sub-step
    /// after a change cannot roll back (the buffers hold no earlier
    /// sub-step of the new length): it reports the state it failed in.
    pub fn set_step(&mut self, dt_s: f64, control: StepControl) -> Result<(), FemError> {
        let substeps_per_step = substeps_for(dt_s, self.model.critical_time_step(), control)?;
        if dt_s == self.dt_s && substeps_per_step == self.substeps_per_step {
            return Ok(());
        }
        let h = dt_s / substeps_per_step as f64;
        let (ratio, damping) = (h / self.h_s, self.model.options().damping_per_s);
        with_state!(self, |_k, s| {
            s.rescale_previous(ratio);
            s.set_substep(h, damping);
        });
        self.clock = ClockOrigin {
            time_s: self.time_s,
            steps: self.steps,
            substeps: self.substeps,
        };
        self.dt_s = dt_s;
        self.substeps_per_step = substeps_per_step;
        self.h_s = h;
        // The buffers no longer hold the last sub-step's state.
        self.can_roll_back = false;
        Ok(())
    }

    /// Advances by one dt (all of its sub-steps). On error the state is the
    /// last good sub-step's: every element with J > 0, every value finite.
    pub fn step(&mut self) -> Result<(), FemError> {
        for _ in 0..self.substeps_per_step {
            self.substep()?;
        }
        Ok(())
    }

    fn substep(&mut self) -> Result<(), FemError> {
        let t = self.time_s;
        // Time from the sub-step count, so long runs accumulate no drift.
        let t_next = self.clock_at(self.substeps + 1);
        let anp = self.model.uses_anp();
        let model = Arc::clone(&self.model);
        let reference = &model.mesh().nodes;
        let (loads, coupled) = (&self.loads, &self.coupled);
        let result = with_state!(self, |k, s| s
            .substep(k, anp, loads, coupled, reference, t, t_next));
        match result {
            Ok(()) => {
                self.time_s = t_next;
                self.substeps += 1;
                self.steps = self.steps_at(self.substeps);
                self.can_roll_back = true;
                Ok(())
            }
            Err(Failure::Element(element, j)) => {
                // The state at t produced the bad element: go back to t - h,
                // whose elements were all checked.
                if self.can_roll_back {
                    with_state!(self, |_k, s| s.roll_back());
                    self.substeps -= 1;
                    self.steps = self.steps_at(self.substeps);
                    self.time_s = self.clock_at(self.substeps);
                    self.can_roll_back = false;
                }
                if j.is_nan() {
                    Err(FemError::Diverged {
                        time_s: t,
                        last_good_time_s: self.time_s,
                        what: format!("element {element} has a non-finite deformation"),
                    })
                } else {
                    Err(FemError::ElementInvertedDuringRun {
                        element,
                        jacobian: j,
                        time_s: t,
                    })
                }
            }
            Err(Failure::Node(node)) => Err(FemError::Diverged {
                time_s: t_next,
                last_good_time_s: t,
                what: format!(
                    "node {node} displacement is non-finite or beyond 100 x the model size"
                ),
            }),
        }
    }

    /// Steps until the time reaches `t_s` (within half a step).
    pub fn advance_to(&mut self, t_s: f64) -> Result<(), FemError> {
        check_end_time(t_s)?;
        while self.time_s + 0.5 * self.dt_s < t_s {
            self.step()?;
        }
        Ok(())
    }

    /// The simulated time: steps times the step, unrounded, as the loads
    /// read it. Outputs give [`reported_time_s`] of it.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Completed steps of dt.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Completed sub-steps.
    pub fn substeps(&self) -> u64 {
        self.substeps
    }

    /// Current displacement of every node, m.
    pub fn displacements(&self) -> Vec<[f64; 3]> {
        with_state_ref!(self, |_k, s| State::to_vec3(&s.u_curr))
    }

    /// Current displacement of one node, m (None if out of range).
    pub fn displacement(&self, node: u32) -> Option<[f64; 3]> {
        let n = node as usize;
        if n >= self.model.node_count() {
            return None;
        }
        Some(with_state_ref!(self, |_k, s| [
            s.u_curr[3 * n].to_f64(),
            s.u_curr[3 * n + 1].to_f64(),
            s.u_curr[3 * n + 2].to_f64()
        ]))
    }

    /// Holds the given displacements on those nodes from the next step on,
    /// until [`Self::release_imposed`] (replacing earlier values for the same nodes).
    pub fn impose_displacements(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
    ) -> Result<(), FemError> {
        self.coupled.hold(nodes, displacements_m, self.model.node_count())
    }

    /// Holds the given nodes on the planes through the given displacements
    /// square to `normals`, free to slide along them (frictionless contact:
    /// [`crate::coupling`]), from the next step on, until
    /// [`Self::release_imposed`].
    pub fn impose_sliding(
        &mut self,
        nodes: &[u32],
        displacements_m: &[[f64; 3]],
        normals: &[[f64; 3]],
    ) -> Result<(), FemError> {
        self.coupled
            .hold_sliding(nodes, displacements_m, normals, self.model.node_count())
    }

    /// Frees every node held by [`Self::impose_displacements`] or
    /// [`Self::impose_sliding`].
    pub fn release_imposed(&mut self) {
        self.coupled.clear();
    }

    /// Nodes currently held through the coupling API.
    pub fn imposed(&self) -> &CoupledNodes {
        &self.coupled
    }

    /// Recomputes the internal forces at the current displacement (the step
    /// computes them at the start of each sub-step, i.e. one sub-step behind).
    pub fn update_internal_forces(&mut self) -> Result<(), FemError> {
        let anp = self.model.uses_anp();
        let t = self.time_s;
        with_state!(self, |k, s| s.element_forces(k, anp)).map_err(|(element, jacobian)| {
            FemError::ElementInvertedDuringRun {
                element,
                jacobian,
                time_s: t,
            }
        })
    }

    /// Internal nodal forces F(u) at the given nodes, N: the force with
    /// which the tissue resists being displaced there, so that whatever holds
    /// those nodes (a support, an imposed displacement, a contact) carries
    /// F. Evaluated at the displacement of the last force evaluation: the
    /// start of the last sub-step, or the current one after
    /// [`Self::update_internal_forces`].
    pub fn internal_forces(&self, nodes: &[u32]) -> Result<Vec<[f64; 3]>, FemError> {
        let nn = self.model.node_count();
        nodes
            .iter()
            .try_for_each(|&n| check_node("internal_forces", n, nn))?;
        Ok(with_state_ref!(self, |k, s| nodes
            .iter()
            .map(|&n| k.nodes.gather(&s.forces, n as usize).map(|v| v.to_f64()))
            .collect()))
    }

    /// Sum of the internal forces over a node set, N (the reaction force of
    /// supports or imposed displacements on those nodes, at rest).
    pub fn reaction_force(&self, nodes: &[u32]) -> Result<[f64; 3], FemError> {
        let f = self.internal_forces(nodes)?;
        Ok(f.iter().fold([0.0; 3], |acc, v| {
            [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]
        }))
    }

    /// Von Mises stress, maximum principal stretch and J per element.
    pub fn element_fields(&self) -> ElementFields {
        let anp = self.model.uses_anp();
        with_state_ref!(self, |k, s| fields::evaluate(k, anp, &s.u_curr).0)
    }

    /// J = det F per element (one-point, as in [`Self::element_fields`]),
    /// without the stresses and stretches: cheap enough for every step.
    pub fn volume_ratios(&self) -> Vec<f64> {
        with_state_ref!(self, |k, s| fields::volume_ratios(k, &s.u_curr))
    }

    /// Kinetic, strain and hourglass energies of the current state.
    pub fn energies(&self) -> Energies {
        let anp = self.model.uses_anp();
        let h = self.h_s;
        with_state_ref!(self, |k, s| {
            let (_, strain_j, hourglass_j) = fields::evaluate(k, anp, &s.u_curr);
            Energies {
                kinetic_j: fields::kinetic_energy(k, &s.u_curr, &s.u_prev, h),
                strain_j,
                hourglass_j,
            }
        })
    }

    /// A copy of the whole mutable state. After an error it is the last
    /// good state: failed sub-steps never commit, and an element found
    /// inverted rolls the state back to the sub-step before, so every value
    /// is finite and every element valid; except for an inversion found in
    /// the first sub-step after [`Self::restore`] or a change of step, which
    /// has no sub-step before it to go back to.
    pub fn snapshot(&self) -> SolverSnapshot {
        let (displacements_m, previous_displacements_m) = with_state_ref!(self, |_k, s| (
            State::to_vec3(&s.u_curr),
            State::to_vec3(&s.u_prev)
        ));
        SolverSnapshot {
            time_s: self.time_s,
            steps: self.steps,
            substeps: self.substeps,
            displacements_m,
            previous_displacements_m,
            coupled: self.coupled.held.clone(),
            sliding: self.coupled.sliding.clone(),
            clock: self.clock,
            substep_s: Some(self.h_s),
        }
    }

    /// Puts the solver back into a snapshot's state (the same model and
    /// boundary conditions continue from there bit for bit).
    pub fn restore(&mut self, snap: &SolverSnapshot) -> Result<(), FemError> {
        let nn = self.model.node_count();
        for len in [
            snap.displacements_m.len(),
            snap.previous_displacements_m.len(),
        ] {
            if len != nn {
                return Err(FemError::SnapshotMismatch {
                    got: len,
                    expected: nn,
                });
            }
        }
        snap.check_clock(self.h_s)?;
        let coupled = snap.coupling();
        coupled.check_restored(nn)?;
        with_state!(self, |_k, s| {
            State::from_vec3(&mut s.u_curr, &snap.displacements_m);
            State::from_vec3(&mut s.u_prev, &snap.previous_displacements_m);
        });
        self.time_s = snap.time_s;
        self.steps = snap.steps;
        self.substeps = snap.substeps;
        self.clock = snap.clock;
        self.coupled = coupled;
        self.can_roll_back = false;
        Ok(())
    }
}

/// A simulated time as outputs give it: rounded to the nanosecond, so 7000
/// steps of 50 us read 0.35 s and not 0.35000000000000003. Steps of a
/// nanosecond or more (every labour run; a `carus solve` job's step is its
/// own) keep their output times apart.
pub fn reported_time_s(t: f64) -> f64 {
    (t * 1e9).round() / 1e9
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{box_h8, box_t4};
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::model::{MaterialRegion, ModelOptions, Precision, TetFormulation};

    fn region() -> MaterialRegion {
        MaterialRegion {
            element_set: None,
            material: Material::neo_hookean(1006.711409, 50_000.0),
            density_kg_m3: 1000.0,
        }
    }

    fn model(mesh: &Mesh, options: ModelOptions) -> Arc<TledModel> {
        Arc::new(TledModel::new(mesh, &[region()], &options).unwrap())
    }

    /// A smooth pseudo-random displacement field, a few per cent of the size.
    fn wavy(mesh: &Mesh, amp: f64) -> Vec<[f64; 3]> {
        mesh.nodes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let s = (i as f64 * 12.9898).sin() * 0.3;
                [
                    amp * (3.0 * p[1] + s).sin(),
                    amp * (2.0 * p[2] - s).cos() * 0.5,
                    amp * (p[0] * 4.0 + s).sin() * 0.7,
                ]
            })
            .collect()
    }

    fn set_displacement(solver: &mut TledSolver, u: &[[f64; 3]]) {
        let mut snap = solver.snapshot();
        snap.displacements_m = u.to_vec();
        snap.previous_displacements_m = u.to_vec();
        solver.restore(&snap).unwrap();
    }

    fn total_energy(solver: &TledSolver) -> f64 {
        let e = solver.energies();
        e.strain_j + e.hourglass_j
    }

    /// The per-step volume ratios are the output fields' J, element by
    /// element, for H8, T4 and T4ANP.
    #[test]
    fn volume_ratios_are_the_fields_jacobian() {
        let cases = [
            (box_h8([0.1, 0.08, 0.06], [2, 2, 2]), TetFormulation::T4),
            (box_t4([0.1, 0.08, 0.06], [2, 1, 1]), TetFormulation::T4Anp),
        ];
        for (mesh, tet_formulation) in cases {
            let options = ModelOptions { tet_formulation, ..ModelOptions::default() };
            let mut solver =
                TledSolver::new(model(&mesh, options), &BoundaryConditions::default(), 1e-4, StepControl::Refuse)
                    .unwrap();
            set_displacement(&mut solver, &wavy(&mesh, 0.01));
            let j = solver.volume_ratios();
            assert_eq!(j, solver.element_fields().jacobian);
            assert!(j.iter().any(|v| (v - 1.0).abs() > 1e-3), "{j:?}");
        }
    }

    /// The internal forces are the gradient of the stored energy (strain plus
    /// hourglass) for H8, T4 and T4ANP.
    #[test]
    fn internal_forces_are_the_energy_gradient() {
        let cases = [
            (box_h8([0.1, 0.08, 0.06], [2, 2, 2]), TetFormulation::T4),
            (box_t4([0.1, 0.08, 0.06], [2, 1, 1]), TetFormulation::T4),
            (box_t4([0.1, 0.08, 0.06], [2, 2, 1]), TetFormulation::T4Anp),
        ];
        for (mesh, tet_formulation) in cases {
            let m = model(
                &mesh,
                ModelOptions {
                    hourglass_coefficient: 0.3,
                    tet_formulation,
                    ..ModelOptions::default()
                },
            );
            let mut solver =
                TledSolver::new(m, &BoundaryConditions::default(), 1e-4, StepControl::Refuse)
                    .unwrap();
            let u = wavy(&mesh, 0.01);
            set_displacement(&mut solver, &u);
            solver.update_internal_forces().unwrap();
            let all: Vec<u32> = (0..mesh.node_count() as u32).collect();
            let f = solver.internal_forces(&all).unwrap();
            let h = 1e-7;
            let scale = f.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for n in [0usize, 4, mesh.node_count() / 2, mesh.node_count() - 1] {
                for c in 0..3 {
                    let mut up = u.clone();
                    let mut um = u.clone();
                    up[n][c] += h;
                    um[n][c] -= h;
                    set_displacement(&mut solver, &up);
                    let ep = total_energy(&solver);
                    set_displacement(&mut solver, &um);
                    let em = total_energy(&solver);
                    let fd = (ep - em) / (2.0 * h);
                    assert!(
                        (fd - f[n][c]).abs() < 1e-5 * scale,
                        "{:?} node {n} comp {c}: fd {fd} vs {}",
                        mesh.kind,
                        f[n][c]
                    );
                }
            }
        }
    }

    /// Internal forces of every node of `mesh` held at displacement `u`.
    fn internal_forces_at(mesh: &Mesh, options: ModelOptions, u: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let all: Vec<u32> = (0..mesh.node_count() as u32).collect();
        let m = model(mesh, options);
        let mut s =
            TledSolver::new(m, &BoundaryConditions::default(), 1e-4, StepControl::Refuse).unwrap();
        set_displacement(&mut s, u);
        s.update_internal_forces().unwrap();
        s.internal_forces(&all).unwrap()
    }

    #[test]
    fn f32_forces_match_f64() {
        let mesh = box_h8([0.1, 0.1, 0.1], [3, 3, 3]);
        let u = wavy(&mesh, 0.01);
        let forces = |precision| {
            internal_forces_at(
                &mesh,
                ModelOptions {
                    precision,
                    ..ModelOptions::default()
                },
                &u,
            )
        };
        let (a, b) = (forces(Precision::F64), forces(Precision::F32));
        let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((x - y).abs() < 1e-4 * scale, "{x} vs {y}");
        }
    }

    #[test]
    fn anp_equals_t4_for_a_uniform_dilatation() {
        // Homogeneous deformation: every element and node has the same J, so
        // averaging changes nothing.
        let mesh = box_t4([0.1, 0.1, 0.1], [2, 2, 2]);
        let u: Vec<[f64; 3]> = mesh
            .nodes
            .iter()
            .map(|p| [0.05 * p[0] + 0.02 * p[1], -0.03 * p[1], 0.04 * p[2]])
            .collect();
        let forces = |tet_formulation| {
            internal_forces_at(
                &mesh,
                ModelOptions {
                    tet_formulation,
                    ..ModelOptions::default()
                },
                &u,
            )
        };
        let (a, b) = (forces(TetFormulation::T4), forces(TetFormulation::T4Anp));
        for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn time_step_above_critical_is_refused_or_substepped() {
        let mesh = box_h8([0.1, 0.1, 0.1], [4, 4, 4]);
        let m = model(&mesh, ModelOptions::default());
        let crit = m.critical_time_step();
        // H8 cube: L = h = 0.025 m, c = sqrt((kappa + 4 mu / 3) / rho).
        let c = ((50_000.0 + 4.0 * 1006.711409 / 3.0) / 1000.0f64).sqrt();
        assert!((m.element_time_step() - 0.025 / c).abs() < 1e-12 * crit);
        assert!(crit < m.element_time_step());
        match TledSolver::new(
            m.clone(),
            &BoundaryConditions::default(),
            2.5 * crit,
            StepControl::Refuse,
        ) {
            Err(FemError::TimeStepAboveCritical { critical_s, .. }) => assert_eq!(critical_s, crit),
            other => panic!("expected refusal, got {other:?}"),
        }
        let mut s = TledSolver::new(
            m,
            &BoundaryConditions::default(),
            2.5 * crit,
            StepControl::SubStep,
        )
        .unwrap();
        assert_eq!(s.substeps_per_step(), 3);
        s.step().unwrap();
        assert_eq!((s.steps(), s.substeps()), (1, 3));
        assert!((s.time_s() - 2.5 * crit).abs() < 1e-15);
    }

    /// The deformed critical step is the reference one on the reference
    /// shape, and on a cube pressed flat at constant volume (stretched by a
    /// in x and y, 1 / a^2 in z) it is the critical step of a model built
    /// on that shape: L = V / A_max falls by a^2.
    #[test]
    fn the_critical_step_follows_the_deformed_shape() {
        let mesh = box_h8([0.1, 0.1, 0.1], [4, 4, 4]);
        let m = model(&mesh, ModelOptions::default());
        let mut solver =
            TledSolver::new(m.clone(), &BoundaryConditions::default(), m.critical_time_step(), StepControl::Refuse)
                .unwrap();
        let at_rest = m.critical_time_step_at(&mesh.nodes, &solver.volume_ratios());
        assert!((at_rest / m.critical_time_step() - 1.0).abs() < 1e-12, "{at_rest}");
        let a: f64 = 1.8;
        let flat: Vec<[f64; 3]> = mesh.nodes.iter().map(|p| [a * p[0], a * p[1], p[2] / (a * a)]).collect();
        let u: Vec<[f64; 3]> = flat.iter().zip(&mesh.nodes).map(|(x, p)| [x[0] - p[0], x[1] - p[1], x[2] - p[2]]).collect();
        set_displacement(&mut solver, &u);
        let j = solver.volume_ratios();
        assert!(j.iter().all(|j| (j - 1.0).abs() < 1e-12));
        let pressed = m.critical_time_step_at(&flat, &j);
        assert!((pressed * a * a / at_rest - 1.0).abs() < 1e-9, "{pressed} against {at_rest}");
        let rebuilt = model(&Mesh { nodes: flat, ..mesh.clone() }, ModelOptions::default());
        let margin = m.critical_time_step() / m.element_time_step();
        assert!((pressed / (margin * rebuilt.element_time_step()) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn t4_critical_step_uses_minimum_altitude() {
        let mesh = box_t4([0.1, 0.1, 0.1], [1, 1, 1]);
        let m = model(&mesh, ModelOptions::default());
        let c = ((50_000.0 + 4.0 * 1006.711409 / 3.0) / 1000.0f64).sqrt();
        // Each tetrahedron of the six-tet split: V = h^3/6, largest face sqrt(2) h^2 / 2.
        let altitude = 3.0 * (0.1f64.powi(3) / 6.0) / (2f64.sqrt() / 2.0 * 0.01);
        assert!((m.element_time_step() - altitude / c).abs() < 1e-12);
    }
}

#[cfg(test)]
mod run_tests {
    use super::*;
    use crate::generate::box_h8;
    use crate::loads::{ImposedDisplacement, SurfacePressure};
    use crate::material::Material;
    use crate::model::{MaterialRegion, ModelOptions};

    fn model(n: usize, options: ModelOptions) -> (crate::mesh::Mesh, Arc<TledModel>) {
        let mesh = box_h8([0.1; 3], [n; 3]);
        let region = MaterialRegion {
            element_set: None,
            material: Material::neo_hookean(1000.0, 20_000.0),
            density_kg_m3: 1000.0,
        };
        let m = Arc::new(TledModel::new(&mesh, &[region], &options).unwrap());
        (mesh, m)
    }

    fn pull(mesh: &crate::mesh::Mesh, ux: f64) -> BoundaryConditions {
        let mut bc = BoundaryConditions::default();
        bc.fix_nodes(&mesh.node_sets["x0"]);
        bc.displacements.push(ImposedDisplacement {
            nodes: mesh.node_sets["x1"].clone(),
            components: [Some(ux), Some(0.0), Some(0.0)],
            shape: LoadShape::Smooth345 { duration_s: 0.05 },
        });
        bc
    }

    /// Big enough for several element tasks and node tasks, so the
    /// combining of chunks done on different threads is exercised.
    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        use crate::kernel::lanes::LANES;
        use crate::kernel::passes::{BLOCKS_PER_TASK, NODES_PER_TASK};
        let (mesh, m) = model(
            12,
            ModelOptions {
                damping_per_s: 5.0,
                ..ModelOptions::default()
            },
        );
        assert!(mesh.element_count() > 2 * BLOCKS_PER_TASK * LANES, "{} elements fit in two element tasks", mesh.element_count());
        assert!(mesh.nodes.len() > 2 * NODES_PER_TASK, "{} nodes fit in two node tasks", mesh.nodes.len());
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut s = TledSolver::new(
                    m.clone(),
                    &pull(&mesh, 0.02),
                    0.9 * m.critical_time_step(),
                    StepControl::Refuse,
                )
                .unwrap();
                for _ in 0..120 {
                    s.step().unwrap();
                }
                s.displacements()
            })
        };
        let (a, b) = (run(1), run(3));
        assert!(a
            .iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(a.iter().flatten().any(|v| v.abs() > 1e-3));
    }

    #[test]
    fn snapshot_restore_resumes_bit_for_bit() {
        let (mesh, m) = model(
            3,
            ModelOptions {
                damping_per_s: 2.0,
                ..ModelOptions::default()
            },
        );
        let dt = 0.9 * m.critical_time_step();
        let mut a =
            TledSolver::new(m.clone(), &pull(&mesh, 0.02), dt, StepControl::Refuse).unwrap();
        for _ in 0..50 {
            a.step().unwrap();
        }
        let snap = a.snapshot();
        for _ in 0..50 {
            a.step().unwrap();
        }
        let mut b = TledSolver::new(m, &pull(&mesh, 0.02), dt, StepControl::Refuse).unwrap();
        b.restore(&snap).unwrap();
        for _ in 0..50 {
            b.step().unwrap();
        }
        assert_eq!(a.snapshot(), b.snapshot());
    }

    /// A damaged snapshot's coupling (a target not finite, a sliding normal
    /// not of unit length) is refused, not projected on the wrong plane; an
    /// end time that is not finite is refused, not stepped to for ever.
    #[test]
    fn a_damaged_coupling_and_an_endless_time_are_refused() {
        let (mesh, m) = model(2, ModelOptions::default());
        let dt = 0.9 * m.critical_time_step();
        let mut s = TledSolver::new(m, &pull(&mesh, 0.02), dt, StepControl::Refuse).unwrap();
        let good = SolverSnapshot { coupled: vec![(0, [0.0; 3])], sliding: vec![(0, [0.0, 0.0, 1.0])], ..s.snapshot() };
        s.restore(&good).unwrap();
        for (damage, why) in [
            (SolverSnapshot { coupled: vec![(0, [f64::NAN, 0.0, 0.0])], sliding: Vec::new(), ..good.clone() }, "held displacement of node 0"),
            (SolverSnapshot { sliding: vec![(0, [0.0, 0.0, 2.0])], ..good.clone() }, "not of unit length"),
        ] {
            let e = s.restore(&damage).unwrap_err().to_string();
            assert!(e.contains(why) && e.contains("damaged"), "{e}");
        }
        let e = s.advance_to(f64::INFINITY).unwrap_err().to_string();
        assert!(e.contains("advance_to") && e.contains("finite"), "{e}");
    }

    /// A snapshot resumes only on a clock it can continue: at the sub-step
    /// it was taken at, with its clock origin before its state and its
    /// times finite; each refusal says why, and the solver is untouched.
    #[test]
    fn restore_refuses_a_clock_it_cannot_continue() {
        let (mesh, m) = model(2, ModelOptions::default());
        let h = 0.9 * m.critical_time_step();
        let mut s = TledSolver::new(m.clone(), &pull(&mesh, 0.02), h, StepControl::Refuse).unwrap();
        for _ in 0..4 {
            s.step().unwrap();
        }
        s.set_step(h / 2.0, StepControl::Refuse).unwrap();
        s.step().unwrap();
        let refined = s.snapshot();
        assert_eq!(refined.substep_s, Some(h / 2.0));
        let mut other = TledSolver::new(m, &pull(&mesh, 0.02), h, StepControl::Refuse).unwrap();
        let untouched = other.snapshot();
        let refused = |other: &mut TledSolver, snap: &SolverSnapshot, why: &str| {
            let e = other.restore(snap).unwrap_err().to_string();
            assert!(e.contains(why), "{e}");
        };
        refused(&mut other, &refined, "restore it into a solver built with the step it was taken at");
        // A snapshot from before the sub-step was recorded: the step is
        // read off its clock (one sub-step of h / 2 since the origin).
        let mut unrecorded = refined.clone();
        unrecorded.substep_s = None;
        refused(&mut other, &unrecorded, "taken at a sub-step of");
        for damage in [
            |s: &mut SolverSnapshot| s.clock.substeps = s.substeps + 1,
            |s: &mut SolverSnapshot| s.clock.steps = s.steps + 1,
        ] {
            let mut ahead = refined.clone();
            damage(&mut ahead);
            refused(&mut other, &ahead, "lies after its state");
        }
        for damage in [|s: &mut SolverSnapshot| s.time_s = f64::NAN, |s: &mut SolverSnapshot| s.clock.time_s = f64::INFINITY] {
            let mut endless = refined.clone();
            damage(&mut endless);
            refused(&mut other, &endless, "not finite");
        }
        assert_eq!(other.snapshot(), untouched);
        other.set_step(h / 2.0, StepControl::Refuse).unwrap();
        other.restore(&refined).unwrap();
        other.restore(&unrecorded).unwrap();
        assert_eq!(other.snapshot(), refined);
        // An unrecorded snapshot at the built step is taken as it comes.
        let mut fresh = TledSolver::new(other.model().clone(), &pull(&mesh, 0.02), h, StepControl::Refuse).unwrap();
        let mut old = s.snapshot();
        old.substep_s = None;
        old.clock = ClockOrigin::default();
        old.time_s = 4.0 * h;
        old.steps = 4;
        old.substeps = 4;
        fresh.restore(&old).unwrap();
    }

    /// A free block drifting at a uniform velocity: a change of step keeps
    /// the velocity (each new sub-step moves it v h'), the time and the step
    /// count, back and forth.
    #[test]
    fn a_change_of_step_keeps_the_time_and_the_velocity() {
        let (_mesh, m) = model(2, ModelOptions::default());
        let h = 0.9 * m.critical_time_step();
        let mut s = TledSolver::new(m.clone(), &BoundaryConditions::default(), h, StepControl::Refuse).unwrap();
        let v = [0.3, -0.1, 0.2];
        let mut snap = s.snapshot();
        snap.displacements_m = vec![[v[0] * h, v[1] * h, v[2] * h]; m.node_count()];
        snap.previous_displacements_m = vec![[0.0; 3]; m.node_count()];
        s.restore(&snap).unwrap();
        let x = |s: &TledSolver| s.displacements()[0][0];
        for _ in 0..3 {
            s.step().unwrap();
        }
        s.set_step(h / 3.0, StepControl::Refuse).unwrap();
        assert_eq!(s.dt_s(), h / 3.0);
        let before = x(&s);
        s.step().unwrap();
        assert!((x(&s) - before - v[0] * h / 3.0).abs() < 1e-12);
        s.set_step(h, StepControl::Refuse).unwrap();
        let before = x(&s);
        s.step().unwrap();
        assert!((x(&s) - before - v[0] * h).abs() < 1e-12);
        assert_eq!((s.steps(), s.substeps()), (5, 5));
        assert!((s.time_s() - (4.0 + 1.0 / 3.0) * h).abs() < 1e-15);
        // The same step again changes nothing.
        let same = s.snapshot();
        s.set_step(h, StepControl::Refuse).unwrap();
        assert_eq!(s.snapshot(), same);
    }

    /// A pulled, damped block whose step halves half-way agrees with the run
    /// at the fine step throughout as closely as the coarse run does, and
    /// resumes bit for bit from a snapshot taken after the change.
    #[test]
    fn halving_the_step_mid_run_agrees_with_the_fine_run_and_resumes() {
        let (mesh, m) = model(
            3,
            ModelOptions {
                damping_per_s: 5.0,
                ..ModelOptions::default()
            },
        );
        let h = 0.9 * m.critical_time_step();
        let steps = 400;
        let mut fine = TledSolver::new(m.clone(), &pull(&mesh, 0.02), h / 2.0, StepControl::Refuse).unwrap();
        for _ in 0..2 * steps {
            fine.step().unwrap();
        }
        let mut changed = TledSolver::new(m.clone(), &pull(&mesh, 0.02), h, StepControl::Refuse).unwrap();
        for _ in 0..steps / 2 {
            changed.step().unwrap();
        }
        changed.set_step(h / 2.0, StepControl::Refuse).unwrap();
        for _ in 0..steps / 2 {
            changed.step().unwrap();
        }
        let snap = changed.snapshot();
        for _ in 0..steps / 2 {
            changed.step().unwrap();
        }
        let mut coarse = TledSolver::new(m.clone(), &pull(&mesh, 0.02), h, StepControl::Refuse).unwrap();
        for _ in 0..steps {
            coarse.step().unwrap();
        }
        assert!((changed.time_s() - fine.time_s()).abs() < 1e-12 * fine.time_s());
        let a = fine.displacements();
        let largest = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let off = |s: &TledSolver| {
            a.iter().flatten().zip(s.displacements().iter().flatten()).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        // The switch is first order (the last sub-step's velocity is kept,
        // not centred anew): within the coarse step's own error of the fine
        // run, both about 0.2 % of the displacement.
        let (switched, coarse) = (off(&changed), off(&coarse));
        assert!(largest > 1e-2 && switched < 2.0 * coarse && switched < 5e-3 * largest, "{switched}, {coarse} of {largest}");
        let mut resumed = TledSolver::new(m, &pull(&mesh, 0.02), h / 2.0, StepControl::Refuse).unwrap();
        resumed.restore(&snap).unwrap();
        for _ in 0..steps / 2 {
            resumed.step().unwrap();
        }
        assert_eq!(resumed.snapshot(), changed.snapshot());
    }

    #[test]
    fn inversion_during_a_run_names_the_element_and_keeps_the_last_good_state() {
        let (mesh, m) = model(2, ModelOptions::default());
        let mut bc = BoundaryConditions::default();
        bc.fix_nodes(&mesh.node_sets["x0"]);
        // A huge sudden compression of the far face.
        bc.displacements.push(ImposedDisplacement {
            nodes: mesh.node_sets["x1"].clone(),
            components: [Some(-0.09), None, None],
            shape: LoadShape::Step,
        });
        let mut s = TledSolver::new(m, &bc, 0.5 * 1e-4, StepControl::SubStep).unwrap();
        let mut failure = None;
        for _ in 0..100 {
            let before = s.snapshot();
            if let Err(e) = s.step() {
                failure = Some(e);
                // Only whole sub-steps commit: the state is a valid earlier one.
                assert!(s.time_s() <= before.time_s + s.dt_s());
                assert!(s.element_fields().jacobian.iter().all(|&j| j > 0.0));
                break;
            }
        }
        match failure {
            Some(FemError::ElementInvertedDuringRun {
                element, jacobian, ..
            }) => {
                assert!(element < 8);
                assert!(jacobian <= 0.0);
            }
            other => panic!("expected an inversion, got {other:?}"),
        }
    }

    /// Loads and reactions balance at rest: gravity (a dead load) against
    /// the fixed base, and a small follower pressure on the top face.
    #[test]
    fn gravity_and_pressure_are_carried_to_the_supports() {
        let (mesh, m) = model(
            2,
            ModelOptions {
                damping_per_s: 60.0,
                ..ModelOptions::default()
            },
        );
        let base = mesh.node_sets["z0"].clone();
        let masses = m.node_masses_kg();
        let base_mass: f64 = base.iter().map(|&n| masses[n as usize]).sum();
        for (gravity, pressure_pa) in [(Some([0.0, 0.0, -9.81]), 0.0), (None, 2.0)] {
            let mut bc = BoundaryConditions::default();
            bc.fix_nodes(&base);
            bc.gravity_m_s2 = gravity;
            bc.pressures.push(SurfacePressure {
                triangles: mesh.surfaces["z1"].clone(),
                pressure_pa,
                shape: LoadShape::RampHold { ramp_s: 0.05 },
            });
            let mut s = TledSolver::new(
                m.clone(),
                &bc,
                0.9 * m.critical_time_step(),
                StepControl::Refuse,
            )
            .unwrap();
            s.advance_to(2.0).unwrap();
            s.update_internal_forces().unwrap();
            let r = s.reaction_force(&base).unwrap();
            // The internal forces of the base balance the loads on the other nodes.
            let expected = if gravity.is_some() {
                (1.0 - base_mass) * 9.81
            } else {
                pressure_pa * 0.01
            };
            let tolerance = if gravity.is_some() { 1e-6 } else { 2e-3 };
            assert!(
                (r[2] - expected).abs() < tolerance * expected,
                "{r:?} vs {expected}"
            );
            assert!(r[0].abs() < 1e-9 && r[1].abs() < 1e-9);
        }
    }

    /// A damped 2^3 cube fixed on its x = 0 face, for the coupling tests.
    fn damped_cube_fixed_at_x0() -> (crate::mesh::Mesh, Arc<TledModel>, BoundaryConditions) {
        let (mesh, m) = model(
            2,
            ModelOptions {
                damping_per_s: 30.0,
                ..ModelOptions::default()
            },
        );
        let mut bc = BoundaryConditions::default();
        bc.fix_nodes(&mesh.node_sets["x0"]);
        (mesh, m, bc)
    }

    #[test]
    fn coupling_holds_and_releases_nodes() {
        let (mesh, m, bc) = damped_cube_fixed_at_x0();
        let mut s = TledSolver::new(
            m.clone(),
            &bc,
            0.9 * m.critical_time_step(),
            StepControl::Refuse,
        )
        .unwrap();
        let held = mesh.node_sets["x1"].clone();
        let push = vec![[0.01, 0.0, 0.0]; held.len()];
        assert!(s.impose_displacements(&held, &push[1..]).is_err());
        s.impose_displacements(&held, &push).unwrap();
        s.advance_to(0.5).unwrap();
        for &n in &held {
            assert_eq!(s.displacement(n).unwrap(), [0.01, 0.0, 0.0]);
        }
        s.update_internal_forces().unwrap();
        let pull = s.reaction_force(&held).unwrap();
        let support = s.reaction_force(&mesh.node_sets["x0"]).unwrap();
        assert!(
            pull[0] > 0.0 && (pull[0] + support[0]).abs() < 1e-2 * pull[0],
            "{pull:?} {support:?}"
        );
        s.release_imposed();
        s.advance_to(3.0).unwrap();
        let back = s.displacement(held[0]).unwrap();
        assert!(back[0].abs() < 1e-4, "{back:?}");
    }

    /// A face pressed onto a frictionless wall (x = 1 cm) and pulled along
    /// it: held sliding, it slides and keeps to the wall, and the wall
    /// carries no tangential load at rest; held in full, it does not move.
    #[test]
    fn a_sliding_hold_keeps_the_node_on_its_plane_and_lets_it_slide() {
        let (mesh, m, mut bc) = damped_cube_fixed_at_x0();
        let wall = mesh.node_sets["x1"].clone();
        let pull = [0.0, 0.05, 0.0];
        bc.forces.push(crate::loads::NodalForce {
            nodes: wall.clone(),
            force_n: pull,
            shape: LoadShape::Step,
        });
        let solver = || TledSolver::new(m.clone(), &bc, 0.9 * m.critical_time_step(), StepControl::Refuse).unwrap();
        let run = |sliding: bool| {
            let mut s = solver();
            let at = vec![[0.01, 0.0, 0.0]; wall.len()];
            if sliding {
                let normals = vec![[-2.0, 0.0, 0.0]; wall.len()];
                assert!(s.impose_sliding(&wall, &at, &normals[1..]).is_err());
                s.impose_sliding(&wall, &at, &normals).unwrap();
            } else {
                s.impose_displacements(&wall, &at).unwrap();
            }
            s.advance_to(3.0).unwrap();
            s.update_internal_forces().unwrap();
            (s.clone(), wall.iter().map(|&n| s.displacement(n).unwrap()).collect::<Vec<_>>())
        };
        let (s, slid) = run(true);
        for u in &slid {
            assert!((u[0] - 0.01).abs() < 1e-15, "{u:?}");
            assert!(u[1] > 1e-4, "{u:?}");
        }
        // At rest the tissue's own force balances the pull along the wall.
        let f = s.internal_forces(&wall).unwrap();
        for v in &f {
            assert!((v[1] - pull[1]).abs() < 1e-3 * pull[1], "{v:?}");
        }
        let snapshot = s.snapshot();
        assert_eq!(snapshot.sliding.len(), wall.len());
        let mut resumed = solver();
        resumed.restore(&snapshot).unwrap();
        assert_eq!(resumed.imposed(), s.imposed());
        let (_, held) = run(false);
        for u in &held {
            assert_eq!(*u, [0.01, 0.0, 0.0]);
        }
    }

    #[test]
    fn a_runaway_stops_with_the_last_good_state() {
        let (mesh, m) = model(2, ModelOptions::default());
        let mut bc = BoundaryConditions::default();
        bc.fix_nodes(&mesh.node_sets["x0"]);
        bc.forces.push(crate::loads::NodalForce {
            nodes: vec![mesh.node_sets["x1"][0]],
            force_n: [1e15, 0.0, 0.0],
            shape: LoadShape::Step,
        });
        let mut s = TledSolver::new(
            m.clone(),
            &bc,
            0.9 * m.critical_time_step(),
            StepControl::Refuse,
        )
        .unwrap();
        let before = s.snapshot();
        match s.step() {
            Err(FemError::Diverged {
                last_good_time_s, ..
            }) => assert_eq!(last_good_time_s, 0.0),
            other => panic!("expected divergence, got {other:?}"),
        }
        assert_eq!(s.snapshot(), before);
        assert!(s.displacements().iter().flatten().all(|v| v.is_finite()));
    }
}

#[cfg(test)]
mod reported_time_tests {
    use super::reported_time_s;
    use proptest::prelude::*;

    #[test]
    fn step_counts_read_as_the_decimal_they_are() {
        assert_eq!(7.0 * 0.05, 0.35000000000000003);
        assert_eq!(reported_time_s(7.0 * 0.05), 0.35);
        assert_eq!(reported_time_s(11040.0 * 0.0005), 5.52);
    }

    proptest! {
        /// Within half a nanosecond of the clock, and in the clock's order.
        #[test]
        fn rounding_keeps_the_time_and_its_order(step in 0u64..2_000_000, dt in 1e-7f64..2e-3) {
            let (t, next) = (step as f64 * dt, (step + 1) as f64 * dt);
            prop_assert!((reported_time_s(t) - t).abs() <= 0.5e-9 + 1e-15 * t);
            prop_assert!(reported_time_s(next) > reported_time_s(t));
        }
    }
}
