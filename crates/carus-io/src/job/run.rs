//! Building the model from a checked job and running it to the end (or to
//! the first solver failure), writing frames and history on the way.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use carus_fem::{
    BoundaryConditions, ElementKind, FemError, FixedDofs, ImposedDisplacement, LoadShape, Material,
    MaterialRegion, Mesh, ModelOptions, MooneyRivlin, NeoHookean, NodalForce, Precision,
    StepControl, SurfacePressure, TetFormulation, TledModel, TledSolver,
};
use carus_fem::solver::reported_time_s;
use serde::Serialize;

use super::load::{mesh_path, parse_job, read_job_text};
use super::spec::{
    JobSpec, Law, LoadSpec, OutputSpec, PrecisionSpec, TetSpec, TimeStep, AUTO_TIME_STEP_FRACTION,
};
use super::JobError;
use crate::builder::MeshFile;
use crate::csv::CsvWriter;
use crate::pvd::PvdCollection;
use crate::vtk::{write_vtu, FrameFields};

/// Options of a run that are not part of the job.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Set from outside (Ctrl-C) to end the run at the next step, with its
    /// state then written as the last frame and the report saying so.
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

/// Where a run stands, reported after every frame and history row.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub time_s: f64,
    pub end_time_s: f64,
    pub steps: u64,
    pub frames: usize,
}

/// What a run did: printed by `carus solve` (one JSON object with `--json`)
/// and written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct JobReport {
    pub out_dir: String,
    /// Frames written (VTU files in `frames/`).
    pub frames: usize,
    /// Steps of `dt_s` taken.
    pub steps: u64,
    pub simulated_s: f64,
    pub wall_s: f64,
    pub critical_dt_s: f64,
    pub dt_s: f64,
    /// Sub-steps per step (above 1 only with `sub_stepping = true`).
    pub substeps_per_step: u32,
    /// Largest nodal displacement magnitude at the end of the run, m.
    pub max_displacement_m: f64,
    /// Force the supports exert on the tissue at the end (sum of internal
    /// nodal forces), per fixed or displaced node set, N.
    pub reactions_n: BTreeMap<String, [f64; 3]>,
    pub element_kind: &'static str,
    /// The tetrahedron's formulation (`t4`, `t4anp`): null for H8.
    pub tet_formulation: Option<&'static str>,
    /// What the H8 hourglass control is scaled by (`shear`,
    /// `dilatational`): null for T4.
    pub hourglass_modulus: Option<&'static str>,
    pub elements: usize,
    pub nodes: usize,
    /// Why the run stopped early (the last frame holds the last good
    /// state), or null.
    pub failure: Option<String>,
    /// What the log should say: what the mesh reader skipped on purpose,
    /// and moduli that look given the wrong way round.
    #[serde(skip)]
    pub notes: Vec<String>,
}

fn load_shape(load: &LoadSpec) -> LoadShape {
    match *load {
        LoadSpec::Step => LoadShape::Step,
        LoadSpec::Ramp { duration_s } => LoadShape::Ramp { duration_s },
        LoadSpec::RampHold { ramp_s } => LoadShape::RampHold { ramp_s },
        LoadSpec::Smooth345 { duration_s } => LoadShape::Smooth345 { duration_s },
    }
}

/// The solver's message with the mesh file's own id of the element it names.
fn describe(error: &FemError, file: &MeshFile) -> String {
    let element = match error {
        FemError::InvertedElement { element, .. }
        | FemError::DegenerateElement { element, .. }
        | FemError::ElementInvertedDuringRun { element, .. }
        | FemError::MissingMaterial { element } => Some(*element),
        _ => None,
    };
    match element.and_then(|e| file.element_id(e).map(|id| (e, id))) {
        Some((e, id)) => format!(
            "{error} [element {e} is element {id} of {}]",
            file.source.display()
        ),
        None => error.to_string(),
    }
}

struct Sets<'a> {
    job: &'a Path,
    file: &'a MeshFile,
}

impl Sets<'_> {
    fn nodes(&self, key: String, name: &str) -> Result<Vec<u32>, JobError> {
        match self.file.mesh.node_sets.get(name) {
            Some(nodes) if !nodes.is_empty() => Ok(nodes.clone()),
            Some(_) => Err(JobError::Invalid {
                path: self.job.to_path_buf(),
                line: None,
                key,
                problem: format!("node set {name:?} is empty"),
                fix: "name a set with nodes on the meshed volume".into(),
            }),
            None => Err(JobError::UnknownSet {
                path: self.job.to_path_buf(),
                line: None,
                key,
                kind: "node set",
                name: name.to_string(),
                available: self.file.mesh.node_sets.keys().cloned().collect(),
            }),
        }
    }

    fn surface(&self, key: String, name: &str) -> Result<Vec<[u32; 3]>, JobError> {
        self.file.mesh
            .surfaces
            .get(name)
            .cloned()
            .ok_or_else(|| JobError::UnknownSet {
                path: self.job.to_path_buf(),
                line: None,
                key,
                kind: "surface",
                name: name.to_string(),
                available: self.file.mesh.surfaces.keys().cloned().collect(),
            })
    }

    fn check_element_set(&self, key: String, name: &str) -> Result<(), JobError> {
        if self.file.mesh.element_sets.contains_key(name) {
            return Ok(());
        }
        Err(JobError::UnknownSet {
            path: self.job.to_path_buf(),
            line: None,
            key,
            kind: "element set",
            name: name.to_string(),
            available: self.file.mesh.element_sets.keys().cloned().collect(),
        })
    }
}

/// A note for each material given by shear and bulk moduli whose Poisson
/// ratio, nu = (3K - 2mu) / (2 (3K + mu)), is below 0: a solid that widens
/// sideways as it is pulled. The solver takes it (any nu in (-1, 0.5) is a
/// stable solid), but soft tissue is nearly incompressible (Miller et al.
/// 2007 model it with nu = 0.49, VALIDATION.md V3: a bulk modulus 50 times
/// the shear), so such a pair is most likely the two moduli swapped.
fn auxetic_notes(spec: &JobSpec) -> Vec<String> {
    spec.materials
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let shear = match m.law {
                Law::NeoHookean => m.shear_modulus_pa?,
                Law::MooneyRivlin => 2.0 * (m.c10_pa? + m.c01_pa?),
            };
            let bulk = m.bulk_modulus_pa?;
            let poisson = (3.0 * bulk - 2.0 * shear) / (2.0 * (3.0 * bulk + shear));
            (poisson < 0.0).then(|| {
                format!(
                    "material[{i}]: bulk_modulus_pa = {bulk} with a small-strain shear modulus of {shear} Pa is a \
                     Poisson ratio of {poisson:.2}, a solid that widens as it is pulled; soft tissue is nearly \
                     incompressible (0.45-0.499, the bulk modulus tens of times the shear): check that the two \
                     are not swapped"
                )
            })
        })
        .collect()
}

/// Notes on imposed displacements larger than the whole mesh (`size_m`,
/// its bounding box's diagonal): a mesh read in the wrong `length_unit` (a
/// 0.1 m cube read in mm is 0.1 mm across) turns a modest pull into a
/// crush, and the run then fails as if the physics had.
fn displacement_notes(spec: &JobSpec, size_m: f64) -> Vec<String> {
    spec.displacements
        .iter()
        .enumerate()
        .filter_map(|(i, d)| {
            let length_m = [d.x_m, d.y_m, d.z_m].iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
            (size_m > 0.0 && length_m > size_m).then(|| {
                format!(
                    "displacement[{i}] on `{}` is {length_m:.3e} m, {:.0} times the mesh's size ({size_m:.3e} m \
                     corner to corner, with `mesh.length_unit = \"{}\"`): check that the unit is the mesh file's",
                    d.node_set,
                    length_m / size_m,
                    spec.mesh.length_unit.name()
                )
            })
        })
        .collect()
}

/// Notes on output intervals set shorter than the time step: each step
/// then writes a frame (or a history row), which for a long run is far
/// more files than asked for, and the spacing set is not kept. Defaults
/// (fractions of the run) are not noted: a short run may well fall below
/// them.
fn interval_notes(output: &OutputSpec, dt_s: f64, steps: u64) -> Vec<String> {
    [
        ("frame_interval_s", output.frame_interval_s, "frame"),
        ("history_interval_s", output.history_interval_s, "history row"),
    ]
    .into_iter()
    .filter_map(|(key, interval_s, what)| Some((key, interval_s?, what)))
    .filter(|&(_, interval_s, _)| interval_s < dt_s)
    .map(|(key, interval_s, what)| {
        format!(
            "output.{key} = {interval_s:.3e} s is shorter than the time step ({dt_s:.3e} s): a {what} was written \
             at every step ({steps} steps); set it to a multiple of the step to keep the spacing asked for"
        )
    })
    .collect()
}

fn materials(spec: &JobSpec, sets: &Sets) -> Result<Vec<MaterialRegion>, JobError> {
    let mut regions = Vec::with_capacity(spec.materials.len());
    for (i, m) in spec.materials.iter().enumerate() {
        if let Some(set) = &m.element_set {
            sets.check_element_set(format!("material[{i}].element_set"), set)?;
        }
        // The loader checked that exactly one parameter set is present.
        let material = match (
            m.law,
            m.shear_modulus_pa,
            m.bulk_modulus_pa,
            m.young_modulus_pa,
            m.poisson_ratio,
        ) {
            (Law::NeoHookean, Some(mu), Some(kappa), _, _) => Material::neo_hookean(mu, kappa),
            (Law::NeoHookean, _, _, Some(e), Some(nu)) => {
                Material::NeoHookean(NeoHookean::from_young_poisson(e, nu).map_err(|err| {
                    JobError::Invalid {
                        path: sets.job.to_path_buf(),
                        line: None,
                        key: format!("material[{i}]"),
                        problem: err.to_string(),
                        fix: "give valid moduli".into(),
                    }
                })?)
            }
            _ => Material::MooneyRivlin(MooneyRivlin {
                c10_pa: m.c10_pa.unwrap_or_default(),
                c01_pa: m.c01_pa.unwrap_or_default(),
                bulk_modulus_pa: m.bulk_modulus_pa.unwrap_or_default(),
            }),
        };
        regions.push(MaterialRegion {
            element_set: m.element_set.clone(),
            material,
            density_kg_m3: m.density_kg_m3,
        });
    }
    Ok(regions)
}

/// Node sets held by supports (fixed or displaced), by name: their
/// reactions are reported.
type Supports = Vec<(String, Vec<u32>)>;

/// Boundary conditions, and the supports whose reaction is reported.
fn boundary_conditions(
    spec: &JobSpec,
    sets: &Sets,
) -> Result<(BoundaryConditions, Supports), JobError> {
    let mut bcs = BoundaryConditions::default();
    let mut supports: Supports = Vec::new();
    let mut support = |name: &str, nodes: &[u32]| {
        if !supports.iter().any(|(n, _)| n == name) {
            supports.push((name.to_string(), nodes.to_vec()));
        }
    };
    // Which table holds each node's component: an imposed displacement on
    // a component another table holds would have one silently override
    // the other (two fixings agree, as where fixed faces share an edge).
    // Each held component names its table by index into `tables`.
    let mut tables: Vec<(String, bool)> = Vec::new();
    let mut held: BTreeMap<(u32, usize), usize> = BTreeMap::new();
    let mut hold = |table: String, nodes: &[u32], components: [bool; 3], displaced: bool| -> Result<(), JobError> {
        tables.push((table, displaced));
        let this = tables.len() - 1;
        for &node in nodes {
            for axis in (0..3).filter(|&a| components[a]) {
                let earlier = held.insert((node, axis), this).map(|i| &tables[i]);
                if let Some((first, _)) = earlier.filter(|(_, was_displaced)| displaced || *was_displaced) {
                    return Err(JobError::Invalid {
                        path: sets.job.to_path_buf(),
                        line: None,
                        key: format!("{}.node_set", tables[this].0),
                        problem: format!(
                            "node {} (the mesh file's number) is already held in {} by {first}",
                            sets.file.node_id(node as usize).unwrap_or(u64::from(node)),
                            ["x", "y", "z"][axis]
                        ),
                        fix: "hold each node's component in one table only: drop one, or give `[[fixed]]` \
                              the `components` the other leaves free"
                            .into(),
                    });
                }
            }
        }
        Ok(())
    };
    for (i, f) in spec.fixed.iter().enumerate() {
        let nodes = sets.nodes(format!("fixed[{i}].node_set"), &f.node_set)?;
        let mut components = [f.components.is_none(); 3];
        for axis in f.components.iter().flatten() {
            components[*axis as usize] = true;
        }
        hold(format!("fixed[{i}]"), &nodes, components, false)?;
        support(&f.node_set, &nodes);
        bcs.fixed.push(FixedDofs { nodes, components });
    }
    for (i, d) in spec.displacements.iter().enumerate() {
        let nodes = sets.nodes(format!("displacement[{i}].node_set"), &d.node_set)?;
        hold(format!("displacement[{i}]"), &nodes, [d.x_m, d.y_m, d.z_m].map(|c| c.is_some()), true)?;
        support(&d.node_set, &nodes);
        bcs.displacements.push(ImposedDisplacement {
            nodes,
            components: [d.x_m, d.y_m, d.z_m],
            shape: load_shape(&d.load),
        });
    }
    for (i, f) in spec.forces.iter().enumerate() {
        let nodes = sets.nodes(format!("force[{i}].node_set"), &f.node_set)?;
        let force_n = match (f.force_per_node_n, f.total_force_n) {
            (Some(per_node), _) => per_node,
            (None, Some(total)) => total.map(|v| v / nodes.len() as f64),
            (None, None) => [0.0; 3],
        };
        bcs.forces.push(NodalForce {
            nodes,
            force_n,
            shape: load_shape(&f.load),
        });
    }
    for (i, p) in spec.pressures.iter().enumerate() {
        bcs.pressures.push(SurfacePressure {
            triangles: sets.surface(format!("pressure[{i}].surface"), &p.surface)?,
            pressure_pa: p.pressure_pa,
            shape: load_shape(&p.load),
        });
    }
    bcs.gravity_m_s2 = spec.gravity.as_ref().map(|g| g.acceleration_m_s2);
    Ok((bcs, supports))
}

/// The folder of a run's frames, in its output folder.
pub const FRAMES_DIR: &str = "frames";
/// The frames as a ParaView time series.
pub const SOLUTION_PVD: &str = "solution.pvd";
/// The time histories.
pub const HISTORY_FILE: &str = "history.csv";
/// The report, as `--json` prints it.
pub const SUMMARY_FILE: &str = "summary.json";

/// The name in [`FRAMES_DIR`] of frame `k`.
fn frame_name(k: usize) -> String {
    format!("frame_{k:05}.vtu")
}

/// Whether `name` is one of a run's frames (`frame_00012.vtu`).
pub fn is_frame_name(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|rest| rest.strip_suffix(".vtu"))
        .is_some_and(|k| k.len() >= 5 && k.bytes().all(|b| b.is_ascii_digit()))
}

/// Whether `dir` exists and holds anything.
fn occupied(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_some())
}

/// Refuses an output folder that holds anything: replacing one is the
/// caller's to decide (`carus solve --force` replaces only a folder carus
/// made, and nothing a user added to it).
fn refuse_occupied(dir: &Path) -> Result<(), JobError> {
    match occupied(dir) {
        true => Err(JobError::OutDirExists {
            dir: dir.to_path_buf(),
        }),
        false => Ok(()),
    }
}

/// A column name from a set name (letters, digits and `_` only).
fn column(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn max_norm(u: &[[f64; 3]]) -> f64 {
    u.iter()
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max)
}

/// Frames, PVD and history of a running job.
struct Recorder {
    out_dir: PathBuf,
    pvd: PvdCollection,
    history: CsvWriter,
    supports: Supports,
    last_frame_time_s: Option<f64>,
    last_history_time_s: Option<f64>,
    reactions: BTreeMap<String, [f64; 3]>,
}

impl Recorder {
    fn frame(&mut self, solver: &TledSolver, mesh: &Mesh) -> Result<(), JobError> {
        let name = format!("{FRAMES_DIR}/{}", frame_name(self.pvd.frames().len()));
        let displacement = solver.displacements();
        let fields = solver.element_fields();
        write_vtu(
            &self.out_dir.join(&name),
            mesh,
            &FrameFields {
                displacement_m: &displacement,
                von_mises_pa: &fields.von_mises_pa,
                max_principal_stretch: &fields.max_principal_stretch,
                jacobian: &fields.jacobian,
                time_s: Some(reported_time_s(solver.time_s())),
            },
        )?;
        // Listed once its frame is written, and the list written whole.
        let mut listed = self.pvd.clone();
        listed.push(reported_time_s(solver.time_s()), name);
        listed.write(&self.out_dir.join(SOLUTION_PVD))?;
        self.pvd = listed;
        self.last_frame_time_s = Some(solver.time_s());
        Ok(())
    }

    fn history(&mut self, solver: &mut TledSolver) -> Result<(), JobError> {
        let energies = solver.energies();
        let forces_ok = solver.update_internal_forces().is_ok();
        let mut row = vec![
            reported_time_s(solver.time_s()),
            solver.steps() as f64,
            max_norm(&solver.displacements()),
            energies.kinetic_j,
            energies.strain_j,
            energies.hourglass_j,
        ];
        for (name, nodes) in &self.supports {
            let reaction = match solver.reaction_force(nodes) {
                Ok(r) if forces_ok => r,
                _ => [f64::NAN; 3],
            };
            self.reactions.insert(name.clone(), reaction);
            row.extend_from_slice(&reaction);
        }
        self.history.row(&row)?;
        self.last_history_time_s = Some(solver.time_s());
        Ok(())
    }

    /// The frame and history row the end of a run owes, unless the last
    /// ones were taken at its time: the summary's reactions are the end's.
    fn close(&mut self, solver: &mut TledSolver, mesh: &Mesh) -> Result<(), JobError> {
        if self.last_frame_time_s != Some(solver.time_s()) {
            self.frame(solver, mesh)?;
        }
        if self.last_history_time_s != Some(solver.time_s()) {
            self.history(solver)?;
        }
        Ok(())
    }
}

/// The model and solver of a checked job on its mesh (in metres), and the
/// supports whose reactions are reported.
fn build_solver(
    job_path: &Path,
    spec: &JobSpec,
    file: &MeshFile,
) -> Result<(TledSolver, Supports), JobError> {
    let mesh = &file.mesh;
    let sets = Sets { job: job_path, file };
    let regions = materials(spec, &sets)?;
    let (bcs, supports) = boundary_conditions(spec, &sets)?;
    let solver_spec = &spec.solver;
    let model_options = ModelOptions {
        tet_formulation: match solver_spec.tet_formulation {
            TetSpec::T4 => TetFormulation::T4,
            TetSpec::T4anp => TetFormulation::T4Anp,
        },
        hourglass_coefficient: solver_spec.hourglass_coefficient,
        hourglass_modulus: solver_spec.hourglass_modulus,
        damping_per_s: solver_spec.damping_per_s,
        precision: match solver_spec.precision {
            PrecisionSpec::F64 => Precision::F64,
            PrecisionSpec::F32 => Precision::F32,
        },
    };
    let model_error = |e: FemError| JobError::Model {
        path: file.source.clone(),
        message: describe(&e, file),
    };
    let model = TledModel::new(mesh, &regions, &model_options).map_err(model_error)?;
    // A material far too stiff or too light (another unit, a slip of
    // digits) makes the stable step so small that the run could not end.
    let critical_s = model.critical_time_step();
    let steps = solver_spec.end_time_s / critical_s;
    if steps.is_nan() || steps > super::load::MAX_STEPS {
        return Err(JobError::Invalid {
            path: job_path.to_path_buf(),
            line: None,
            key: "materials".into(),
            problem: format!(
                "the stable time step is {critical_s:.3e} s, so {} s would take {steps:.1e} steps: \
                 solver.end_time_s is far too long, or a material's stiffness is far too high or its \
                 density far too low (the step is an element's size over the wave speed, \
                 sqrt(E / density))",
                crate::text::shown_number(solver_spec.end_time_s)
            ),
            fix: "check solver.end_time_s (seconds), each material's young_modulus_pa (Pa) and \
                  density_kg_m3 (kg/m^3), and solver.hourglass_coefficient"
                .into(),
        });
    }
    let (dt_s, control) = match solver_spec.time_step_s {
        // A whole number of steps, each at most the fraction of the critical
        // one, so the run ends on end_time_s itself (and a run shorter than
        // one such step is one step).
        TimeStep::Auto => {
            let end_s = solver_spec.end_time_s;
            (end_s / (end_s / (AUTO_TIME_STEP_FRACTION * critical_s)).ceil(), StepControl::Refuse)
        }
        TimeStep::Seconds(dt) if solver_spec.sub_stepping => (dt, StepControl::SubStep),
        TimeStep::Seconds(dt) => (dt, StepControl::Refuse),
    };
    let solver = TledSolver::new(Arc::new(model), &bcs, dt_s, control).map_err(|e| match e {
        FemError::TimeStepAboveCritical { .. } => JobError::Invalid {
            path: job_path.to_path_buf(),
            line: None,
            key: "solver.time_step_s".into(),
            problem: e.to_string(),
            fix: "lower time_step_s, set it to \"auto\", or set solver.sub_stepping = true".into(),
        },
        other => model_error(other),
    })?;
    Ok((solver, supports))
}

/// A job read, checked and its model built, not yet run: all that can be
/// refused about a job is refused before its output folder is touched.
pub struct PreparedJob {
    spec: JobSpec,
    file: MeshFile,
    solver: TledSolver,
    supports: Supports,
    /// When reading began: the run's wall time counts reading and building.
    start: Instant,
}

/// Reads the job file at `job_path` and builds its model (see
/// [`PreparedJob::run_into`]).
pub fn prepare_job(job_path: &Path) -> Result<PreparedJob, JobError> {
    prepare(job_path, || Ok(()))
}

/// [`prepare_job`], with `before_build` checked between the job's own
/// errors and the (possibly long) model build.
fn prepare(job_path: &Path, before_build: impl FnOnce() -> Result<(), JobError>) -> Result<PreparedJob, JobError> {
    let start = Instant::now();
    let text = read_job_text(job_path)?;
    let spec = parse_job(job_path, &text)?;
    before_build()?;
    let file = crate::read_mesh(&mesh_path(job_path, &spec))?.to_metres(spec.mesh.length_unit);
    let (solver, supports) = build_solver(job_path, &spec, &file).map_err(|e| e.at_line_in(&text))?;
    Ok(PreparedJob { spec, file, solver, supports, start })
}

/// Runs the job file at `job_path`, writing into `out_dir`, which must be
/// new or empty (refused before the model is built):
/// `frames/frame_NNNNN.vtu`, `solution.pvd`, `history.csv` and
/// `summary.json`. A solver failure mid-run still writes the last good
/// state as the final frame and returns a report whose `failure` is set.
pub fn run_job(
    job_path: &Path,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<JobReport, JobError> {
    prepare(job_path, || refuse_occupied(out_dir))?.run_into(out_dir, options, progress)
}

impl PreparedJob {
    /// Runs the job into `out_dir` (made if it is not there), as
    /// [`run_job`] does; the caller has made sure that it holds nothing
    /// the run could overwrite.
    pub fn run_into(self, out_dir: &Path, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<JobReport, JobError> {
        let PreparedJob { spec, file, mut solver, supports, start } = self;
        let mesh = &file.mesh;
        let critical_dt_s = solver.model().critical_time_step();
        let dt_s = solver.dt_s();

        std::fs::create_dir_all(out_dir.join(FRAMES_DIR)).map_err(|cause| JobError::OutDir {
            dir: out_dir.to_path_buf(),
            cause,
        })?;
        let end_s = spec.solver.end_time_s;
        let frame_interval_s = spec.output.frame_interval_s.unwrap_or(end_s / 20.0);
        let history_interval_s = spec
            .output
            .history_interval_s
            .unwrap_or(frame_interval_s / 10.0);
        let mut header: Vec<String> = [
            "time_s",
            "step",
            "max_displacement_m",
            "kinetic_j",
            "strain_j",
            "hourglass_j",
        ]
        .map(String::from)
        .to_vec();
        for (name, _) in &supports {
            for axis in ["x", "y", "z"] {
                header.push(format!("reaction_{}_{axis}_n", column(name)));
            }
        }
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        let mut recorder = Recorder {
            out_dir: out_dir.to_path_buf(),
            pvd: PvdCollection::new(),
            history: CsvWriter::create(&out_dir.join(HISTORY_FILE), &header)?,
            supports,
            last_frame_time_s: None,
            last_history_time_s: None,
            reactions: BTreeMap::new(),
        };
        recorder.frame(&solver, mesh)?;
        recorder.history(&mut solver)?;
        let (mut next_frame, mut next_history) = (1u64, 1u64);
        let mut failure = None;
        // An output that cannot be written stops the run; what was written
        // before it is kept, and the summary says where it stopped.
        let mut output_failed = None;
        // Half a step of slack: the run ends on the step nearest end_time_s.
        while solver.time_s() + 0.5 * dt_s < end_s {
            if options.stop.as_ref().is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed)) {
                failure = Some(format!(
                    "stopped by the user at t = {:.6e} s (step {}); the last frame holds that state",
                    solver.time_s(),
                    solver.steps()
                ));
                break;
            }
            if let Err(e) = solver.step() {
                failure = Some(format!(
                    "{} (step {} of dt = {dt_s:.3e} s; the last frame holds the state at t = {:.6e} s)",
                    describe(&e, &file),
                    solver.steps() + 1,
                    solver.time_s()
                ));
                break;
            }
            let t = solver.time_s() + 0.5 * dt_s;
            let due_history = t >= next_history as f64 * history_interval_s;
            let due_frame = t >= next_frame as f64 * frame_interval_s;
            let written = (|| {
                if due_history {
                    recorder.history(&mut solver)?;
                    next_history = (t / history_interval_s).floor() as u64 + 1;
                }
                if due_frame {
                    recorder.frame(&solver, mesh)?;
                    next_frame = (t / frame_interval_s).floor() as u64 + 1;
                }
                Ok::<(), JobError>(())
            })();
            if let Err(e) = written {
                failure = Some(format!(
                    "{e}; the run stopped at t = {:.6e} s (step {}): the frames and history rows before it are kept",
                    solver.time_s(),
                    solver.steps()
                ));
                output_failed = Some(e);
                break;
            }
            let recorded = due_history || due_frame;
            if recorded {
                progress(&Progress {
                    time_s: solver.time_s(),
                    end_time_s: end_s,
                    steps: solver.steps(),
                    frames: recorder.pvd.frames().len(),
                });
            }
        }
        if output_failed.is_none() {
            let closed = recorder.close(&mut solver, mesh).and_then(|()| Ok(recorder.history.flush()?));
            if let Err(e) = closed {
                let stopped = format!("{e}: the last frame or history row was not written, the ones before are kept");
                failure = Some(failure.map_or(stopped.clone(), |f| format!("{f}; then {stopped}")));
                output_failed = Some(e);
            }
        } else {
            // The rows before the failure, whole; the failure itself is the error kept.
            let _ = recorder.history.flush();
        }
        let report = JobReport {
            out_dir: out_dir.display().to_string(),
            frames: recorder.pvd.frames().len(),
            steps: solver.steps(),
            simulated_s: reported_time_s(solver.time_s()),
            wall_s: start.elapsed().as_secs_f64(),
            critical_dt_s,
            dt_s,
            substeps_per_step: solver.substeps_per_step(),
            max_displacement_m: max_norm(&solver.displacements()),
            reactions_n: recorder.reactions.clone(),
            element_kind: mesh.kind.name(),
            tet_formulation: (mesh.kind == ElementKind::T4).then_some(match spec.solver.tet_formulation {
                TetSpec::T4 => "t4",
                TetSpec::T4anp => "t4anp",
            }),
            hourglass_modulus: (mesh.kind == ElementKind::H8).then(|| spec.solver.hourglass_modulus.name()),
            elements: mesh.element_count(),
            nodes: mesh.node_count(),
            failure,
            notes: file
                .notes
                .iter()
                .cloned()
                .chain(auxetic_notes(&spec))
                .chain(displacement_notes(&spec, solver.model().size_m()))
                .chain(interval_notes(&spec.output, dt_s, solver.steps()))
                .collect(),
        };
        let summary = out_dir.join(SUMMARY_FILE);
        let json = serde_json::to_string_pretty(&report).unwrap_or_default();
        let written = std::fs::write(&summary, json + "\n");
        if written.is_err() {
            // Half a summary would read as a damaged one.
            let _ = std::fs::remove_file(&summary);
        }
        match (written, output_failed) {
            (Ok(()), _) => Ok(report),
            // With no room for the summary either, the first failure is the one to fix.
            (Err(_), Some(first)) => Err(first),
            (Err(cause), None) => Err(crate::WriteError::Io { path: summary, cause }.into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `carus solve --force` tells a run's frames from files put beside them.
    #[test]
    fn a_frame_is_known_by_its_name() {
        assert!(is_frame_name(&frame_name(0)) && is_frame_name(&frame_name(123_456)));
        for name in ["frame_1.vtu", "frame_00001.vtk", "my_frame_00001.vtu", "frame_0000a.vtu", "frame_.vtu"] {
            assert!(!is_frame_name(name), "{name}");
        }
    }

    #[test]
    fn set_names_become_csv_columns() {
        assert_eq!(column("x0"), "x0");
        assert_eq!(column("left face,1"), "left_face_1");
    }

    /// Shear and bulk moduli the wrong way round are noted; tissue-like
    /// ones, and a Poisson ratio given outright, are not.
    #[test]
    fn swapped_moduli_are_noted() {
        let job = |material: &str| {
            let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cube_n5.msh");
            let text = format!("[mesh]\nfile = \"{mesh}\"\nlength_unit = \"m\"\n[[material]]\n{material}density_kg_m3 = 1000.0\n[solver]\nend_time_s = 1.0\n");
            crate::job::load::parse_job(Path::new("job.toml"), &text).unwrap()
        };
        let swapped = auxetic_notes(&job("law = \"neo_hookean\"\nshear_modulus_pa = 50000.0\nbulk_modulus_pa = 1000.0\n"));
        assert_eq!(swapped.len(), 1);
        assert!(swapped[0].starts_with("material[0]: bulk_modulus_pa = 1000") && swapped[0].contains("Poisson ratio of -0.92"), "{swapped:?}");
        assert!(auxetic_notes(&job("law = \"neo_hookean\"\nshear_modulus_pa = 1000.0\nbulk_modulus_pa = 50000.0\n")).is_empty());
        assert!(auxetic_notes(&job("law = \"neo_hookean\"\nyoung_modulus_pa = 3000.0\npoisson_ratio = -0.2\n")).is_empty());
        let mooney = job("law = \"mooney_rivlin\"\nc10_pa = 500.0\nc01_pa = 500.0\nbulk_modulus_pa = 100.0\n");
        assert_eq!(auxetic_notes(&mooney).len(), 1);
    }

    /// A `[[fixed]]` table holds the components it names, in the solver's
    /// x, y, z order whatever order the file lists them in.
    #[test]
    fn fixed_components_hold_the_axes_named() {
        let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cube_n5.msh");
        let text = format!(
            "[mesh]\nfile = \"{mesh}\"\nlength_unit = \"m\"\n[[material]]\nlaw = \"neo_hookean\"\nshear_modulus_pa = 1000.0\nbulk_modulus_pa = 50000.0\ndensity_kg_m3 = 1000.0\n\
             [[fixed]]\nnode_set = \"x0\"\ncomponents = [\"z\", \"x\"]\n[[fixed]]\nnode_set = \"x1\"\ncomponents = [\"y\"]\n[solver]\nend_time_s = 1.0\n"
        );
        let spec = parse_job(Path::new("job.toml"), &text).unwrap();
        let file = crate::read_mesh(Path::new(mesh)).unwrap();
        let (bcs, _) = boundary_conditions(&spec, &Sets { job: Path::new("job.toml"), file: &file }).unwrap();
        let held: Vec<[bool; 3]> = bcs.fixed.iter().map(|f| f.components).collect();
        assert_eq!(held, [[true, false, true], [false, true, false]]);
    }
}
