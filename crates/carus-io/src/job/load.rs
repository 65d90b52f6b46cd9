//! Reading a job file: TOML syntax and unknown keys (with the key's path,
//! its line and column, and the nearest valid key), then impossible values.

use std::path::{Path, PathBuf};

use super::spec::{DisplacementSpec, ForceSpec, JobSpec, Law, LoadSpec, MaterialSpec, TimeStep};
use super::JobError;

/// Reads and checks a job file.
pub fn load_job(path: &Path) -> Result<JobSpec, JobError> {
    parse_job(path, &read_job_text(path)?)
}

/// A job file's text.
pub(crate) fn read_job_text(path: &Path) -> Result<String, JobError> {
    crate::input::read_text(path).map_err(|cause| JobError::Io {
        path: path.to_path_buf(),
        cause,
    })
}

/// Parses and checks job-file text; `path` names it in errors and is
/// where a relative `mesh.file` is looked for from (which must exist).
pub fn parse_job(path: &Path, text: &str) -> Result<JobSpec, JobError> {
    let deserializer =
        toml::Deserializer::parse(text).map_err(|e| toml_error(path, text, String::new(), &e))?;
    let spec: JobSpec = serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let key = e.path().to_string();
        another_kind_of_file(path, text).unwrap_or_else(|| toml_error(path, text, key, e.inner()))
    })?;
    check_values(path, &spec).map_err(|e| e.at_line_in(text))?;
    Ok(spec)
}

/// A file of another kind given for a job (a labour scenario, a pelvis's
/// landmarks file), named as what it is with the command that takes it,
/// instead of its first key the job does not know.
fn another_kind_of_file(path: &Path, text: &str) -> Option<JobError> {
    let table: toml::Table = text.parse().ok()?;
    let has = |key: &str| table.contains_key(key);
    let name = path.display();
    let (message, hint) = if has("mesh") && (has("axes") || has("landmarks")) {
        (
            "this is a pelvis's landmarks file (a `mesh` with its [axes] and [landmarks]), not a `carus solve` job".to_string(),
            "a labour scenario imports it (`[pelvis] import = ...`, docs/IMPORT.md); `carus measure pelvis` measures a file that does; a job's [mesh] names a volume mesh (docs/SOLVE.md)".to_string(),
        )
    } else if !has("name") && !table.is_empty() && table.keys().all(|k| ["pelvis", "head", "floor"].contains(&k.as_str())) {
        (
            "this is an anatomy file ([pelvis], [head], [floor]), not a `carus solve` job".to_string(),
            format!("`carus measure`, `carus mesh` and `carus render` read it (`carus mesh floor {name} --out DIR` writes the pelvic floor's volume mesh); `carus solve` takes a job with [mesh], [[material]] and [solver] (docs/SOLVE.md)"),
        )
    } else if has("name") || ["pelvis", "head", "expulsion", "trajectory", "start", "numerics"].iter().any(|k| has(k)) {
        (
            "this is a labour scenario (it has a `name` or a scenario's tables), not a `carus solve` job".to_string(),
            format!("run it with `carus run {name}`; `carus solve` takes a job with [mesh], [[material]] and [solver] (docs/SOLVE.md)"),
        )
    } else {
        return None;
    };
    Some(JobError::Syntax { path: path.to_path_buf(), line: 1, column: 1, key: String::new(), message, hint })
}

/// The most steps a job may take: at the cube benchmark's 0.035 us per
/// element-step (docs/PERFORMANCE.md), ten hours of one core for a mesh
/// of a thousand elements; more is a slip of units or digits.
pub(crate) const MAX_STEPS: f64 = 1e9;

fn toml_error(path: &Path, text: &str, key: String, error: &toml::de::Error) -> JobError {
    let (line, column) = match error.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = crate::input::line_at(text.as_bytes(), span.start);
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            (line, column)
        }
        None => (0, 0),
    };
    let (message, hint) = match crate::toml_text::written_twice(text, error) {
        Some(twice) => {
            let (message, fix) = twice.message_and_fix();
            (message, fix.to_string())
        }
        None => {
            let message = error.message().trim().to_string();
            let hint = hint_for(&message);
            (message, hint)
        }
    };
    JobError::Syntax {
        path: path.to_path_buf(),
        line,
        column,
        key: if key == "." { String::new() } else { key },
        message,
        hint,
    }
}

/// A hint for serde's messages: the nearest expected key for an unknown
/// one, the unit convention for everything else.
fn hint_for(message: &str) -> String {
    const UNITS: &str = "keys carry their SI unit in their name (`_m`, `_s`, `_pa`, `_n`, `_kg_m3`); see docs/SOLVE.md";
    if message.starts_with("unknown variant") {
        return "use one of the values listed".to_string();
    }
    if message.starts_with("invalid type") {
        return format!("write numbers without quotes and names in quotes; {UNITS}");
    }
    let Some(rest) = message.strip_prefix("unknown field `") else {
        return UNITS.to_string();
    };
    let unknown = rest.split('`').next().unwrap_or_default();
    let expected: Vec<&str> = message
        .split("expected ")
        .nth(1)
        .unwrap_or_default()
        .split('`')
        .skip(1)
        .step_by(2)
        .collect();
    match expected.iter().min_by_key(|k| edit_distance(unknown, k)) {
        Some(best) if edit_distance(unknown, best) <= unknown.len().max(3) / 2 + 2 => {
            format!("did you mean `{best}`? ({UNITS})")
        }
        _ => UNITS.to_string(),
    }
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

struct Checker<'a> {
    path: &'a Path,
}

impl Checker<'_> {
    fn fail(&self, key: String, problem: String, fix: &str) -> JobError {
        JobError::Invalid {
            path: self.path.to_path_buf(),
            line: None,
            key,
            problem,
            fix: fix.to_string(),
        }
    }

    fn positive(&self, key: String, value: f64) -> Result<(), JobError> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(self.fail(
                key,
                format!("{value} must be positive and finite"),
                "give a positive value",
            ))
        }
    }

    fn non_negative(&self, key: String, value: f64) -> Result<(), JobError> {
        if value.is_finite() && value >= 0.0 {
            Ok(())
        } else {
            Err(self.fail(
                key,
                format!("{value} must be zero or positive"),
                "give a value >= 0",
            ))
        }
    }

    fn finite(&self, key: String, values: &[f64]) -> Result<(), JobError> {
        match values.iter().find(|v| !v.is_finite()) {
            Some(v) => Err(self.fail(
                key,
                format!("{v} is not a finite number"),
                "give finite numbers",
            )),
            None => Ok(()),
        }
    }

    fn load(&self, key: String, load: &LoadSpec) -> Result<(), JobError> {
        match *load {
            LoadSpec::Step => Ok(()),
            LoadSpec::Ramp { duration_s } | LoadSpec::Smooth345 { duration_s } => {
                self.non_negative(format!("{key}.duration_s"), duration_s)
            }
            LoadSpec::RampHold { ramp_s } => self.non_negative(format!("{key}.ramp_s"), ramp_s),
        }
    }

    fn material(&self, key: &str, m: &MaterialSpec) -> Result<(), JobError> {
        self.positive(format!("{key}.density_kg_m3"), m.density_kg_m3)?;
        let given = |v: Option<f64>| v.is_some();
        match m.law {
            Law::NeoHookean => {
                let moduli = given(m.shear_modulus_pa) && given(m.bulk_modulus_pa);
                let engineering = given(m.young_modulus_pa) && given(m.poisson_ratio);
                let stray = given(m.c10_pa) || given(m.c01_pa);
                if moduli == engineering || stray {
                    return Err(self.fail(
                        key.to_string(),
                        "a neo_hookean material needs either shear_modulus_pa and bulk_modulus_pa, or young_modulus_pa and poisson_ratio (and nothing else)".into(),
                        "give exactly one of the two pairs",
                    ));
                }
                let one_of_each = (given(m.shear_modulus_pa) || given(m.bulk_modulus_pa))
                    && (given(m.young_modulus_pa) || given(m.poisson_ratio));
                if one_of_each {
                    return Err(self.fail(
                        key.to_string(),
                        "moduli from both pairs are given (shear/bulk and Young/Poisson), and one pair fixes the other".into(),
                        "keep either shear/bulk or Young/Poisson",
                    ));
                }
                if let (Some(mu), Some(kappa)) = (m.shear_modulus_pa, m.bulk_modulus_pa) {
                    self.positive(format!("{key}.shear_modulus_pa"), mu)?;
                    self.positive(format!("{key}.bulk_modulus_pa"), kappa)?;
                }
                if let (Some(e), Some(nu)) = (m.young_modulus_pa, m.poisson_ratio) {
                    self.positive(format!("{key}.young_modulus_pa"), e)?;
                    if !(nu > -1.0 && nu < 0.5) {
                        return Err(self.fail(
                            format!("{key}.poisson_ratio"),
                            format!("{nu} lies outside (-1, 0.5)"),
                            "for nearly incompressible tissue use 0.45-0.499, or give shear and bulk moduli",
                        ));
                    }
                }
            }
            Law::MooneyRivlin => {
                let (Some(c10), Some(c01), Some(kappa)) = (m.c10_pa, m.c01_pa, m.bulk_modulus_pa)
                else {
                    return Err(self.fail(
                        key.to_string(),
                        "a mooney_rivlin material needs c10_pa, c01_pa and bulk_modulus_pa".into(),
                        "give all three",
                    ));
                };
                if given(m.shear_modulus_pa) || given(m.young_modulus_pa) || given(m.poisson_ratio)
                {
                    return Err(self.fail(
                        key.to_string(),
                        "a mooney_rivlin material takes c10_pa, c01_pa and bulk_modulus_pa only"
                            .into(),
                        "remove the other moduli",
                    ));
                }
                self.non_negative(format!("{key}.c10_pa"), c10)?;
                self.non_negative(format!("{key}.c01_pa"), c01)?;
                self.positive(format!("{key}.c10_pa + c01_pa"), c10 + c01)?;
                self.positive(format!("{key}.bulk_modulus_pa"), kappa)?;
            }
        }
        Ok(())
    }

    fn displacement(&self, key: &str, d: &DisplacementSpec) -> Result<(), JobError> {
        let components: Vec<f64> = [d.x_m, d.y_m, d.z_m].into_iter().flatten().collect();
        if components.is_empty() {
            return Err(self.fail(
                key.to_string(),
                "no component is imposed".into(),
                "give at least one of x_m, y_m, z_m",
            ));
        }
        self.finite(key.to_string(), &components)?;
        self.load(format!("{key}.load"), &d.load)
    }

    fn force(&self, key: &str, f: &ForceSpec) -> Result<(), JobError> {
        match (f.force_per_node_n, f.total_force_n) {
            (Some(v), None) | (None, Some(v)) => self.finite(key.to_string(), &v)?,
            _ => {
                return Err(self.fail(
                    key.to_string(),
                    "give either force_per_node_n or total_force_n".into(),
                    "keep exactly one of the two",
                ))
            }
        }
        self.load(format!("{key}.load"), &f.load)
    }
}

fn check_values(path: &Path, spec: &JobSpec) -> Result<(), JobError> {
    let c = Checker { path };
    if spec.mesh.file.trim().is_empty() {
        return Err(c.fail(
            "mesh.file".into(),
            "is empty".into(),
            "give the mesh file's path, relative to the job file",
        ));
    }
    let mesh = mesh_path(path, spec);
    if !mesh.exists() {
        return Err(c.fail(
            "mesh.file".into(),
            format!("{:?} names {}, which does not exist", spec.mesh.file, mesh.display()),
            match Path::new(&spec.mesh.file).is_absolute() {
                true => "give the path of the mesh file",
                false => "a relative path starts at the job file's folder, not the current one",
            },
        ));
    }
    if spec.materials.is_empty() {
        return Err(c.fail(
            "material".into(),
            "the job has no [[material]] table".into(),
            "add one, e.g. [[material]] law = \"neo_hookean\", shear_modulus_pa = ..., bulk_modulus_pa = ..., density_kg_m3 = ...",
        ));
    }
    for (i, m) in spec.materials.iter().enumerate() {
        c.material(&format!("material[{i}]"), m)?;
    }
    for (i, f) in spec.fixed.iter().enumerate() {
        if f.components.as_ref().is_some_and(Vec::is_empty) {
            return Err(c.fail(
                format!("fixed[{i}].components"),
                "is empty".into(),
                "list the fixed components, e.g. [\"x\", \"y\", \"z\"], or leave the key out to fix all three",
            ));
        }
        let listed = f.components.as_deref().unwrap_or_default();
        if let Some(twice) = listed.iter().enumerate().find_map(|(k, a)| listed[..k].contains(a).then_some(a)) {
            return Err(c.fail(
                format!("fixed[{i}].components"),
                format!("names \"{}\" twice", format!("{twice:?}").to_lowercase()),
                "list each fixed component once, e.g. [\"x\", \"y\"]",
            ));
        }
    }
    for (i, d) in spec.displacements.iter().enumerate() {
        c.displacement(&format!("displacement[{i}]"), d)?;
    }
    for (i, f) in spec.forces.iter().enumerate() {
        c.force(&format!("force[{i}]"), f)?;
    }
    for (i, p) in spec.pressures.iter().enumerate() {
        c.finite(format!("pressure[{i}].pressure_pa"), &[p.pressure_pa])?;
        c.load(format!("pressure[{i}].load"), &p.load)?;
    }
    if let Some(g) = &spec.gravity {
        c.finite("gravity.acceleration_m_s2".into(), &g.acceleration_m_s2)?;
    }
    let s = &spec.solver;
    c.positive("solver.end_time_s".into(), s.end_time_s)?;
    if let TimeStep::Seconds(dt) = s.time_step_s {
        c.positive("solver.time_step_s".into(), dt)?;
        if s.end_time_s / dt > MAX_STEPS {
            return Err(c.fail(
                "solver.time_step_s".into(),
                format!("{dt:e} s would take {:.1e} steps to reach end_time_s = {} s", s.end_time_s / dt, s.end_time_s),
                "a step near the critical one, or \"auto\"",
            ));
        }
        if dt > s.end_time_s {
            return Err(c.fail(
                "solver.time_step_s".into(),
                format!("{dt} s is longer than the run ({} s)", s.end_time_s),
                "use a step below end_time_s, or \"auto\"",
            ));
        }
    }
    c.non_negative("solver.damping_per_s".into(), s.damping_per_s)?;
    c.non_negative(
        "solver.hourglass_coefficient".into(),
        s.hourglass_coefficient,
    )?;
    if let Some(v) = spec.output.frame_interval_s {
        c.positive("output.frame_interval_s".into(), v)?;
    }
    if let Some(v) = spec.output.history_interval_s {
        c.positive("output.history_interval_s".into(), v)?;
    }
    Ok(())
}

/// The mesh file's path: relative paths start at the job file's folder.
pub fn mesh_path(job_path: &Path, spec: &JobSpec) -> PathBuf {
    let file = Path::new(&spec.mesh.file);
    if file.is_absolute() {
        file.to_path_buf()
    } else {
        job_path.parent().unwrap_or(Path::new(".")).join(file)
    }
}
