//! `carus mesh pelvis|head|trunk|floor [FILE.toml] --out DIR`: writes the anatomy
//! for inspection: surfaces as binary STL in mm (for CAD tools and
//! slicers) and as VTU in metres (for ParaView, beside the pelvic floor's
//! VTU and a run's outputs), landmarks as CSV and JSON (mm), each part in
//! its own frame.
//! Each surface is checked for places where it crosses itself, which a
//! mesher or the contact's inside test would trip on.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_anatomy::floor::ATTACHED;
use carus_anatomy::pelvis::AxisSample;
use carus_anatomy::TriSurface;
use carus_io::{write_vtu, FrameFields};

use super::measure::AnatomyFile;
use super::{print_json, Status};

/// Which part to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MeshPart {
    /// The bony pelvis surface, its landmarks and the pelvic axis.
    Pelvis,
    /// The fetal head surface and its landmarks.
    Head,
    /// The fetal trunk surface (neck to breech) and its landmarks.
    Trunk,
    /// The pelvic floor volume mesh (with the pelvis it is shaped to).
    Floor,
}

#[derive(clap::Args)]
pub struct MeshArgs {
    /// The part to write.
    #[arg(value_enum)]
    pub part: MeshPart,
    /// Anatomy or scenario file (TOML) with `[pelvis]`, `[head]`, `[trunk]` or `[floor]`
    /// tables (docs/ANATOMY.md); without it, the defaults (the floor a
    /// labour run builds, 192 elements).
    pub file: Option<PathBuf>,
    /// Folder to write into (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Print one JSON object (the files written) on standard output.
    #[arg(long)]
    pub json: bool,
    /// Write over the files of an earlier `carus mesh` in the folder.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: &MeshArgs) -> anyhow::Result<Status> {
    let file = AnatomyFile::load(args.file.as_deref())?;
    refuse_to_overwrite(&args.out, args.part, args.force)?;
    super::create_out_folder(&args.out, "--out")?;
    let mut written = Vec::new();
    let mut crossings = Vec::new();
    match args.part {
        MeshPart::Pelvis | MeshPart::Floor => {
            let pelvis = file.pelvis()?;
            write_part(&args.out, "pelvis", &pelvis.surface, &pelvis.landmarks.named(), &mut written, &mut crossings)?;
            let axis = carus_anatomy::pelvis::axis_samples(&pelvis);
            written.push(write_axis(&args.out.join("pelvic_axis.csv"), &axis)?);
            if args.part == MeshPart::Floor {
                let floor = file.floor(&pelvis)?;
                let path = args.out.join("pelvic_floor.vtu");
                let zeros_n = vec![[0.0; 3]; floor.node_count()];
                let zeros_e = vec![0.0; floor.element_count()];
                let ones_e = vec![1.0; floor.element_count()];
                let fields = FrameFields {
                    displacement_m: &zeros_n,
                    von_mises_pa: &zeros_e,
                    max_principal_stretch: &ones_e,
                    jacobian: &ones_e,
                    time_s: None,
                };
                write_vtu(&path, &floor, &fields)?;
                written.push(path);
                let attached: Vec<(String, [f64; 3])> =
                    floor.node_sets[ATTACHED].iter().map(|&n| (format!("node_{n}"), floor.nodes[n as usize])).collect();
                written.extend(write_landmarks(&args.out, "pelvic_floor_attached_nodes", &attached)?);
                eprintln!(
                    "pelvic floor: {} H8 elements, {} nodes, {} attached",
                    floor.element_count(),
                    floor.node_count(),
                    attached.len()
                );
            }
        }
        MeshPart::Head => {
            let head = file.head()?;
            write_part(&args.out, "head", &head.surface, &head.landmarks.named(), &mut written, &mut crossings)?;
        }
        MeshPart::Trunk => {
            let trunk = file.trunk()?;
            write_part(&args.out, "trunk", &trunk.surface, &trunk.landmarks.named(), &mut written, &mut crossings)?;
        }
    }
    if args.json {
        let files: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        let crossings: serde_json::Map<String, serde_json::Value> =
            crossings.iter().map(|(name, n)| (name.to_string(), (*n).into())).collect();
        print_json(&serde_json::json!({
            "out_dir": args.out.display().to_string(),
            "files": files,
            "self_intersecting_pairs": crossings,
        }))?;
    } else {
        for p in &written {
            println!("wrote {}", p.display());
        }
    }
    Ok(Status::Success)
}

/// Writes a part's surface (`NAME.stl`, `NAME.vtu`, in the `NAME frame`)
/// and its landmarks (`NAME_landmarks.csv`, `.json`), adding the files to
/// `written` and the surface's self-crossings to `crossings`.
fn write_part(
    out: &Path,
    name: &'static str,
    surface: &TriSurface,
    landmarks: &[(&str, glam::DVec3)],
    written: &mut Vec<PathBuf>,
    crossings: &mut Vec<(&'static str, Option<usize>)>,
) -> anyhow::Result<()> {
    written.extend(write_surface(out, name, surface, &format!("{name} frame"))?);
    crossings.push((name, self_crossings(name, surface)));
    let points: Vec<(String, [f64; 3])> = landmarks.iter().map(|(n, p)| (n.to_string(), p.to_array())).collect();
    written.extend(write_landmarks(out, &format!("{name}_landmarks"), &points)?);
    Ok(())
}

/// The names of the files `part` writes, in the order it writes them.
fn file_names(part: MeshPart) -> Vec<String> {
    let pair = |stem: &str, a: &str, b: &str| [format!("{stem}.{a}"), format!("{stem}.{b}")];
    let mut names = Vec::new();
    match part {
        MeshPart::Pelvis | MeshPart::Floor => {
            names.extend(pair("pelvis", "stl", "vtu"));
            names.extend(pair("pelvis_landmarks", "csv", "json"));
            names.push("pelvic_axis.csv".to_string());
            if part == MeshPart::Floor {
                names.push("pelvic_floor.vtu".to_string());
                names.extend(pair("pelvic_floor_attached_nodes", "csv", "json"));
            }
        }
        MeshPart::Head => {
            names.extend(pair("head", "stl", "vtu"));
            names.extend(pair("head_landmarks", "csv", "json"));
        }
        MeshPart::Trunk => {
            names.extend(pair("trunk", "stl", "vtu"));
            names.extend(pair("trunk_landmarks", "csv", "json"));
        }
    }
    names
}

/// Checked before anything is written, so that a refusal leaves the folder
/// as it was. A folder carus made for runs (a run's, a sweep's, sanity's)
/// is refused even with `--force`: its `pelvis.vtu` is the run's own, in
/// the run's anatomy.
fn refuse_to_overwrite(out: &Path, part: MeshPart, force: bool) -> anyhow::Result<()> {
    if super::run::carus_made(out) || super::holds_batch(out) {
        anyhow::bail!(
            "{} holds carus runs, whose files `carus mesh` would write over; choose another --out",
            out.display()
        );
    }
    let existing: Vec<String> = file_names(part).into_iter().filter(|name| out.join(name).exists()).collect();
    if !existing.is_empty() && !force {
        anyhow::bail!(
            "{} already holds {}; choose another --out, or add --force to write over them",
            out.display(),
            existing.join(", ")
        );
    }
    Ok(())
}

/// How many pairs of the surface's triangles cross each other (not
/// counting neighbours); a note on standard error when any do. A check,
/// not a requirement: a surface it cannot index is noted and skipped.
fn self_crossings(name: &'static str, surface: &TriSurface) -> Option<usize> {
    let collider = match carus_contact::TriangleCollider::new(name, &surface.vertices, &surface.triangles) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("note: the {name} surface was not checked for self-intersections: {e}");
            return None;
        }
    };
    let pairs = carus_contact::self_intersections(&collider).len();
    if pairs > 0 {
        eprintln!(
            "note: the {name} surface crosses itself: {pairs} pairs of triangles intersect \
             (docs/ANATOMY.md, \"Self-intersections\"); a mesher that needs a clean shell will refuse it"
        );
    }
    Some(pairs)
}

/// `NAME.stl` (mm) and `NAME.vtu` (m) of `surface`, in `frame`.
fn write_surface(out: &Path, name: &str, surface: &TriSurface, frame: &str) -> anyhow::Result<[PathBuf; 2]> {
    let stl = write_stl(&out.join(format!("{name}.stl")), surface, frame)?;
    let vtu = out.join(format!("{name}.vtu"));
    carus_labour::output::write_surface_vtu(&vtu, &surface.vertices, &surface.triangles, &carus_analysis::RigidPose::default(), None)?;
    Ok([stl, vtu])
}

/// Binary STL, coordinates in millimetres (what CAD tools and slicers
/// expect of STL), in `frame` (named in its header).
fn write_stl(path: &Path, surface: &TriSurface, frame: &str) -> anyhow::Result<PathBuf> {
    let mut bytes = Vec::with_capacity(84 + 50 * surface.triangles.len());
    let mut header = [0u8; 80];
    let title = format!("carus anatomy, millimetres, {frame}");
    header[..title.len()].copy_from_slice(title.as_bytes());
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(&(surface.triangles.len() as u32).to_le_bytes());
    for t in 0..surface.triangles.len() {
        let [a, b, c] = surface.corners(t);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for v in [normal, a * 1e3, b * 1e3, c * 1e3] {
            for x in v.to_array() {
                bytes.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(&0u16.to_le_bytes());
    }
    std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path.to_path_buf())
}

/// `NAME.csv` (name,x_mm,y_mm,z_mm) and `NAME.json` ({name: [x, y, z]} in
/// mm) from points in metres.
fn write_landmarks(dir: &Path, name: &str, points: &[(String, [f64; 3])]) -> anyhow::Result<[PathBuf; 2]> {
    let csv_path = dir.join(format!("{name}.csv"));
    let mut csv = String::from("name,x_mm,y_mm,z_mm\n");
    for (label, p) in points {
        csv += &format!("{label},{:.4},{:.4},{:.4}\n", p[0] * 1e3, p[1] * 1e3, p[2] * 1e3);
    }
    std::fs::write(&csv_path, csv).with_context(|| format!("cannot write {}", csv_path.display()))?;
    let json_path = dir.join(format!("{name}.json"));
    let map: serde_json::Map<String, serde_json::Value> =
        points.iter().map(|(label, p)| (label.clone(), serde_json::json!([p[0] * 1e3, p[1] * 1e3, p[2] * 1e3]))).collect();
    let mut out = std::fs::File::create(&json_path).with_context(|| format!("cannot write {}", json_path.display()))?;
    writeln!(out, "{}", serde_json::to_string_pretty(&map)?).with_context(|| format!("cannot write {}", json_path.display()))?;
    Ok([csv_path, json_path])
}

/// `sigma_mm,x_mm,y_mm,z_mm` along the pelvic axis.
fn write_axis(path: &Path, samples: &[AxisSample]) -> anyhow::Result<PathBuf> {
    let mut csv = String::from("sigma_mm,x_mm,y_mm,z_mm,tangent_x,tangent_y,tangent_z\n");
    for s in samples {
        let ([x, y, z], [tx, ty, tz]) = (s.point_mm, s.tangent);
        csv += &format!("{:.4},{x:.4},{y:.4},{z:.4},{tx:.6},{ty:.6},{tz:.6}\n", s.sigma_mm);
    }
    std::fs::write(path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;
    use carus_anatomy::fetus::{FetalHead, HeadDiameters};

    /// Each part writes exactly the files [`file_names`] lists (what the
    /// overwrite check looks for), and a second run into the same folder is
    /// refused without `--force` and leaves the files as they were.
    #[test]
    fn the_overwrite_check_knows_every_file_and_refuses_without_force() {
        let dir = tempfile::tempdir().unwrap();
        for part in [MeshPart::Head, MeshPart::Trunk, MeshPart::Floor] {
            let out = dir.path().join(format!("{part:?}"));
            let args = MeshArgs { part, file: None, out: out.clone(), json: false, force: false };
            run(&args).unwrap();
            let mut written: Vec<String> =
                std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
            let mut listed = file_names(part);
            written.sort();
            listed.sort();
            assert_eq!(written, listed);
            let stamp = |name: &str| std::fs::metadata(out.join(name)).unwrap().modified().unwrap();
            let before = stamp(&listed[0]);
            let refusal = run(&args).unwrap_err().to_string();
            assert!(refusal.contains("--force") && refusal.contains(&listed[0]), "{refusal}");
            assert_eq!(stamp(&listed[0]), before);
            run(&MeshArgs { force: true, ..args }).unwrap();
        }
        // Pelvis writes a subset of the floor's files.
        assert!(file_names(MeshPart::Pelvis).iter().all(|n| file_names(MeshPart::Floor).contains(n)));
    }

    /// A run's folder holds the run's own pelvis.vtu: never written over.
    #[test]
    fn a_run_folder_is_refused_even_with_force() {
        use carus_labour::output::{RUN_FILE, SCENARIO_FILE};
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(SCENARIO_FILE), "").unwrap();
        std::fs::write(dir.path().join(RUN_FILE), "{}").unwrap();
        let args = MeshArgs { part: MeshPart::Pelvis, file: None, out: dir.path().to_path_buf(), json: false, force: true };
        let refusal = run(&args).unwrap_err().to_string();
        assert!(refusal.contains("holds carus runs"), "{refusal}");
        assert!(!dir.path().join("pelvis.stl").exists());
    }

    /// The generated head is a clean shell; a copy of it moved half its
    /// width into itself is not.
    #[test]
    fn a_clean_shell_has_no_crossings_and_an_overlapping_one_has() {
        let head = FetalHead::new(&HeadDiameters::default()).unwrap();
        assert_eq!(self_crossings("head", &head.surface), Some(0));
        let n = head.surface.vertices.len() as u32;
        let shift = glam::DVec3::new(0.03, 0.0, 0.0);
        let mut twice = head.surface.clone();
        twice.vertices.extend(head.surface.vertices.iter().map(|&v| v + shift));
        twice.triangles.extend(head.surface.triangles.iter().map(|t| t.map(|k| k + n)));
        assert!(self_crossings("head", &twice).unwrap() > 0);
    }

    /// A surface goes out twice, in one frame: STL in millimetres for CAD
    /// tools, VTU in metres to open in ParaView beside the floor's VTU.
    #[test]
    fn each_surface_is_written_in_millimetres_and_in_metres() {
        let head = FetalHead::new(&HeadDiameters::default()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let [stl, vtu] = write_surface(dir.path(), "head", &head.surface, "head frame").unwrap();
        let stl = std::fs::read(stl).unwrap();
        assert!(stl.starts_with(b"carus anatomy, millimetres, head frame"));
        let f32_at = |k: usize| f32::from_le_bytes(stl[k..k + 4].try_into().unwrap()) as f64;
        // The first triangle's first corner, after its normal.
        let corner_mm = glam::DVec3::new(f32_at(96), f32_at(100), f32_at(104));
        let first = head.surface.vertices[head.surface.triangles[0][0] as usize];
        assert!((corner_mm * 1e-3 - first).length() < 1e-7, "{corner_mm} mm against {first} m");
        let points = carus_io::vtk::read_vtk_arrays(&vtu).unwrap().points;
        assert_eq!(points.len(), head.surface.vertices.len());
        assert_eq!(points[0], head.surface.vertices[0].to_array());
        let text = std::fs::read_to_string(vtu).unwrap();
        assert!(text.contains(&format!("NumberOfCells=\"{}\"", head.surface.triangles.len())));
    }
}
