//! `carus measure pelvis|head|trunk [FILE.toml] [--json]`: builds (or imports) the
//! anatomy a file describes and prints every diameter, plane and landmark.

use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_anatomy::fetus::{
    AtlantoOccipitalPlacement, FetalHead, HeadDiameters, HeadMeasurement, Trunk, TrunkDiameters, TrunkMeasurement,
    DEFAULT_HEAD_SUBDIVISIONS,
};
use carus_anatomy::floor::{pelvic_floor, FloorParameters};
use carus_anatomy::pelvis::{measure, Pelvis, PelvisMeasurement, PelvisSpec};
use serde::Deserialize;

use super::{print_json, Status};

/// Which part to measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MeasurePart {
    /// The maternal bony pelvis (`[pelvis]` table).
    Pelvis,
    /// The fetal head (`[head]` table).
    Head,
    /// The fetal trunk (`[trunk]` table).
    Trunk,
}

#[derive(clap::Args)]
pub struct MeasureArgs {
    /// The part to measure.
    #[arg(value_enum)]
    pub part: MeasurePart,
    /// Anatomy or scenario file (TOML) with a `[pelvis]`, `[head]` or `[trunk]`
    /// table of canonical keys (docs/ANATOMY.md); without it, the defaults.
    pub file: Option<PathBuf>,
    /// Print one JSON object on standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &MeasureArgs) -> anyhow::Result<Status> {
    let file = AnatomyFile::load(args.file.as_deref())?;
    match args.part {
        MeasurePart::Pelvis => {
            let pelvis = file.pelvis()?;
            let m = measure(&pelvis);
            if args.json {
                print_json(&m)?;
            } else {
                print_pelvis(&m, file.describe());
            }
        }
        MeasurePart::Head => {
            let head = file.head()?;
            let m = head.measure();
            if args.json {
                print_json(&m)?;
            } else {
                print_head(&m, file.describe());
            }
        }
        MeasurePart::Trunk => {
            let m = file.trunk()?.measure();
            if args.json {
                print_json(&m)?;
            } else {
                print_trunk(&m, file.describe());
            }
        }
    }
    Ok(Status::Success)
}

fn print_pelvis(m: &PelvisMeasurement, source: String) {
    println!("Pelvis ({source}), pelvis frame: x mother's right, y anterior, z cranial; mm and degrees");
    println!();
    println!("Diameters");
    let d = &m.diameters;
    let rows: [(&str, &str, f64); 14] = [
        ("inlet_ap_mm", "obstetric conjugate (promontory - upper inner symphysis)", d.inlet_ap_mm),
        ("inlet_transverse_mm", "widest inlet transverse (iliopectineal points)", d.inlet_transverse_mm),
        ("inlet_oblique_mm", "inlet oblique, mean of right and left", d.inlet_oblique_mm),
        ("mid_ap_mm", "lower symphysis - S4-S5", d.mid_ap_mm),
        ("interspinous_mm", "between the ischial spines", d.interspinous_mm),
        ("outlet_ap_mm", "lower symphysis - coccyx tip", d.outlet_ap_mm),
        ("outlet_transverse_mm", "intertuberous", d.outlet_transverse_mm),
        ("outlet_oblique_mm", "outlet oblique, mean of right and left", d.outlet_oblique_mm),
        ("symphysis_length_mm", "inner symphysis, upper - lower border", d.symphysis_length_mm),
        ("sacral_length_mm", "promontory - sacral apex", d.sacral_length_mm),
        ("sacral_depth_mm", "S2-S3 behind the promontory-apex chord", d.sacral_depth_mm),
        ("subpubic_angle_deg", "pubic arch at the lower symphysis", d.subpubic_angle_deg),
        ("inlet_posterior_share", "inlet posterior sagittal / obstetric conjugate", d.inlet_posterior_share),
        ("mid_posterior_share", "mid-pelvis posterior sagittal / mid_ap_mm", d.mid_posterior_share),
    ];
    for (key, meaning, value) in rows {
        // A share needs more than the tenth of a millimetre a size does.
        let places = if key.ends_with("_share") { 3 } else { 1 };
        println!("  {key:<22} {value:8.places$}   {meaning}");
    }
    println!("  {:<22} {:8.1} / {:.1}", "inlet obliques R / L", m.inlet_oblique_right_mm, m.inlet_oblique_left_mm);
    println!("  {:<22} {:8.1} / {:.1}", "outlet obliques R / L", m.outlet_oblique_right_mm, m.outlet_oblique_left_mm);
    println!("  {:<22} {:8.1}", "inlet post. sagittal", m.inlet_posterior_sagittal_mm);
    println!("  {:<22} {:8.1}", "mid post. sagittal", m.mid_posterior_sagittal_mm);
    println!("  {:<22} {:8.1}", "outlet post. sagittal", m.outlet_posterior_sagittal_mm);
    println!();
    println!("Planes (centre, caudal normal, tilt from the inlet, AP, transverse, sigma along the pelvic axis)");
    for name in ["inlet", "greatest_dimensions", "mid", "outlet"] {
        let p = &m.planes[name];
        let transverse = p.transverse_mm.map_or("-".to_string(), |t| format!("{t:.1}"));
        println!(
            "  {name:<20} centre ({:6.1} {:6.1} {:6.1})  normal ({:5.2} {:5.2} {:5.2})  tilt {:5.1}  AP {:6.1}  transverse {:>6}  sigma {:6.1}",
            p.centre_mm[0], p.centre_mm[1], p.centre_mm[2], p.normal[0], p.normal[1], p.normal[2], p.tilt_from_inlet_deg, p.ap_mm, transverse, p.sigma_mm
        );
    }
    println!("  pelvic axis length (inlet to outlet centre) {:.1}", m.axis_length_mm);
    println!();
    println!("Landmarks (x, y, z)");
    for (name, p) in &m.landmarks_mm {
        println!("  {name:<26} {:7.1} {:7.1} {:7.1}", p[0], p[1], p[2]);
    }
    println!(
        "  largest landmark distance from the surface: {:.2}{}",
        m.landmark_surface_gap_mm,
        match m.landmark_surface_gap_landmark {
            "" => String::new(),
            name => format!(" ({name})"),
        }
    );
}

fn print_head(m: &HeadMeasurement, source: String) {
    println!("Fetal head ({source}), head frame: x occipitofrontal, y towards the fetal left, z vertex; mm");
    println!();
    println!("Diameters");
    for (key, value) in [
        ("biparietal_mm", m.biparietal_mm),
        ("bitemporal_mm", m.bitemporal_mm),
        ("occipitofrontal_mm", m.occipitofrontal_mm),
        ("suboccipitobregmatic_mm", m.suboccipitobregmatic_mm),
        ("mentovertical_mm", m.mentovertical_mm),
        ("submentobregmatic_mm", m.submentobregmatic_mm),
    ] {
        println!("  {key:<26} {value:8.1}");
    }
    println!();
    let e = &m.extents;
    println!("Extents of the surface");
    for (what, value) in [
        ("along x (occiput to forehead)", e.along_o_mm),
        ("along y (side to side)", e.along_b_mm),
        ("along z (skull base or chin to top)", e.along_v_mm),
        ("presenting, deflexed (vertex)", e.presenting_deflexed_mm),
        ("presenting, well flexed", e.presenting_flexed_mm),
        ("presenting, brow", e.presenting_brow_mm),
        ("presenting, face", e.presenting_face_mm),
    ] {
        println!("  {what:<36} {value:8.1}");
    }
    println!();
    println!("Landmarks (x, y, z)");
    for (name, p) in &m.landmarks_mm {
        println!("  {name:<26} {:7.1} {:7.1} {:7.1}", p[0], p[1], p[2]);
    }
}

fn print_trunk(m: &TrunkMeasurement, source: String) {
    println!("Fetal trunk ({source}), trunk frame: origin at the atlanto-occipital pivot, x ventral, y towards the fetal left, z cranial; mm");
    println!();
    println!("Diameters and lengths");
    for (key, value, meaning) in [
        ("bisacromial_mm", m.bisacromial_mm, "between the acromions"),
        ("bitrochanteric_mm", m.bitrochanteric_mm, "between the greater trochanters"),
        ("chest_breadth_mm", m.chest_breadth_mm, "across the chest's widest ring"),
        ("chest circumference", m.chest_circumference_mm, "round that ring"),
        ("cervical_spine_mm", m.cervical_spine_mm, "the neck: pivot to the first thoracic vertebra"),
        ("trunk_length_mm", m.trunk_length_mm, "neck base to the buttocks' lowest ring"),
        ("width", m.width_mm, "side to side, the widest ring"),
        ("length", m.length_mm, "along the spine, pivot to breech"),
    ] {
        println!("  {key:<22} {value:8.1}   {meaning}");
    }
    println!();
    println!("Landmarks (x, y, z)");
    for (name, p) in &m.landmarks_mm {
        println!("  {name:<26} {:7.1} {:7.1} {:7.1}", p[0], p[1], p[2]);
    }
}

/// The text of an anatomy or scenario file; a folder, a mesh or a binary
/// file is refused as not one, with how a mesh is imported.
fn read_text(path: &Path) -> anyhow::Result<String> {
    let not_toml = |what: &str| {
        anyhow::anyhow!(
            "{}: {what}; give an anatomy (or scenario) file, TOML text with a [pelvis], [head] or [trunk] table \
             (docs/ANATOMY.md)\n  hint: a pelvis mesh is imported through a landmarks file that names it: \
             `[pelvis] import = \"pelvis.landmarks.toml\"` (docs/IMPORT.md); a fetal head is built from \
             its diameters (`[head]`), and its trunk from `[trunk]`; a fetal mesh cannot be imported yet",
            path.display()
        )
    };
    if path.is_dir() {
        return Err(not_toml("is a folder"));
    }
    if path.is_file() && carus_anatomy::import::MeshFormat::from_path(path).is_ok() {
        return Err(not_toml("is a mesh, not an anatomy file"));
    }
    let bytes = carus_io::input::read_bytes(path).with_context(|| format!("cannot read {}", path.display()))?;
    String::from_utf8(bytes).map_err(|_| not_toml("is not a text file (UTF-8)"))
}

/// The floor a run builds when its scenario leaves `[floor.mesh]` out, so
/// that the floor a user inspects is the one the runs simulate.
fn run_floor() -> FloorParameters {
    carus_labour::scenario::FloorSection::default().mesh
}

/// An anatomy file's `[floor]`: its keys over [`run_floor`].
fn floor_part(path: &Path, table: &toml::Table) -> anyhow::Result<FloorParameters> {
    match table.get("floor") {
        None => Ok(run_floor()),
        Some(toml::Value::Table(keys)) if keys.contains_key("mesh") => anyhow::bail!(
            "{}: [floor.mesh] is a scenario's table; an anatomy file gives the same keys in [floor] itself \
             (`[floor]` then `sag_mm = ...`; docs/ANATOMY.md), or give the file a `name` to read it as a scenario",
            path.display()
        ),
        Some(toml::Value::Table(keys)) => carus_labour::scenario::floor_mesh_from(keys.clone())
            .with_context(|| format!("{}: in the [floor] table (keys and units: docs/ANATOMY.md)", path.display())),
        Some(other) => anyhow::bail!("{}: `floor` must be a table, not {}", path.display(), other.type_str()),
    }
}

/// The line of `key` in the first of `tables` of a file's `text` that
/// writes it.
fn line_in(text: Option<&str>, tables: &[&str], key: Option<&str>) -> Option<std::num::NonZeroUsize> {
    let (text, key) = text.zip(key)?;
    tables.iter().find_map(|table| carus_io::toml_text::line_of_key(text, &format!("{table}.{key}")))
}

/// The tables an anatomy file may have.
const TABLES: [&str; 4] = ["pelvis", "head", "trunk", "floor"];

/// The anatomy tables (`[pelvis]`, `[head]`, `[trunk]`, `[floor]`) of an anatomy or
/// scenario file, shared with `carus mesh`. Other tables of a scenario file
/// are left to the commands that use them.
pub struct AnatomyFile {
    pub path: Option<PathBuf>,
    pub pelvis: PelvisSpec,
    pub head: HeadDiameters,
    /// The head's atlanto-occipital pivot: a scenario's `[fetus]` keys, else the default.
    pub pivot: AtlantoOccipitalPlacement,
    pub trunk: TrunkDiameters,
    pub floor: FloorParameters,
    /// The tables an anatomy file left out (the defaults stand in), noted
    /// when the part is built so that an empty or misnamed file is not
    /// taken for a measured one.
    left_out: Vec<&'static str>,
}

impl AnatomyFile {
    /// Reads `path`, or the defaults when there is none.
    pub fn load(path: Option<&Path>) -> anyhow::Result<Self> {
        let Some(path) = path else {
            return Ok(AnatomyFile {
                path: None,
                pelvis: PelvisSpec::default(),
                head: HeadDiameters::default(),
                pivot: AtlantoOccipitalPlacement::default(),
                trunk: TrunkDiameters::default(),
                floor: run_floor(),
                left_out: Vec::new(),
            });
        };
        let text = read_text(path)?;
        let table = carus_labour::scenario::toml_table(path, &text)?;
        carus_labour::scenario::check_not_landmarks_file(path, &text, &table)?;
        // A scenario (it has a `name`) is read whole, as `carus run` reads
        // it, and keeps the floor's shape in [floor.mesh]; an anatomy file
        // has the three tables only, so that a misspelt one is not quietly
        // replaced by the defaults.
        if table.contains_key("name") {
            let scenario = carus_labour::Scenario::from_file(path)?;
            return Ok(AnatomyFile {
                pelvis: scenario.pelvis,
                head: scenario.head,
                pivot: scenario.fetus.atlanto_occipital(),
                trunk: scenario.trunk.diameters(),
                floor: scenario.floor.mesh,
                path: Some(path.to_path_buf()),
                left_out: Vec::new(),
            });
        }
        if let Some(unknown) = table.keys().find(|k| !TABLES.contains(&k.as_str())) {
            anyhow::bail!(
                "{}: `{unknown}` is not a table of an anatomy file, which has [pelvis], [head], [trunk] and [floor] \
                 (docs/ANATOMY.md); a scenario file starts with its `name`",
                path.display()
            );
        }
        /// The tables read whole from the text, so that a wrong value is
        /// named by its line; `[floor]` has its own reader.
        #[derive(Deserialize)]
        struct Tables {
            #[serde(default)]
            pelvis: PelvisSpec,
            #[serde(default)]
            head: HeadDiameters,
            #[serde(default)]
            trunk: TrunkDiameters,
        }
        let Tables { pelvis, head, trunk } = carus_labour::scenario::from_toml_text(path, &text)?;
        carus_labour::Scenario::check_anatomy_tables(path, &text, &pelvis, &head, &trunk)?;

        let base = path.parent().unwrap_or(Path::new("."));
        carus_labour::scenario::check_pelvis_import(path, &text, &pelvis, base)?;
        Ok(AnatomyFile {
            pelvis,
            head,
            pivot: AtlantoOccipitalPlacement::default(),
            trunk,
            floor: floor_part(path, &table)?,
            path: Some(path.to_path_buf()),
            left_out: TABLES.into_iter().filter(|t| !table.contains_key(*t)).collect(),
        })
    }

    /// Builds the pelvis the file describes (imports resolve next to the file).
    /// An imported mesh with holes or dropped triangles gets a note on
    /// standard error: contact samples can slip through a hole.
    pub fn pelvis(&self) -> anyhow::Result<Pelvis> {
        self.note_if_left_out("pelvis");
        let base = self.path.as_deref().and_then(Path::parent).unwrap_or(Path::new("."));
        let (pelvis, report) = self.pelvis.build_with_report(base).map_err(|e| {
            let text = self.path.as_deref().filter(|_| e.of_diameters()).and_then(|p| read_text(p).ok());
            let where_ = self.at_key(text.as_deref(), "pelvis", e.diameter_key()).unwrap_or_else(|| "the default pelvis".into());
            // The keys the message names that the file leaves to their defaults.
            match text.and_then(|t| carus_labour::scenario::defaults_note_in(&t, "pelvis", &e.to_string())) {
                Some(note) => anyhow::anyhow!("{where_}: {e}\n  note: {note}"),
                None => anyhow::Error::from(e).context(where_),
            }
        })?;
        if let Some(note) = report.and_then(|(r, mesh)| import_note(&r, &mesh)) {
            eprintln!("note: {note}");
        }
        Ok(pelvis)
    }

    /// Builds the head the file describes; a failure names the file, and
    /// the line of the diameter to change where the file writes it.
    pub fn head(&self) -> anyhow::Result<FetalHead> {
        self.note_if_left_out("head");
        FetalHead::with_subdivisions(&self.head, &self.pivot, DEFAULT_HEAD_SUBDIVISIONS).map_err(|e| {
            let text = self.path.as_deref().and_then(|p| read_text(p).ok());
            let at = self.at_key(text.as_deref(), "head", e.diameter_key()).unwrap_or_else(|| format!("{}: [head]", self.describe()));
            anyhow::Error::from(e).context(format!("{at}: the diameters cannot be built"))
        })
    }

    /// Builds the trunk the file describes (its values already checked
    /// as a scenario's are, at their lines).
    pub fn trunk(&self) -> anyhow::Result<Trunk> {
        self.note_if_left_out("trunk");
        Trunk::new(&self.trunk).with_context(|| format!("{}: [trunk]", self.describe()))
    }

    /// `file:line: [table]` at the line of `key` in the file's `text`
    /// (`file: [table]` where the file does not write it); None for the
    /// defaults, which have no file.
    fn at_key(&self, text: Option<&str>, table: &str, key: Option<&str>) -> Option<String> {
        let path = self.path.as_ref()?;
        Some(format!("{}: [{table}]", carus_io::toml_text::located(path, line_in(text, &[table], key))))
    }

    /// Builds the pelvic floor the file describes on `pelvis`; a failure names
    /// the file, and the line of the key to change where the file writes it
    /// (in a scenario's `[floor.mesh]` or an anatomy file's `[floor]`).
    pub fn floor(&self, pelvis: &Pelvis) -> anyhow::Result<carus_fem::Mesh> {
        self.note_if_left_out("floor");
        pelvic_floor(pelvis, &self.floor).map_err(|e| {
            let text = self.path.as_deref().and_then(|p| read_text(p).ok());
            let line = line_in(text.as_deref(), &["floor.mesh", "floor"], e.key());
            let at = match (&self.path, line) {
                (Some(path), Some(_)) => carus_io::toml_text::located(path, line),
                _ => self.describe(),
            };
            anyhow::Error::from(e).context(format!("{at}: the [floor] cannot be built for this pelvis"))
        })
    }

    fn note_if_left_out(&self, table: &str) {
        if let Some(path) = self.path.as_ref().filter(|_| self.left_out.contains(&table)) {
            eprintln!("note: {} has no [{table}] table: the default {table} is used", path.display());
        }
    }

    /// Where the anatomy came from, for headings.
    pub fn describe(&self) -> String {
        let source = self.path.as_ref().map_or("defaults".to_string(), |p| p.display().to_string());
        match &self.pelvis {
            PelvisSpec::Imported { landmarks_file } => format!("{source}, pelvis imported from {}", landmarks_file.display()),
            PelvisSpec::Generated(_) => source,
        }
    }
}

/// What an imported pelvis's mesh report means for a run: holes let the
/// fetus slip through (fix them); flipped faces turned to agree, a surface
/// turned to face outwards and dropped degenerate triangles leave it whole.
pub(super) fn import_note(r: &carus_anatomy::import::MeshReport, mesh: &Path) -> Option<String> {
    let mut said = Vec::new();
    if r.reoriented > 0 {
        said.push(format!(
            "{} of its {} triangles ran against their neighbours (faces flipped in export) and were turned to agree",
            r.reoriented, r.triangles_read
        ));
    }
    if r.turned_outwards {
        said.push(
            "its triangles faced into the bone (the volume a part of it encloses was negative), which \
             would draw the fetus into it; they were turned to face outwards. Export the mesh with \
             outward normals (MeshLab: Invert Faces Orientation) to silence this note"
                .to_string(),
        );
    } else if r.unorientable_edges > 0 {
        said.push(format!(
            "{} edges are run the same way by two triangles that could not be turned to agree (a surface \
             with no outside, such as a Moebius band), so which way is out is unknown there: mend the mesh \
             (e.g. MeshLab's Re-Orient all faces coherently) and export it again",
            r.unorientable_edges
        ));
    } else if r.open_edges > 0 {
        said.push(format!(
            "{} open edges (holes), {} non-manifold edges, {} degenerate triangles dropped of {} read; \
             the fetus can slip through a hole: fill the holes (e.g. MeshLab's Close Holes) and export it again",
            r.open_edges, r.non_manifold_edges, r.degenerate_dropped, r.triangles_read
        ));
    } else if r.degenerate_dropped > 0 {
        said.push(format!(
            "{} degenerate (zero-area) triangles dropped of {} read; no hole is left, so the surface \
             the contact uses is whole",
            r.degenerate_dropped, r.triangles_read
        ));
    }
    (!said.is_empty()).then(|| format!("{}: {}", mesh.display(), said.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Holes get the fix; dropped degenerate triangles alone are no hole;
    /// a clean mesh gets no note.
    #[test]
    fn an_import_note_tells_holes_from_dropped_triangles() {
        let mesh = Path::new("pelvis.stl");
        let report = |open_edges, degenerate_dropped| carus_anatomy::import::MeshReport {
            triangles_read: 100,
            vertices: 52,
            degenerate_dropped,
            parts: 1,
            closed_parts: usize::from(open_edges == 0),
            open_edges,
            non_manifold_edges: 0,
            unorientable_edges: 0,
            reoriented: 0,
            turned_outwards: false,
        };
        let holes = import_note(&report(6, 1), mesh).unwrap();
        assert!(holes.starts_with("pelvis.stl: 6 open edges (holes)") && holes.contains("fill the holes"), "{holes}");
        let dropped = import_note(&report(0, 2), mesh).unwrap();
        assert!(dropped.contains("2 degenerate (zero-area) triangles dropped of 100") && !dropped.contains("fill"), "{dropped}");
        assert_eq!(import_note(&report(0, 0), mesh), None);
        let flipped = import_note(&carus_anatomy::import::MeshReport { reoriented: 3, ..report(0, 0) }, mesh).unwrap();
        assert!(flipped.starts_with("pelvis.stl: 3 of its 100 triangles ran against their neighbours"), "{flipped}");
        let turned = import_note(&carus_anatomy::import::MeshReport { turned_outwards: true, ..report(0, 0) }, mesh).unwrap();
        assert!(turned.starts_with("pelvis.stl: its triangles faced into the bone") && turned.contains("turned to face outwards"), "{turned}");
    }

    /// A diameter set that cannot be built names the file and the line of
    /// the key to change, for the pelvis and the head; a key the file
    /// leaves out names no line.
    #[test]
    fn unbuildable_diameters_name_their_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("anatomy.toml");
        let text = "[pelvis]\ninlet_ap_mm = 110.0\nmid_posterior_share = 0.05\n\n[head]\nbiparietal_mm = 95.0\nbitemporal_mm = 99.0\n";
        std::fs::write(&path, text).unwrap();
        let file = AnatomyFile::load(Some(&path)).unwrap();
        let e = format!("{:#}", file.pelvis().err().unwrap());
        assert!(e.starts_with(&format!("{}:3: [pelvis]: mid_posterior_share = 0.05 is outside 0.2 to 0.7", path.display())), "{e}");
        let e = format!("{:#}", file.head().err().unwrap());
        assert!(e.starts_with(&format!("{}:7: [head]: the diameters cannot be built: bitemporal_mm (99 mm)", path.display())), "{e}");
        std::fs::write(&path, "[floor]\nsag_mm = 12.0\nlevator_origin_share = 0.1\nhiatus_front_share = 0.9\n").unwrap();
        let file = AnatomyFile::load(Some(&path)).unwrap();
        let e = format!("{:#}", file.floor(&file.pelvis().unwrap()).err().unwrap());
        assert!(e.starts_with(&format!("{}:3: the [floor] cannot be built for this pelvis: levator_origin_share = 0.1", path.display())), "{e}");
        std::fs::write(&path, "[pelvis]\ninlet_transverse_mm = 100.0\n").unwrap();
        let e = format!("{:#}", AnatomyFile::load(Some(&path)).unwrap().pelvis().err().unwrap());
        assert!(e.starts_with(&format!("{}: [pelvis]: interspinous_mm = 102", path.display())) && e.contains("note: interspinous_mm is the default"), "{e}");
    }

    fn load(text: &str) -> anyhow::Result<AnatomyFile> {
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("file.toml");
        std::fs::write(&path, text)?;
        AnatomyFile::load(Some(&path))
    }

    #[test]
    fn a_scenario_file_gives_its_floor_mesh_and_an_anatomy_file_its_floor() {
        let scenario = carus_labour::scenario::Scenario::builtin("normal").unwrap();
        let mut text = scenario.to_toml().unwrap();
        text = text.replace("sag_mm = 20.0", "sag_mm = 12.0");
        let file = load(&text).unwrap();
        assert_eq!(file.floor.sag_mm, 12.0, "read from [floor.mesh]");
        assert_eq!(file.head, scenario.head);
        let anatomy = load("[floor]\nsag_mm = 15.0\n").unwrap();
        assert_eq!(anatomy.floor.sag_mm, 15.0);
        // Keys left out, or no file at all, give the floor a run builds.
        let run = carus_labour::scenario::FloorSection::default().mesh;
        assert_eq!(FloorParameters { sag_mm: 15.0, ..run }, anatomy.floor);
        assert_eq!(AnatomyFile::load(None).unwrap().floor, run);
        assert_eq!(load("[head]\nbiparietal_mm = 95.0\n").unwrap().floor, run);
        // A tissue key belongs to a scenario; in an anatomy file it is named.
        let error = format!("{:#}", load("[floor]\nshear_modulus_pa = 16500.0\n").err().unwrap());
        assert!(error.contains("[floor]") && error.contains("shear_modulus_pa"), "{error}");
        // A misspelt table is named, in an anatomy file and in a scenario.
        let error = format!("{:#}", load("[pelvsi]\ninlet_ap_mm = 100.0\n").err().unwrap());
        assert!(error.contains("`pelvsi` is not a table"), "{error}");
        let error = format!("{:#}", load(&text.replace("[head]", "[haed]")).err().unwrap());
        assert!(error.contains("haed"), "{error}");
        // The head is measured with the scenario's pivot; an anatomy file's has the default.
        let moved = text.replace("atlanto_occipital_behind_deg = 15.0", "atlanto_occipital_behind_deg = 30.0");
        let file = load(&moved).unwrap();
        assert_eq!(file.pivot, AtlantoOccipitalPlacement { behind_vertical_deg: 30.0, depth: 0.15 });
        let pivot = file.head().unwrap().landmarks.atlanto_occipital;
        assert!(((-pivot.x).atan2(-pivot.z).to_degrees() - 30.0).abs() < 1e-9, "{pivot}");
        assert_eq!(anatomy.pivot, AtlantoOccipitalPlacement::default());
        // A unit after a number gets the scenario's advice, with its line.
        let error = format!("{:#}", load("[head]\nbiparietal_mm = 95mm\n").err().unwrap());
        assert!(error.contains("file.toml:2") && error.contains("write the number alone"), "{error}");
        // A value of the wrong type is named by its line too, and a misspelt key.
        let error = format!("{:#}", load("[pelvis]
inlet_ap_mm = 110.0
[head]
biparietal_mm = \"abc\"\n").err().unwrap());
        assert!(error.contains("file.toml:4") && error.contains("invalid type") && error.contains("numbers without quotes"), "{error}");
        let error = format!("{:#}", load("[head]
biparietal_mn = 95.0
").err().unwrap());
        assert!(error.contains("file.toml:2") && error.contains("biparietal_mn"), "{error}");
    }

    /// The trunk of an anatomy file or a scenario is measured back, its
    /// chest apart from its shoulders; a chest in cm is refused at its line.
    #[test]
    fn the_trunk_is_read_from_either_file_and_measured_back() {
        let m = load("[trunk]\nbisacromial_mm = 150.0\nchest_breadth_mm = 116.6\n").unwrap().trunk().unwrap().measure();
        assert!((m.bisacromial_mm - 150.0).abs() < 0.1 && (m.chest_breadth_mm - 116.6).abs() < 0.1, "{m:?}");
        assert!(m.landmarks_mm.contains_key("bisacromial_midpoint") && m.landmarks_mm.len() == 8);
        let large = carus_labour::scenario::Scenario::builtin("large-shoulders").unwrap();
        let file = load(&large.to_toml().unwrap()).unwrap();
        let (ours, default) = (file.trunk().unwrap().measure(), AnatomyFile::load(None).unwrap().trunk().unwrap().measure());
        assert!((ours.bisacromial_mm - 175.0).abs() < 1e-9 && ours.chest_circumference_mm == default.chest_circumference_mm, "{ours:?}");
        let e = format!("{:#}", load("[head]\nbiparietal_mm = 95.0\n[trunk]\nchest_breadth_mm = 10.8\n").err().unwrap());
        assert!(e.contains("file.toml:4: `trunk.chest_breadth_mm` = 10.8") && e.contains("mm (not cm)"), "{e}");
    }

    /// A scenario's [floor.mesh] in an anatomy file says where its keys go.
    #[test]
    fn a_scenario_floor_table_in_an_anatomy_file_says_where_its_keys_go() {
        let e = format!("{:#}", load("[floor.mesh]\nsag_mm = 20.0\n").err().unwrap());
        assert!(e.contains("[floor.mesh] is a scenario's table") && e.contains("in [floor] itself"), "{e}");
    }

    /// An anatomy file's sizes get the checks a scenario's get: a head in
    /// cm, a pelvis in metres, named at their line with the unit.
    #[test]
    fn an_anatomy_file_in_another_unit_is_refused_as_a_scenario_is() {
        for (text, key) in [
            ("[head]\nbiparietal_mm = 950.0\n", "`head.biparietal_mm` = 950"),
            ("[pelvis]\ninlet_ap_mm = 0.11\n", "`pelvis.inlet_ap_mm` = 0.11"),
        ] {
            let e = format!("{:#}", load(text).err().unwrap());
            assert!(e.contains(":2: ") && e.contains(key) && e.contains("mm (not cm)"), "{e}");
        }
    }

    #[test]
    fn a_mesh_a_folder_or_a_bad_import_is_refused_with_how_to_import() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = dir.path().join("pelvis.stl");
        std::fs::write(&mesh, [0u8, 159, 146, 150]).unwrap();
        let binary = dir.path().join("pelvis.bin");
        std::fs::write(&binary, [0u8, 159, 146, 150]).unwrap();
        for (path, what) in [(&mesh, "is a mesh"), (&binary, "is not a text file"), (&dir.path().to_path_buf(), "is a folder")] {
            let e = format!("{:#}", AnatomyFile::load(Some(path)).err().unwrap());
            assert!(e.starts_with(&format!("{}: {what}", path.display())), "{e}");
            assert!(e.contains("anatomy (or scenario) file") && e.contains("[pelvis] import = "), "{e}");
        }
        // A misspelt built-in is told as the scenario's is, with the built-in names.
        let e = format!("{:#}", load("[pelvis]\nimport = \"visible-human-male\"\n").err().unwrap());
        assert!(e.contains("file.toml:2: `pelvis.import`") && e.contains("does not exist"), "{e}");
        assert!(e.contains(carus_anatomy::pelvis::VISIBLE_HUMAN_FEMALE), "{e}");
        let e = format!("{:#}", load("[pelvis]\nimport = \"\"\n").err().unwrap());
        assert!(e.contains("file.toml:2: `pelvis.import`: is empty: it names no landmarks file"), "{e}");
    }

    /// A landmarks file's own lines (`units = mm`) are quoted in its error,
    /// never taken for the anatomy file's keys left to their defaults.
    #[test]
    fn a_broken_landmarks_file_is_not_taken_for_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/anatomy/visible-human-female-pelvis.landmarks.toml");
        let text = std::fs::read_to_string(shipped).unwrap().replace("units = \"mm\"", "units = mm");
        std::fs::write(dir.path().join("broken.landmarks.toml"), text).unwrap();
        let path = dir.path().join("anatomy.toml");
        std::fs::write(&path, "[pelvis]\nimport = \"broken.landmarks.toml\"\n").unwrap();
        let e = format!("{:#}", AnatomyFile::load(Some(&path)).unwrap().pelvis().err().unwrap());
        assert!(e.contains("broken.landmarks.toml") && e.contains("units = mm"), "{e}");
        assert!(!e.contains("the default"), "{e}");
    }

    #[test]
    fn the_real_pelvis_scenario_names_the_shipped_pelvis_from_any_folder() {
        let scenario = carus_labour::scenario::Scenario::builtin("real-pelvis").unwrap();
        let file = load(&scenario.to_toml().unwrap()).unwrap();
        let pelvis = file.pelvis().unwrap();
        let imported = carus_anatomy::import::visible_human_female_pelvis().unwrap().pelvis;
        assert_eq!(pelvis.landmarks, imported.landmarks);
    }
}
