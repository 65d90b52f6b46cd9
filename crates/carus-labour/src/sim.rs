//! The forward simulation: the mutable state of a run and the step
//! pipeline, a short sequence of named stages:
//! expulsion -> pelvis contacts (head, trunk) -> head on trunk -> neck (and spine) -> floor reaction ->
//! passive resistance -> rigid integration -> floor coupling -> record
//! (poses, and at the same instants the loads per site, crate::loads).
//!
//! Nothing here reads a way-point, a target rotation or any term that knows
//! the expected outcome (CARDINAL_MOVEMENTS.md, "What the forward mode may
//! use"): every force comes from the expulsion generator, contact with the
//! bone, the floor and the fetus's own trunk (with friction), the neck's elasticity or the passive
//! resistance of the surroundings.

use carus_analysis::{ContactSite, FetalPart, PoseSample};
use carus_contact::{
    obstacle_contacts_by_region, pair_contacts, BodyContactState, BodyMotion, ContactReport, Neck, NeckAngles, NeckGeometry,
    NeckLoad, RigidBodyState, RigidPose, TissueContact, TriangleCollider, Wrench,
};
use carus_fem::{SolverSnapshot, StepControl, TledSolver};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::expulsion::Expulsion;
use crate::loads::{self, AxialMoments, Body, GuideLoad, LoadSample, SiteLoad};
use crate::scenario::FloorCoupling;
use crate::scene::{Scene, HEAD, LOWER_TRUNK, TRUNK};
use crate::trajectory::{Mode, GUIDE_DAMPING_RATIO};
use crate::LabourError;

/// How far from the pelvic axis a head has been thrown, not walked out,
/// when the canal cannot hold it: no pelvis is a metre across.
const THROWN_M: f64 = 1.0;

/// The floor's part of the mutable state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorState {
    pub solver: SolverSnapshot,
    /// Contact of each fetal body (head, trunk, lower trunk) with the floor's nodes.
    pub contacts: Vec<TissueContact>,
    /// Contact of the bony canal wall (with the sacrospinous ligaments)
    /// with the floor's nodes: the tissue slides on the bone, never into it.
    pub bone: TissueContact,
    /// Rigid steps whose floor took finer sub-steps than the reference
    /// shape's (an element pressed flat: [`MAX_SUBSTEP_REFINEMENT`]).
    #[serde(default)]
    pub refined_steps: u64,
    /// The most sub-steps one rigid step took (the reference sub-steps
    /// when none was refined).
    #[serde(default)]
    pub most_substeps: u32,
}

/// The most times finer than the reference shape's that the floor is
/// sub-stepped when contact has pressed an element flat (numerical
/// bound, not physics): a rigid step then costs up to this many times
/// more, and an element that needs more is being crushed and fails as a
/// floor failure, named, as it did before sub-steps followed the shape.
pub const MAX_SUBSTEP_REFINEMENT: u32 = 16;

/// One recorded floor figure: the largest principal stretch over the floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FloorSample {
    pub time_s: f64,
    pub peak_stretch: f64,
    pub peak_von_mises_pa: f64,
    /// Floor nodes held by the fetus.
    pub held_nodes: usize,
    /// Floor elements with a corner turned inside out (scaled Jacobian
    /// below 0, Knupp 2000): the solver's inversion check, at the element's
    /// centre, does not see them, and their stresses are not to be trusted.
    #[serde(default)]
    pub inverted_corner_elements: usize,
}

impl FloorSample {
    /// When a floor element first had a corner turned inside out among
    /// `samples`: the floor's stretches from then on are not to be trusted.
    pub fn first_inverted_s(samples: &[FloorSample]) -> Option<f64> {
        samples.iter().find(|f| f.inverted_corner_elements > 0).map(|f| f.time_s)
    }
}

/// Everything that changes during a run; serializable, so a checkpoint
/// resumes bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimState {
    /// Completed rigid steps.
    pub step: u64,
    pub bodies: RigidBodyState,
    pub neck: Option<Neck>,
    /// The thoracolumbar joint, when the spine bends.
    #[serde(default)]
    pub spine: Option<Neck>,
    pub bone_contacts: Vec<BodyContactState>,
    /// The trunk's samples below its thoracic inlet against the head (friction
    /// anchors on the head), when that contact is on.
    #[serde(default)]
    pub head_trunk: Option<BodyContactState>,
    pub floor: Option<FloorState>,
    /// The floor's force on each body from the last coupling, applied at the next step.
    pub floor_wrench: Vec<Wrench>,
    /// Pose history samples so far.
    pub samples: Vec<PoseSample>,
    pub floor_samples: Vec<FloorSample>,
    /// The contact loads of the steps that ended at `samples`' instants
    /// (as `samples`' forces: each from the pose its step began in, one
    /// rigid step before the pose recorded with it).
    #[serde(default)]
    pub loads: Vec<LoadSample>,
}

/// Wall time each stage of the rigid step took, seconds, summed over the
/// steps this simulation object took (a resumed run counts its own part):
/// what `carus bench labour` prints. Never read back by the physics, so
/// timing leaves the run bit for bit the same.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// The expulsion and the contacts with the bony pelvis (broad and narrow phase, friction).
    pub bone_contacts_s: f64,
    /// The trunk against the head (chin on chest).
    pub head_trunk_s: f64,
    /// The neck and spine springs, and the floor's reaction added.
    pub joints_s: f64,
    /// Passive resistance and the rigid bodies' integration.
    pub integration_s: f64,
    /// Which floor nodes the bone and the fetus hold, and where.
    pub floor_contact_s: f64,
    /// The floor's TLED sub-steps and its reaction on the fetus.
    pub floor_tled_s: f64,
    /// Sorting the forces by site and recording the pose and load samples.
    pub recording_s: f64,
}

impl StageTimes {
    pub fn total_s(&self) -> f64 {
        self.named().iter().map(|(_, s)| s).sum()
    }

    /// The stages by name, in step order.
    pub fn named(&self) -> [(&'static str, f64); 7] {
        [
            ("bone_contacts", self.bone_contacts_s),
            ("head_trunk", self.head_trunk_s),
            ("joints", self.joints_s),
            ("integration", self.integration_s),
            ("floor_contact", self.floor_contact_s),
            ("floor_tled", self.floor_tled_s),
            ("recording", self.recording_s),
        ]
    }
}

/// A stopwatch that charges the time since its last lap to a stage.
struct Lap(std::time::Instant);

impl Lap {
    fn start() -> Self {
        Lap(std::time::Instant::now())
    }

    fn charge(&mut self, stage: &mut f64) {
        let now = std::time::Instant::now();
        *stage += (now - self.0).as_secs_f64();
        self.0 = now;
    }
}

/// The running simulation: the scene, the state, and the live TLED solver
/// (the state keeps its snapshot only at checkpoints).
pub struct Simulation<'a> {
    pub scene: &'a Scene,
    pub state: SimState,
    /// Where this object's steps spent their time.
    pub stage_times: StageTimes,
    solver: Option<TledSolver>,
    expulsion: Expulsion,
    dt: f64,
    /// TLED sub-steps per rigid step.
    substeps: u32,
    /// Rigid steps between pose samples.
    sample_every: u64,
    /// The step at `numerics.end_time_s` (the run's last, when it is not
    /// delivered, stopped or failed before), sampled too, so that a run
    /// that reaches its end time records that state wherever the sampling
    /// interval falls.
    end_step: u64,
}

/// What one step found, for the record.
struct StepForces {
    expulsion: DVec3,
    bone: DVec3,
    floor: DVec3,
    dominant: Option<ContactSite>,
    /// The fetal body that bore most of the dominant site's force.
    dominant_part: Option<FetalPart>,
    /// Per site, on recorded steps only.
    sites: Vec<SiteLoad>,
    head_axial: AxialMoments,
    /// The trunk's contact on the head, about the head's centre of mass.
    head_trunk: Wrench,
    neck: Option<NeckAngles>,
    /// The neck's force on the head, at the pivot (none without a trunk).
    neck_force: Option<DVec3>,
    /// The trunk's contact moment on the head about the pivot.
    head_trunk_about_pivot: DVec3,
    spine: Option<NeckAngles>,
    /// What moved the head besides the physics (imposed and hybrid modes).
    guide: Option<Wrench>,
}

/// Where the trajectory wants the head: its pose, and the velocity and
/// angular velocity of following it.
struct HeadTarget {
    pose: RigidPose,
    /// The pose one rigid step later.
    next: RigidPose,
    velocity: DVec3,
    angular_velocity: DVec3,
}

impl<'a> Simulation<'a> {
    /// A fresh run at the scenario's start.
    pub fn new(scene: &'a Scene) -> Result<Self, LabourError> {
        let bodies = RigidBodyState::at_rest(&scene.bodies, &scene.start)?;
        let join = |geometry: Option<NeckGeometry>, stiffness| {
            geometry
                .map(|g| Neck::new(&scene.bodies, &bodies, g, stiffness))
                .transpose()
        };
        let neck = join(scene.neck_joint, scene.scenario.neck)?;
        let spine = join(scene.spine_joint, scene.scenario.spine.joint())?;
        let dt = scene.scenario.numerics.rigid_dt_s;
        // Each joint's error names the key its own section spells.
        let neck_key: fn(&'static str) -> &'static str = |field| field;
        for (section, joint, key_of) in [
            ("neck", &neck, neck_key),
            ("spine", &spine, crate::scenario::SpineSection::key_of),
        ] {
            if let Some(limit) = joint.as_ref().map(|j| j.stable_step(&scene.bodies, &bodies)) {
                if dt > limit.dt_s {
                    let key = key_of(limit.limited_by);
                    return Err(LabourError::UnstableJoint {
                        at: scene.scenario.located_key(&format!("{section}.{key}")),
                        section,
                        key,
                        stiffness: crate::scenario::shown(limit.stiffness),
                        dt_s: dt,
                        limit_s: limit.dt_s,
                    });
                }
            }
        }
        if scene.scenario.trajectory.mode == Mode::Hybrid {
            check_guide_step(scene, &bodies, dt)?;
        }
        let bone_contacts = (0..scene.bodies.len())
            .map(|b| BodyContactState::new(&scene.fetal_body(b).samples))
            .collect();
        let solver = scene
            .floor
            .as_ref()
            .map(|f| new_solver(scene, f, dt))
            .transpose()?;
        let floor = match solver.as_ref() {
            Some((s, reference)) => {
                let reach = scene.scenario.floor.coupling_reach_mm * 1e-3;
                let contact = || -> Result<TissueContact, LabourError> {
                    let c = TissueContact::new(reach)?;
                    Ok(match scene.scenario.floor.coupling {
                        FloorCoupling::Sliding => c.sliding(),
                        FloorCoupling::Held => c,
                    })
                };
                let n = scene.bodies.len();
                Some(FloorState {
                    solver: s.snapshot(),
                    contacts: (0..n).map(|_| contact()).collect::<Result<_, _>>()?,
                    // Tissue never passes into bone: a node the floor
                    // throws through the wall within a step is caught too.
                    bone: contact()?.catching_crossings(),
                    refined_steps: 0,
                    most_substeps: *reference,
                })
            }
            None => None,
        };
        let body_count = scene.bodies.len();
        let head_trunk = scene.head_trunk.as_ref().map(|pair| BodyContactState::new(&pair.trunk_samples));
        let state = SimState {
            step: 0,
            bodies,
            neck,
            spine,
            bone_contacts,
            head_trunk,
            floor,
            floor_wrench: vec![Wrench::default(); body_count],
            samples: Vec::new(),
            floor_samples: Vec::new(),
            loads: Vec::new(),
        };
        let mut sim = Simulation::from_state(scene, state)?;
        let load = |j: &Neck| j.load(&scene.bodies, &sim.state.bodies);
        let neck_load = sim.state.neck.as_ref().map(load);
        let spine = sim.state.spine.as_ref().map(|j| load(j).angles);
        sim.record(StepForces {
            expulsion: sim.expulsion.force(0.0, sim.spine()),
            bone: DVec3::ZERO,
            floor: DVec3::ZERO,
            dominant: None,
            dominant_part: None,
            sites: Vec::new(),
            head_axial: AxialMoments::default(),
            head_trunk: Wrench::default(),
            neck: neck_load.as_ref().map(|l| l.angles),
            neck_force: neck_load.as_ref().map(|l| l.on_head.force),
            head_trunk_about_pivot: DVec3::ZERO,
            spine,
            guide: None,
        });
        Ok(sim)
    }

    /// Continues from a saved state (a checkpoint).
    /// The state must have every part the scene has, each the size of
    /// its body (an edited or foreign checkpoint would otherwise run on
    /// with, say, the head detached from the trunk).
    pub fn from_state(scene: &'a Scene, state: SimState) -> Result<Self, LabourError> {
        let n = scene.bodies.len();
        let b = &state.bodies;
        let samples_match = |contacts: &[BodyContactState]| {
            contacts.len() == n
                && contacts
                    .iter()
                    .enumerate()
                    .all(|(i, c)| c.sample_count() == Some(scene.fetal_body(i).samples.len()))
        };
        let checks = [
            (
                [b.position.len(), b.orientation.len(), b.linear_velocity.len(), b.angular_momentum.len()]
                    .iter()
                    .all(|&len| len == n),
                "the fetal bodies' poses and velocities",
            ),
            (scene.neck_joint.is_some() == state.neck.is_some(), "the neck (`state.neck`)"),
            (scene.spine_joint.is_some() == state.spine.is_some(), "the spine (`state.spine`)"),
            (samples_match(&state.bone_contacts), "the contacts with the bone (`state.bone_contacts`)"),
            (
                match (&scene.head_trunk, &state.head_trunk) {
                    (Some(pair), Some(c)) => c.sample_count() == Some(pair.trunk_samples.len()),
                    (None, None) => true,
                    _ => false,
                },
                "the trunk's contact with the head (`state.head_trunk`, contact.head_trunk)",
            ),
            (state.floor_wrench.len() == n, "the floor's reaction on each body (`state.floor_wrench`)"),
            (
                state.floor.as_ref().is_none_or(|f| f.contacts.len() == n),
                "the floor's contact with each body (`state.floor.contacts`)",
            ),
        ];
        if let Some((_, what)) = checks.iter().find(|(fits, _)| !fits) {
            return Err(LabourError::Checkpoint(format!(
                "the saved state does not fit its scenario: {what} is missing or of another size; \
                 the checkpoint was edited or written by another version of carus: run the \
                 scenario again from the start"
            )));
        }
        let dt = scene.scenario.numerics.rigid_dt_s;
        let reached_s = state.step as f64 * dt;
        // As the run counts its steps (run.rs): the last may end a hair past
        // end_time_s when the step does not divide it.
        let end_step = (scene.scenario.numerics.end_time_s / dt).round() as u64;
        // No run reaches a kilometre (a head off the canal stops it at a
        // metre, THROWN_M, and no push carries a trunk that far): a saved
        // body there is a slip of exponent.
        let thrown = b.position.iter().any(|p| p.length() > 1e3);
        // Every step leaves a unit quaternion (rigid.rs normalises it); any
        // other is no rotation, and the motion built on it blows up later.
        let not_rotation = b.orientation.iter().any(|q| (q.length() - 1.0).abs() > carus_analysis::history::UNIT_TOLERANCE);
        if state.step > end_step || b.first_not_finite().is_some() || thrown || not_rotation {
            return Err(LabourError::Checkpoint(format!(
                "the saved state is not one its scenario can reach (its step count puts it at t = \
                 {reached_s:.3e} s, the scenario ends at {} s; or a pose is not finite, beyond a \
                 kilometre of the pelvis, or its orientation not a unit quaternion \
                 (`state.bodies.orientation`)): the checkpoint was edited or damaged: run the scenario \
                 again from the start",
                scene.scenario.numerics.end_time_s
            )));
        }
        // The samples so far must be a history the detector reads, none
        // after the saved step: found only at the run's end, the rest
        // would be simulated for nothing.
        let recorded = crate::run::history_of(scene, state.samples.clone());
        let last_s = state.samples.last().map_or(0.0, |s| s.time_s);
        let fault = match recorded.validate() {
            Ok(()) | Err(carus_analysis::HistoryError::TooFewSamples { .. }) => {
                (last_s > reached_s + 0.5 * dt).then(|| format!("its last sample, at t = {last_s} s, lies after its step's t = {reached_s} s"))
            }
            Err(e) => Some(e.to_string()),
        }
        .or_else(|| unpaired_records(&state));
        if let Some(fault) = fault {
            return Err(LabourError::Checkpoint(format!(
                "the saved pose history is not one a run writes ({fault}): the checkpoint was edited \
                 or damaged: run the scenario again from the start"
            )));
        }
        let (mut solver, substeps) = match (&scene.floor, &state.floor) {
            (Some(f), Some(_)) => {
                let (s, n) = new_solver(scene, f, dt)?;
                (Some(s), n)
            }
            (None, None) => (None, 0),
            _ => {
                return Err(LabourError::Checkpoint(
                    "the checkpoint's pelvic floor does not match the scenario's (one has a floor, the other none): \
                     the checkpoint was edited or written for another scenario; run the scenario again from the start"
                        .into(),
                ))
            }
        };
        if let (Some(solver), Some(floor)) = (solver.as_mut(), &state.floor) {
            solver.restore(&floor.solver).map_err(|e| {
                LabourError::Checkpoint(format!(
                    "the saved pelvic floor cannot go on in this scenario's floor ({e}): the checkpoint was \
                     edited or damaged: run the scenario again from the start"
                ))
            })?;
        }
        let sample_every = ((scene.scenario.output.every_s / dt).round() as u64).max(1);
        Ok(Simulation {
            scene,
            state,
            stage_times: StageTimes::default(),
            solver,
            expulsion: Expulsion::new(&scene.scenario.expulsion),
            dt,
            substeps,
            sample_every,
            end_step,
        })
    }

    /// The simulated time as reported (samples, frames, the record), so
    /// 11040 steps of 0.5 ms read 5.52 s and not 5.5200000000000005. The
    /// forces read the unrounded clock, and so do the step's errors, which
    /// print it to the millisecond.
    pub fn time_s(&self) -> f64 {
        carus_fem::solver::reported_time_s(self.clock_s())
    }

    fn clock_s(&self) -> f64 {
        self.state.step as f64 * self.dt
    }

    /// The step at `numerics.end_time_s`: the run ends there.
    pub fn end_step(&self) -> u64 {
        self.end_step
    }

    /// Whether the state after `step` steps is a pose sample.
    fn samples_at(&self, step: u64) -> bool {
        step.is_multiple_of(self.sample_every) || step == self.end_step
    }

    /// Whether the last step's state was recorded as a pose sample.
    pub fn sampled_last_step(&self) -> bool {
        self.state.step > 0 && self.samples_at(self.state.step)
    }

    pub fn dt_s(&self) -> f64 {
        self.dt
    }

    /// TLED sub-steps per rigid step (0 without a floor).
    pub fn floor_substeps(&self) -> u32 {
        self.substeps
    }

    /// The state with the floor solver's snapshot brought up to date.
    pub fn checkpoint_state(&mut self) -> &SimState {
        if let (Some(solver), Some(floor)) = (&self.solver, self.state.floor.as_mut()) {
            floor.solver = solver.snapshot();
        }
        &self.state
    }

    pub fn solver(&self) -> Option<&TledSolver> {
        self.solver.as_ref()
    }

    /// The spine direction k (towards the breech) of the segment the
    /// expulsion pushes, pelvis frame.
    fn spine(&self) -> DVec3 {
        match self.scene.trunk {
            Some(_) => {
                self.state.bodies.orientation[self.scene.breech_body()] * self.scene.spine_in_trunk
            }
            // No trunk: the spine leaves the head at the neck's rest attitude.
            None => self.state.bodies.orientation[HEAD] * self.scene.spine_in_head,
        }
    }

    fn motion(&self, b: usize) -> BodyMotion {
        let s = &self.state.bodies;
        BodyMotion {
            pose: s.pose(b),
            linear_velocity: s.linear_velocity[b],
            angular_velocity: s.angular_velocity(&self.scene.bodies, b),
        }
    }

    /// One rigid step with its floor sub-steps.
    pub fn step(&mut self) -> Result<(), LabourError> {
        let mut lap = Lap::start();
        let scene = self.scene;
        let t = self.clock_s();
        let n = scene.bodies.len();
        let mut wrenches = vec![Wrench::default(); n];

        // Expulsion along the spine, from the breech towards the head.
        let spine = self.spine();
        let expulsion = self.expulsion.force(t, spine);
        let pivot = self.pivot();
        if scene.expulsion_at_pivot() {
            wrenches[HEAD] += Wrench::at_point(expulsion, pivot, self.state.bodies.position[HEAD]);
        } else {
            wrenches[scene.breech_body()].force += expulsion;
        }

        // Contacts with the bony pelvis.
        let mut reports: Vec<ContactReport> = Vec::with_capacity(n);
        for (b, wrench) in wrenches.iter_mut().enumerate() {
            let motion = self.motion(b);
            let report = obstacle_contacts_by_region(
                &scene.pelvis_collider,
                scene.contact_law(b),
                scene.region_laws(b),
                &scene.fetal_body(b).samples,
                &motion,
                pivot,
                &mut self.state.bone_contacts[b],
            )?;
            *wrench += report.wrench();
            if let Some((_, depth, region)) = report.first_pushed_through {
                if b == HEAD && self.mode() == Mode::Imposed {
                    return Err(LabourError::TrajectoryThroughBone {
                        time_s: t,
                        site: scene.site_name(region),
                        depth_mm: depth * 1e3,
                    });
                }
                return Err(LabourError::PushedThrough {
                    time_s: t,
                    body: Body::of(b).name(),
                    site: scene.site_name(region),
                    depth_mm: depth * 1e3,
                    force_n: report.force.length(),
                });
            }
            reports.push(report);
        }
        lap.charge(&mut self.stage_times.bone_contacts_s);

        // The head against the trunk below its thoracic inlet (chin on chest).
        let mut head_trunk = Wrench::default();
        if let Some(pair) = &scene.head_trunk {
            let (trunk, head) = (self.motion(TRUNK), self.motion(HEAD));
            let Some(memory) = self.state.head_trunk.as_mut() else {
                return Err(LabourError::Checkpoint(
                    "the state lost its head-trunk contact; start the run again".into(),
                ));
            };
            let r = pair_contacts(&pair.head, &scene.trunk_law, &pair.trunk_samples, &trunk, &head, memory)?;
            wrenches[TRUNK] += r.on_sampled;
            wrenches[HEAD] += r.on_obstacle;
            head_trunk = r.on_obstacle;
        }
        lap.charge(&mut self.stage_times.head_trunk_s);

        // The neck, and the spine when it bends.
        let mut joint = |j: &Neck| {
            let load = j.load(&scene.bodies, &self.state.bodies);
            wrenches[j.head] += load.on_head;
            wrenches[j.trunk] += load.on_trunk;
            load
        };
        let neck_load = self.state.neck.as_ref().map(&mut joint);
        let spine_angles = self.state.spine.as_ref().map(|j| joint(j).angles);

        // The floor's reaction from the last coupling.
        for (w, f) in wrenches.iter_mut().zip(&self.state.floor_wrench) {
            *w += *f;
        }
        lap.charge(&mut self.stage_times.joints_s);

        let mut forces = self.classify(expulsion, &reports);
        forces.spine = spine_angles;
        forces.head_trunk = head_trunk;
        // The hybrid's guide: a spring and damper towards the way-points.
        if self.mode() == Mode::Hybrid {
            if let Some(target) = self.head_target() {
                let guide = self.guide(&target);
                wrenches[HEAD] += guide;
                forces.guide = Some(guide);
            }
        }
        if self.samples_at(self.state.step + 1) {
            self.site_loads(&mut forces, &reports, neck_load.as_ref(), pivot);
        }
        lap.charge(&mut self.stage_times.recording_s);

        // Passive resistance of the surroundings, implicit so that it is
        // stable at any step (it only damps).
        let imposed = self.mode() == Mode::Imposed;
        for (b, w) in wrenches.iter_mut().enumerate() {
            // An imposed head's drag is taken at the path's motion (impose_head).
            if !(b == HEAD && imposed) {
                *w += self.implicit_drag(b, *w);
            }
        }

        let head_before = imposed.then(|| (self.state.bodies.linear_velocity[HEAD], self.state.bodies.angular_momentum[HEAD]));
        self.state.bodies.step(&scene.bodies, &wrenches, self.dt)?;
        if let Some(before) = head_before {
            forces.guide = self.impose_head(before, wrenches[HEAD]);
        }
        if let Some(b) = self.state.bodies.first_not_finite() {
            return Err(LabourError::Diverged { time_s: t, body: Body::of(b).name() });
        }
        if let Some(off) = scene.outside_canal(self.state.bodies.position[HEAD]) {
            if off > THROWN_M {
                return Err(LabourError::Diverged { time_s: t, body: Body::of(HEAD).name() });
            }
            return Err(LabourError::LeftCanal(format!(
                "the fetal head left the birth canal before the outlet (its centre {:.0} mm \
                 from the pelvic axis, more than half the inlet's transverse diameter): the \
                 model has no uterus or abdominal wall to hold it there, so this is not a delivery",
                off * 1e3
            )));
        }
        lap.charge(&mut self.stage_times.integration_s);
        self.couple_floor(&mut lap)?;
        lap.charge(&mut self.stage_times.floor_tled_s);
        self.state.step += 1;
        if self.samples_at(self.state.step) {
            self.record(forces);
        }
        lap.charge(&mut self.stage_times.recording_s);
        Ok(())
    }

    /// How the head is moved (`[trajectory] mode`).
    fn mode(&self) -> Mode {
        self.scene.scenario.trajectory.mode
    }

    /// The trajectory's head at this step's time, in the imposed and hybrid
    /// modes (forward mode has no trajectory), with the velocities of
    /// following it over the step.
    fn head_target(&self) -> Option<HeadTarget> {
        let path = self.scene.trajectory.as_ref()?;
        let pose_at = |n: u64| self.scene.head_on_trajectory(path.at(n as f64 * self.dt));
        let (now, next) = (pose_at(self.state.step), pose_at(self.state.step + 1));
        Some(HeadTarget {
            pose: now,
            next,
            velocity: (next.position_m - now.position_m) / self.dt,
            angular_velocity: shortest(next.orientation * now.orientation.inverse()).to_scaled_axis() / self.dt,
        })
    }

    /// The hybrid's guide on the head, about its centre of mass: springs
    /// (`guide_stiffness_n_per_m`, `guide_torsion_nm_per_rad`) towards the
    /// target pose, critically damped towards its motion.
    fn guide(&self, target: &HeadTarget) -> Wrench {
        let path = &self.scene.scenario.trajectory;
        let (k, kr) = (path.guide_stiffness_n_per_m, path.guide_torsion_nm_per_rad);
        let s = &self.state.bodies;
        let m = self.scene.bodies.mass_kg[HEAD];
        let inertia = head_turning_inertia(&self.scene.bodies, s.orientation[HEAD]);
        let damping = |stiffness: f64, mass: f64| 2.0 * GUIDE_DAMPING_RATIO * (stiffness * mass).sqrt();
        let turn = shortest(target.pose.orientation * s.orientation[HEAD].inverse()).to_scaled_axis();
        Wrench {
            force: k * (target.pose.position_m - s.position[HEAD])
                + damping(k, m) * (target.velocity - s.linear_velocity[HEAD]),
            torque: kr * turn
                + damping(kr, inertia) * (target.angular_velocity - s.angular_velocity(&self.scene.bodies, HEAD)),
        }
    }

    /// Imposed mode: puts the head where the trajectory has it at the end
    /// of this step, moving as it moves, and returns what that took
    /// beyond the forces on it (`applied`, and the surroundings' drag at
    /// the path's motion, over the step from the velocity and momentum
    /// `before`): the teacher's hand.
    fn impose_head(&mut self, before: (DVec3, DVec3), applied: Wrench) -> Option<Wrench> {
        // Its velocities carry the path's position now to the next one,
        // as the symplectic step moves a body.
        let target = self.head_target()?;
        let fetus = &self.scene.scenario.fetus;
        let applied = applied
            + Wrench {
                force: -fetus.head_linear_drag_n_s_per_m * target.velocity,
                torque: -fetus.head_angular_drag_nm_s_per_rad * target.angular_velocity,
            };
        let model = &self.scene.bodies;
        let s = &mut self.state.bodies;
        s.position[HEAD] = target.next.position_m;
        s.orientation[HEAD] = target.next.orientation;
        s.linear_velocity[HEAD] = target.velocity;
        s.set_angular_velocity(model, HEAD, target.angular_velocity);
        let dt = self.dt;
        Some(Wrench {
            force: model.mass_kg[HEAD] * (target.velocity - before.0) / dt - applied.force,
            torque: (s.angular_momentum[HEAD] - before.1) / dt - applied.torque,
        })
    }

    /// The atlanto-occipital pivot as the head carries it.
    pub fn pivot(&self) -> DVec3 {
        self.state
            .bodies
            .pose(HEAD)
            .point(self.scene.pivot_in_head)
    }

    /// Drag force and torque that, added to `w`, give the backward-Euler
    /// update of a linear dashpot to the surroundings.
    fn implicit_drag(&self, b: usize, w: Wrench) -> Wrench {
        let f = &self.scene.scenario.fetus;
        let mass = &self.scene.bodies.mass_kg;
        let (c, ca) = if b == HEAD {
            (
                f.head_linear_drag_n_s_per_m,
                f.head_angular_drag_nm_s_per_rad,
            )
        } else {
            // The trunk's resistance, shared by its segments by mass: the
            // same total on a straight spine moving as one.
            let share = mass[b] / mass[TRUNK..].iter().sum::<f64>();
            (
                share * f.trunk_linear_drag_n_s_per_m,
                share * f.trunk_angular_drag_nm_s_per_rad,
            )
        };
        let s = &self.state.bodies;
        let m = self.scene.bodies.mass_kg[b];
        let dt = self.dt;
        let v_new = (s.linear_velocity[b] + dt * w.force / m) / (1.0 + dt * c / m);
        let inverse_inertia = self.scene.bodies.inverse_inertia_world(b, s.orientation[b]);
        let torque = if inverse_inertia.determinant().abs() > 0.0 {
            let inertia = inverse_inertia.inverse();
            let omega_new = (inertia + DMat3::from_diagonal(DVec3::splat(dt * ca))).inverse()
                * (s.angular_momentum[b] + dt * w.torque);
            -ca * omega_new
        } else {
            DVec3::ZERO
        };
        Wrench {
            force: -c * v_new,
            torque,
        }
    }

    /// The floor stage: hold the tissue nodes the fetus has entered on its
    /// surface (partial Dirichlet-Neumann, Lapeer et al. 2019), sub-step the
    /// tissue over the rigid step, and read back its reaction.
    fn couple_floor(&mut self, lap: &mut Lap) -> Result<(), LabourError> {
        let (Some(solver), Some(floor_state), Some(floor)) = (
            self.solver.as_mut(),
            self.state.floor.as_mut(),
            self.scene.floor.as_ref(),
        ) else {
            return Ok(());
        };
        let scene = self.scene;
        let nodes = deformed(&floor.reference, solver);
        let volume_ratios = solver.volume_ratios();
        let ratio = scene.scenario.floor.crushed_volume_ratio;
        let crushed = (ratio > 0.0).then(|| crushed_nodes(&floor.mesh, &nodes, &volume_ratios, ratio));
        // Contact can press an element flat, its faces stretched at constant
        // volume, and the stable step with it far below the reference
        // shape's that the sub-step was chosen for: sub-step finer while it
        // lasts (docs/SOLVE.md). Read on the shape the last step left,
        // before this step's holds move it: a step behind the contact, which
        // the floor step fraction's margin covers.
        let positions: Vec<[f64; 3]> = nodes.iter().map(|p| p.to_array()).collect();
        let fraction = scene.scenario.numerics.floor_step_fraction;
        let stable = fraction * floor.model.critical_time_step_at(&positions, &volume_ratios);
        let substeps = substeps_within(self.dt, stable, fraction * floor.critical_step_s, self.substeps);
        if substeps != self.substeps {
            solver.set_step(self.dt / substeps as f64, StepControl::Refuse)?;
            floor_state.refined_steps += 1;
        }
        floor_state.most_substeps = floor_state.most_substeps.max(substeps);
        solver.release_imposed();
        // Who holds a node, first come first served (carus-fem's imposed
        // displacements override its fixed dofs, and a later imposition
        // overrides an earlier one): the attachment to bone, the bony wall,
        // the head, the trunk. The bone does not give, while the fetus,
        // held off it by a penalty, may press into it: tissue caught between
        // the two stays on the bone and the fetus passes over it (squeezed
        // aside, not flattened; docs/CONTACT.md).
        let mut prescribed = floor.attached.clone();
        let mut hold = |contact: &mut TissueContact,
                        collider: &TriangleCollider,
                        pose: &RigidPose,
                        prescribed: &mut Vec<bool>|
         -> Result<Vec<u32>, LabourError> {
            let slides = contact.slides();
            let held = contact.update_except(collider, pose, &nodes, prescribed);
            let ids: Vec<u32> = held.iter().map(|h| h.node).collect();
            for &i in &ids {
                prescribed[i as usize] = true;
            }
            let targets: Vec<[f64; 3]> = held
                .iter()
                .map(|h| (h.target - floor.reference[h.node as usize]).to_array())
                .collect();
            if slides {
                let normals: Vec<[f64; 3]> = held.iter().map(|h| h.normal.to_array()).collect();
                solver.impose_sliding(&ids, &targets, &normals)?;
            } else {
                solver.impose_displacements(&ids, &targets)?;
            }
            Ok(ids)
        };
        let poses = &self.state.bodies;
        let on_bone = hold(
            &mut floor_state.bone,
            scene.pelvis_collider.surface(),
            &RigidPose::IDENTITY,
            &mut prescribed,
        )?;
        // The fetus lets go of crushed tissue (FloorSection::crushed_volume_ratio).
        for (p, c) in prescribed.iter_mut().zip(crushed.iter().flatten()) {
            *p |= *c;
        }
        let held_by = floor_state
            .contacts
            .iter_mut()
            .enumerate()
            .map(|(b, contact)| {
                let body = scene.fetal_body(b);
                hold(contact, &body.collider, &poses.pose(b), &mut prescribed)
            })
            .collect::<Result<Vec<_>, _>>()?;
        lap.charge(&mut self.stage_times.floor_contact_s);
        // An element turned inside out is explained wherever the solver
        // sees it: in a sub-step, or in the forces read after them.
        let explain = |e: carus_fem::FemError, solver: &TledSolver| {
            let names: Vec<String> =
                (0..held_by.len()).map(|b| format!("held on the {}", Body::of(b).name().replace('_', " "))).collect();
            let holders: Vec<(&str, &[u32])> = std::iter::once(("held on the bony wall", on_bone.as_slice()))
                .chain(names.iter().map(String::as_str).zip(held_by.iter().map(Vec::as_slice)))
                .collect();
            floor_failure(e, solver, floor, &scene.scenario.floor.mesh, &holders)
        };
        let stepped = (0..substeps)
            .try_for_each(|_| solver.step())
            .and_then(|()| solver.update_internal_forces());
        // Back to the reference sub-step whatever happened: a state
        // written from here records the step it resumes at.
        solver.set_step(self.dt / self.substeps as f64, StepControl::Refuse)?;
        if let Err(e) = stepped {
            return Err(explain(e, solver));
        }
        let pivot = self
            .state
            .bodies
            .pose(HEAD)
            .point(scene.pivot_in_head);
        let push = |ids: &[u32]| -> Result<Vec<DVec3>, LabourError> {
            let f = solver.internal_forces(ids)?;
            Ok(f.iter().map(|v| -DVec3::from_array(*v)).collect())
        };
        for (b, (contact, ids)) in floor_state.contacts.iter_mut().zip(&held_by).enumerate() {
            let r = contact.reaction(&push(ids)?, self.state.bodies.position[b], pivot)?;
            self.state.floor_wrench[b] = r.wrench();
        }
        // The bone takes what the tissue presses on it; the reading only
        // lets go of nodes that would pull on the bone (no adhesion).
        floor_state.bone.reaction(&push(&on_bone)?, DVec3::ZERO, DVec3::ZERO)?;
        Ok(())
    }

    /// Totals, the part of the mother that carried the largest force, and
    /// the fetal body that bore most of it.
    fn classify(&self, expulsion: DVec3, reports: &[ContactReport]) -> StepForces {
        let sites = &self.scene.sites;
        let per_body: Vec<Vec<DVec3>> = reports.iter().map(|r| r.force_by_region(sites.len())).collect();
        let by_site: Vec<DVec3> = (0..sites.len()).map(|k| per_body.iter().map(|f| f[k]).sum()).collect();
        let bone: DVec3 = reports.iter().map(|r| r.force).sum();
        let floor: DVec3 = self.state.floor_wrench.iter().map(|w| w.force).sum();
        let mut dominant = None;
        let mut dominant_part = None;
        let mut largest = 1e-6;
        for (k, f) in by_site.iter().enumerate() {
            if f.length() > largest {
                largest = f.length();
                dominant = Some(sites[k]);
                dominant_part = Some(bearer(per_body.iter().map(|f| f[k])));
            }
        }
        if floor.length() > largest {
            dominant = Some(ContactSite::PelvicFloor);
            dominant_part = Some(bearer(self.state.floor_wrench.iter().map(|w| w.force)));
        }
        StepForces {
            expulsion,
            bone,
            floor,
            dominant,
            dominant_part,
            sites: Vec::new(),
            head_axial: AxialMoments::default(),
            head_trunk: Wrench::default(),
            neck: None,
            neck_force: None,
            head_trunk_about_pivot: DVec3::ZERO,
            spine: None,
            guide: None,
        }
    }

    /// The loads per body and site, and the moments that spin the head
    /// about the pelvic axis (what turns theta).
    fn site_loads(
        &self,
        forces: &mut StepForces,
        reports: &[ContactReport],
        neck: Option<&NeckLoad>,
        pivot: DVec3,
    ) {
        let scene = self.scene;
        let s = &self.state;
        for (b, report) in reports.iter().enumerate() {
            let body = Body::of(b);
            forces
                .sites
                .extend(loads::bone_loads(body, report, &scene.sites, pivot));
            let held = s.floor.as_ref().map_or(0, |f| f.contacts[b].held().len());
            forces.sites.extend(loads::floor_load(
                body,
                &s.floor_wrench[b],
                held,
                s.bodies.position[b],
                pivot,
            ));
        }
        let down = loads::down_the_canal(scene.canal.axis(), s.bodies.position[HEAD]);
        forces.head_axial = AxialMoments {
            bone_nm: reports[HEAD].torque_about_com.dot(down),
            floor_nm: s.floor_wrench[HEAD].torque.dot(down),
            neck_nm: neck.map_or(0.0, |l| l.on_head.torque.dot(down)),
            trunk_nm: forces.head_trunk.torque.dot(down),
            neck_push_nm: neck.map_or(0.0, |l| {
                Wrench::at_point(l.on_head.force, pivot, s.bodies.position[HEAD]).torque.dot(down)
            }),
        };
        forces.neck = neck.map(|l| l.angles);
        forces.neck_force = neck.map(|l| l.on_head.force);
        forces.head_trunk_about_pivot = loads::moment_about(&forces.head_trunk, s.bodies.position[HEAD], pivot);
    }

    fn record(&mut self, forces: StepForces) {
        let s = &self.state.bodies;
        let pose = |b: usize| s.pose(b);
        self.state.samples.push(PoseSample {
            time_s: self.time_s(),
            head: pose(HEAD),
            trunk: self.scene.trunk.as_ref().map(|_| pose(TRUNK)),
            lower_trunk: self.scene.lower_trunk.as_ref().map(|_| pose(LOWER_TRUNK)),
            expulsion_force_n: forces.expulsion,
            bone_contact_force_n: forces.bone,
            floor_contact_force_n: forces.floor,
            dominant_contact: forces.dominant,
            dominant_part: forces.dominant_part,
        });
        self.state.loads.push(LoadSample {
            time_s: self.time_s(),
            sites: forces.sites,
            head_axial: forces.head_axial,
            head_trunk_force_n: forces.head_trunk.force,
            head_trunk_moment_about_pivot_nm: Some(forces.head_trunk_about_pivot),
            neck: forces.neck,
            neck_force_n: forces.neck_force,
            spine: forces.spine,
            guide: forces.guide.map(|g| GuideLoad { force_n: g.force, moment_nm: g.torque }),
        });
        if let (Some(solver), Some(floor), Some(scene_floor)) =
            (&self.solver, &self.state.floor, &self.scene.floor)
        {
            let fields = solver.element_fields();
            let peak = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
            let nodes = deformed(&scene_floor.reference, solver);
            self.state.floor_samples.push(FloorSample {
                time_s: self.time_s(),
                peak_stretch: peak(&fields.max_principal_stretch),
                peak_von_mises_pa: peak(&fields.von_mises_pa),
                held_nodes: floor.contacts.iter().map(|c| c.held().len()).sum(),
                inverted_corner_elements: inverted_corner_elements(&scene_floor.mesh, &nodes),
            });
        }
    }
}

/// Why a saved state's loads or floor samples do not pair with its pose
/// samples one to one, at the same times (the output writes them side by
/// side, row by row), if they do not.
fn unpaired_records(state: &SimState) -> Option<String> {
    let poses: Vec<f64> = state.samples.iter().map(|s| s.time_s).collect();
    let loads: Vec<f64> = state.loads.iter().map(|s| s.time_s).collect();
    let floor: Vec<f64> = state.floor_samples.iter().map(|s| s.time_s).collect();
    let floor_expected: &[f64] = if state.floor.is_some() { &poses } else { &[] };
    let unpaired = |what: &str, got: &[f64], expected: &[f64]| {
        (got != expected).then(|| {
            format!("its {} {what} are not taken at the times of the {} pose samples they go with", got.len(), expected.len())
        })
    };
    unpaired("load samples", &loads, &poses).or_else(|| unpaired("floor samples", &floor, floor_expected))
}

/// Refuses a hybrid guide too stiff for the rigid step. A critically
/// damped spring under symplectic Euler is stable for dt omega below
/// 2 (sqrt(zeta^2 + 1) - zeta), 0.83 at zeta = 1; 0.8 is asked.
fn check_guide_step(scene: &Scene, bodies: &RigidBodyState, dt: f64) -> Result<(), LabourError> {
    let path = &scene.scenario.trajectory;
    let mass = scene.bodies.mass_kg[HEAD];
    let inertia = head_turning_inertia(&scene.bodies, bodies.orientation[HEAD]);
    for (key, stiffness, omega) in [
        ("guide_stiffness_n_per_m", path.guide_stiffness_n_per_m, (path.guide_stiffness_n_per_m / mass).sqrt()),
        ("guide_torsion_nm_per_rad", path.guide_torsion_nm_per_rad, (path.guide_torsion_nm_per_rad / inertia).sqrt()),
    ] {
        let limit_s = 0.8 / omega;
        if dt > limit_s {
            return Err(LabourError::UnstableJoint {
                at: scene.scenario.located_key(&format!("trajectory.{key}")),
                section: "trajectory",
                key,
                stiffness: crate::scenario::shown(stiffness),
                dt_s: dt,
                limit_s,
            });
        }
    }
    Ok(())
}

/// The same rotation with a non-negative scalar part: the short way round.
fn shortest(q: glam::DQuat) -> glam::DQuat {
    if q.w < 0.0 {
        -q
    } else {
        q
    }
}

/// The head's moment of inertia for the guide's damping and step limit,
/// kg m^2: its smallest principal moment or just under it (one over the
/// largest row sum of the inverse inertia, which no eigenvalue of the
/// inverse exceeds), so that no axis is taken as heavier than it is.
fn head_turning_inertia(model: &carus_contact::RigidBodyModel, q: glam::DQuat) -> f64 {
    let inverse = model.inverse_inertia_world(HEAD, q);
    let rows = [inverse.row(0), inverse.row(1), inverse.row(2)];
    1.0 / rows.iter().map(|r| r.abs().element_sum()).fold(0.0, f64::max)
}

/// The floor's nodes where they are now: reference plus displacement.
fn deformed(reference: &[DVec3], solver: &TledSolver) -> Vec<DVec3> {
    reference
        .iter()
        .zip(solver.displacements())
        .map(|(x, d)| *x + DVec3::from_array(d))
        .collect()
}

/// Whether `element`, at node positions `nodes`, has a corner turned
/// inside out (scaled Jacobian below 0).
fn has_inverted_corner(kind: carus_fem::ElementKind, element: &[u32], nodes: &[DVec3]) -> bool {
    // Every step for every element: no allocation (an H8 has the most nodes).
    let mut x = [[0.0; 3]; 8];
    for (corner, &i) in x.iter_mut().zip(element) {
        *corner = nodes[i as usize].to_array();
    }
    carus_fem::quality::scaled_jacobian(kind, &x[..element.len()]) < 0.0
}

/// How many elements of `mesh`, at node positions `nodes`, have a corner
/// turned inside out.
fn inverted_corner_elements(mesh: &carus_fem::Mesh, nodes: &[DVec3]) -> usize {
    mesh.elements()
        .filter(|element| has_inverted_corner(mesh.kind, element, nodes))
        .count()
}

/// Per node: whether it belongs to a crushed element, one whose volume
/// ratio J has fallen below `ratio` or which has a corner turned inside out
/// at node positions `nodes` (a sliver: volume kept, shape lost).
fn crushed_nodes(mesh: &carus_fem::Mesh, nodes: &[DVec3], jacobian: &[f64], ratio: f64) -> Vec<bool> {
    let mut crushed = vec![false; mesh.node_count()];
    for (element, &j) in mesh.elements().zip(jacobian) {
        if j < ratio || has_inverted_corner(mesh.kind, element, nodes) {
            for &i in element {
                crushed[i as usize] = true;
            }
        }
    }
    crushed
}

/// Says where a floor element turned inside out, what it means and what
/// held its nodes (`holders`: a description and the nodes it held in the
/// failing step); other solver errors pass through. The solver has gone
/// back to its last good state, whose stretch is what the element reached.
pub(crate) fn floor_failure(
    error: carus_fem::FemError,
    solver: &TledSolver,
    floor: &crate::scene::FloorScene,
    parameters: &carus_anatomy::floor::FloorParameters,
    holders: &[(&str, &[u32])],
) -> LabourError {
    let carus_fem::FemError::ElementInvertedDuringRun { element, time_s, .. } = error else {
        return error.into();
    };
    let Some(location) = carus_anatomy::floor::element_location(parameters, &floor.mesh, element) else {
        return error.into();
    };
    let stretch = solver.element_fields().max_principal_stretch[element];
    let [(lien, lien_source), (jing, jing_source)] = carus_anatomy::floor::LEVATOR_STRETCH_AT_CROWNING;
    let what = if stretch > lien {
        format!(
            "it had been stretched {stretch:.1} times, past the {lien} that a levator model of an \
             uncomplicated birth predicts at crowning ({lien_source}; {jing} at most in {jing_source}), \
             where real tissue is at risk of tearing; this elastic floor cannot tear"
        )
    } else {
        format!("it was squeezed flat (largest stretch {stretch:.1})")
    };
    let nodes = floor.mesh.element(element);
    let mut counts = vec![0usize; holders.len()];
    let (mut fixed, mut free) = (0, 0);
    for &i in nodes {
        match holders.iter().position(|(_, ids)| ids.contains(&i)) {
            Some(k) => counts[k] += 1,
            None if floor.attached[i as usize] => fixed += 1,
            None => free += 1,
        }
    }
    let mut parts: Vec<String> = holders
        .iter()
        .zip(&counts)
        .filter(|(_, &n)| n > 0)
        .map(|((what, _), n)| format!("{n} {what}"))
        .collect();
    for (n, what) in [(fixed, "fixed to bone"), (free, "free")] {
        if n > 0 {
            parts.push(format!("{n} {what}"));
        }
    }
    let what = format!("{what}; of its {} nodes, {}", nodes.len(), parts.join(", "));
    LabourError::FloorFailed {
        time_s,
        element,
        location,
        what: format!(
            "{what}. Everything simulated up to here is written and stands; docs/LABOUR.md \
             (\"What was tried\") lists the runs that end this way"
        ),
    }
}

/// The fewest sub-steps of a rigid step `dt` at or below the `stable`
/// sub-step, at most `most` (also for a shape with no stable step).
fn fewest_substeps(dt: f64, stable: f64, most: u32) -> u32 {
    if stable.is_nan() || stable <= 0.0 || dt / stable >= most as f64 {
        return most;
    }
    let mut n = ((dt / stable).ceil() as u32).max(1);
    // Rounding can leave dt / n a hair above the stable step.
    while n < most && dt / n as f64 > stable {
        n += 1;
    }
    n
}

/// How far below the built stable sub-step the one re-read on the shape
/// at rest may fall by rounding alone (relative): so little never refines.
const AT_REST_ROUNDING: f64 = 1e-9;

/// The sub-steps of a rigid step `dt` on the floor as it is now, whose
/// stable sub-step is `stable`: the `reference` ones, chosen for the
/// built shape's stable sub-step `reference_stable`, until the shape needs
/// more; then the fewest at or below `stable`, at most
/// [`MAX_SUBSTEP_REFINEMENT`] times the reference.
fn substeps_within(dt: f64, stable: f64, reference_stable: f64, reference: u32) -> u32 {
    if stable >= reference_stable * (1.0 - AT_REST_ROUNDING) {
        return reference;
    }
    fewest_substeps(dt, stable, reference.saturating_mul(MAX_SUBSTEP_REFINEMENT)).max(reference)
}

/// The floor's solver with a sub-step of `dt / n`, n the fewest sub-steps
/// at or below the chosen fraction of the critical step; returns it with n.
fn new_solver(
    scene: &Scene,
    floor: &crate::scene::FloorScene,
    dt: f64,
) -> Result<(TledSolver, u32), LabourError> {
    let h = scene.scenario.numerics.floor_step_fraction * floor.critical_step_s;
    if !h.is_finite() || h <= 0.0 {
        return Err(carus_fem::FemError::InvalidTimeStep { dt_s: h }.into());
    }
    let substeps = fewest_substeps(dt, h, u32::MAX);
    let solver = TledSolver::new(
        floor.model.clone(),
        &floor.bcs,
        dt / substeps as f64,
        StepControl::Refuse,
    )?;
    Ok((solver, substeps))
}

/// The fetal part bearing the largest of `forces`, one per body in the
/// scene's body order.
fn bearer(forces: impl Iterator<Item = DVec3>) -> FetalPart {
    let body = forces.enumerate().max_by(|(_, f), (_, g)| f.length().total_cmp(&g.length())).map_or(HEAD, |(b, _)| b);
    match Body::of(body) {
        Body::Head => FetalPart::Head,
        Body::Trunk | Body::LowerTrunk => FetalPart::Trunk,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference sub-steps while the floor keeps its shape (rounding
    /// at rest included); more, at or below the stable sub-step, once an
    /// element is pressed flat; never more than the cap, which also takes
    /// a shape with no stable step.
    #[test]
    fn sub_steps_follow_the_stable_step_within_their_bounds() {
        let dt = 5e-4;
        let built = dt / 9.0;
        assert_eq!(fewest_substeps(dt, built, u32::MAX), 9);
        assert_eq!(substeps_within(dt, built * 1.3, built, 9), 9);
        assert_eq!(substeps_within(dt, built, built, 9), 9);
        assert_eq!(substeps_within(dt, built * (1.0 - 1e-15), built, 9), 9);
        let cap = 9 * MAX_SUBSTEP_REFINEMENT;
        for k in 1..2000 {
            let stable = dt / (9.0 + 0.37 * k as f64);
            let n = substeps_within(dt, stable, built, 9);
            assert!(n >= 9 && n <= cap);
            if n < cap {
                assert!(dt / n as f64 <= stable && dt / (n - 1) as f64 > stable, "{k}: {n}");
            }
        }
        for stable in [0.0, -1.0, f64::NAN, dt / 1e9] {
            assert_eq!(substeps_within(dt, stable, built, 9), cap);
        }
    }

    /// Two H8 cells side by side share a face: crushing the second marks its
    /// eight nodes and the first cell's other four stay free.
    #[test]
    fn crushed_elements_mark_their_nodes() {
        let mesh = carus_fem::generate::box_h8([2.0, 1.0, 1.0], [2, 1, 1]);
        let nodes = reference_nodes(&mesh);
        let crushed = crushed_nodes(&mesh, &nodes, &[0.9, 0.3], 0.5);
        let second = mesh.element(1);
        for (i, c) in crushed.iter().enumerate() {
            assert_eq!(*c, second.contains(&(i as u32)), "node {i}");
        }
        assert_eq!(crushed.iter().filter(|c| !**c).count(), 4);
        assert!(crushed_nodes(&mesh, &nodes, &[0.9, 0.3], 0.0).iter().all(|c| !c));
    }

    /// The mesh's nodes where it was built.
    fn reference_nodes(mesh: &carus_fem::Mesh) -> Vec<DVec3> {
        mesh.nodes.iter().map(|&x| DVec3::from_array(x)).collect()
    }

    /// The second cell's corner farthest from the first along x, pushed
    /// back past the face the cells share: the nodes so moved.
    fn second_cell_with_a_corner_pushed_through(mesh: &carus_fem::Mesh) -> Vec<DVec3> {
        let mut nodes = reference_nodes(mesh);
        let corner = *mesh
            .element(1)
            .iter()
            .max_by(|&&a, &&b| mesh.nodes[a as usize][0].total_cmp(&mesh.nodes[b as usize][0]))
            .unwrap() as usize;
        nodes[corner].x = 0.5;
        nodes
    }

    /// A sliver counts as crushed though its J stays above the ratio.
    #[test]
    fn an_element_with_an_inverted_corner_is_crushed() {
        let mesh = carus_fem::generate::box_h8([2.0, 1.0, 1.0], [2, 1, 1]);
        let nodes = second_cell_with_a_corner_pushed_through(&mesh);
        let crushed = crushed_nodes(&mesh, &nodes, &[1.0, 0.9], 0.5);
        let second = mesh.element(1);
        for (i, c) in crushed.iter().enumerate() {
            assert_eq!(*c, second.contains(&(i as u32)), "node {i}");
        }
    }

    /// Pushing one corner of the second of two H8 cells through its
    /// opposite face inverts that corner alone: one element counted, though
    /// the cell keeps most of its volume.
    #[test]
    fn an_inverted_corner_is_counted() {
        let mesh = carus_fem::generate::box_h8([2.0, 1.0, 1.0], [2, 1, 1]);
        assert_eq!(inverted_corner_elements(&mesh, &reference_nodes(&mesh)), 0);
        let nodes = second_cell_with_a_corner_pushed_through(&mesh);
        assert_eq!(inverted_corner_elements(&mesh, &nodes), 1);
    }
}
