//! `carus render pelvis|head|fetus|floor|scene [FILE.toml] --out FILE.png`:
//! builds (or imports) the anatomy a file describes and draws a contact
//! sheet of standard views (docs/PICTURES.md).
//!
//! The turning of anatomy (f64, metres) into render meshes (f32) lives here
//! for now; the report crate draws its key moments with its own few lines.

use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_anatomy::fetus::{CapsuleChain, FetalHead, Fetus};
use carus_anatomy::floor::{ATTACHED, LEVATOR_ANI, PERINEAL_BODY};
use carus_anatomy::pelvis::measure;
use carus_anatomy::{Pelvis, TriSurface};
use carus_fem::mesh::Mesh;
use carus_labour::scene::{HEAD, LOWER_TRUNK, TRUNK};
use carus_labour::{Scenario, Scene as LabourScene};
use carus_render::{ContactSheet, RenderMesh, Renderer, Scene, View};
use glam::{DMat3, DVec3};

use super::measure::AnatomyFile;
use super::{print_json, Status};

/// What to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderPart {
    /// The bony pelvis with its landmarks, obstetric planes and pelvic axis.
    Pelvis,
    /// The fetal head with its landmarks (face towards the viewer in the anterior view).
    Head,
    /// The whole fetus: head, trunk and flexed limbs.
    Fetus,
    /// The pelvic floor in the pelvis it is shaped to, attached nodes marked.
    Floor,
    /// Pelvis, floor and fetus at the scenario's start (FILE is a built-in scenario's name or a scenario file).
    Scene,
}

/// A standard view of the pelvis frame (docs/RENDERING.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewName {
    Anterior,
    Lateral,
    Inferior,
    Superior,
    Oblique,
}

impl From<ViewName> for View {
    fn from(v: ViewName) -> View {
        match v {
            ViewName::Anterior => View::Anterior,
            ViewName::Lateral => View::Lateral,
            ViewName::Inferior => View::Inferior,
            ViewName::Superior => View::Superior,
            ViewName::Oblique => View::Oblique,
        }
    }
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// The part to draw.
    #[arg(value_enum)]
    pub part: RenderPart,
    /// Anatomy file (TOML, `[pelvis]`, `[head]`, `[floor]` tables as for
    /// `carus measure`); for `scene`, a built-in scenario's name or a
    /// scenario file. Without it, the defaults (the `normal` scenario).
    pub file: Option<PathBuf>,
    /// PNG file to write (its folder is created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Views, left to right, separated by commas (`--views superior,oblique`).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "anterior,lateral,inferior")]
    pub views: Vec<ViewName>,
    /// Side of each view's square tile, pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(16..=4096))]
    pub size: u32,
    /// Print one JSON object (the file and its size) on standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &RenderArgs) -> anyhow::Result<Status> {
    if !args.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        crate::bad_argument!("--out {}: carus render writes a PNG picture; name the file *.png", args.out.display());
    }
    super::check_picture_path(&args.out, "--out")?;
    let meshes = match args.part {
        RenderPart::Pelvis => pelvis_meshes(
            &AnatomyFile::load(args.file.as_deref())?.pelvis()?,
            BONE_OPACITY_ALONE,
        ),
        RenderPart::Head => {
            let file = AnatomyFile::load(args.file.as_deref())?;
            let head = file.head()?;
            head_meshes(&head, HEAD_OPACITY_ALONE)
        }
        RenderPart::Fetus => {
            let file = AnatomyFile::load(args.file.as_deref())?;
            // The head alone first, so that a diameter it cannot be built
            // from is named at its line, as `carus render head` names it.
            file.head()?;
            let fetus = Fetus::new(&file.head, &file.trunk)
                .with_context(|| format!("{}: the fetus cannot be built", file.describe()))?;
            fetus_meshes(&fetus)
        }
        RenderPart::Floor => {
            let file = AnatomyFile::load(args.file.as_deref())?;
            let pelvis = file.pelvis()?;
            let floor = file.floor(&pelvis)?;
            floor_meshes(&pelvis, &floor)
        }
        RenderPart::Scene => {
            // A built-in's name as `carus run` takes it, or a scenario file.
            let scenario = match args.file.as_deref() {
                Some(path) if path.to_str().is_none() => Scenario::from_file(path)?,
                file => super::run::load(file.and_then(Path::to_str))?,
            };
            let scene = LabourScene::build(&scenario)
                .with_context(|| format!("scenario `{}`", scenario.name))?;
            scene_meshes(&scene)
        }
    };
    let mut renderer =
        Renderer::new_headless().context("cannot draw without a graphics adapter")?;
    let sheet = ContactSheet {
        views: args.views.iter().map(|&v| v.into()).collect(),
        tile_size: [args.size, args.size],
        ..ContactSheet::default()
    };
    let picture = renderer.contact_sheet(&Scene::new(meshes), &sheet)?;
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        super::create_out_folder(dir, "--out")?;
    }
    super::save_picture(&picture, &args.out, "--out")?;
    if args.json {
        let views: Vec<&str> = sheet.views.iter().map(|v| v.name()).collect();
        print_json(&serde_json::json!({
            "out": args.out.display().to_string(),
            "width": picture.width(),
            "height": picture.height(),
            "views": views,
        }))?;
    } else {
        println!(
            "wrote {} ({} x {})",
            args.out.display(),
            picture.width(),
            picture.height()
        );
    }
    Ok(Status::Success)
}

// Colours are sRGB. Bone, skin and muscle as in the report's pictures.
const BONE_RGB: [f32; 3] = [0.89, 0.85, 0.76];
/// See-through enough that landmarks and planes inside the canal show.
const BONE_OPACITY_ALONE: f32 = 0.7;
/// Fainter when the pelvis is context for the floor or the fetus.
const BONE_OPACITY_CONTEXT: f32 = 0.3;
const HEAD_RGB: [f32; 3] = [0.93, 0.72, 0.62];
/// The head drawn alone is see-through enough to show the atlanto-occipital
/// pivot inside it.
const HEAD_OPACITY_ALONE: f32 = 0.8;
const TRUNK_RGB: [f32; 3] = [0.86, 0.64, 0.56];
const LEVATOR_RGB: [f32; 3] = [0.78, 0.42, 0.42];
const PERINEAL_BODY_RGB: [f32; 3] = [0.55, 0.27, 0.35];
/// Landmarks of CONVENTIONS.md, and the further ones the planes and obliques use.
pub(super) const LANDMARK_RGB: [f32; 3] = [0.80, 0.08, 0.10];
/// Light cyan: apart from the dark blue posterior fontanelle the viewer
/// draws beside them.
const AUXILIARY_LANDMARK_RGB: [f32; 3] = [0.55, 0.90, 0.95];
/// The head's landmarks where the pelvis's are drawn too (the viewer):
/// white, apart from the pelvis's red.
pub(super) const HEAD_AMONG_PELVIS_RGB: [f32; 3] = [0.97, 0.97, 0.97];
const ATTACHED_RGB: [f32; 3] = [0.20, 0.20, 0.20];
const AXIS_RGB: [f32; 3] = [0.10, 0.55, 0.25];
/// Inlet, greatest dimensions, mid-pelvis, outlet.
const PLANE_RGB: [[f32; 3]; 4] = [
    [0.20, 0.45, 0.90],
    [0.15, 0.70, 0.45],
    [0.95, 0.60, 0.10],
    [0.60, 0.25, 0.75],
];
const PLANE_OPACITY: f32 = 0.3;
/// Marker sizes, m: visible on a 384 px tile of the whole pelvis.
const PELVIS_MARKER_M: f32 = 3.5e-3;
pub(super) const HEAD_MARKER_M: f32 = 2.5e-3;
const ATTACHED_MARKER_M: f32 = 1.2e-3;
const AXIS_RADIUS_M: f32 = 1.5e-3;
/// Points round each plane's outline.
const OUTLINE_SAMPLES: usize = 64;

/// The landmarks CONVENTIONS.md names for every pelvis.
const CONVENTIONS_LANDMARKS: [&str; 10] = [
    "sacral_promontory",
    "symphysis_upper",
    "symphysis_lower",
    "iliopectineal_left",
    "iliopectineal_right",
    "ischial_spine_left",
    "ischial_spine_right",
    "ischial_tuberosity_left",
    "ischial_tuberosity_right",
    "coccyx_tip",
];

/// Head frame (x occipitofrontal, y fetal left, z vertex) turned so the face
/// looks along +y: the standard views then read as for a person in the
/// anatomical position (anterior = the face, lateral = from the fetal right).
const HEAD_TO_PICTURE: DMat3 = DMat3::from_cols(DVec3::Y, DVec3::NEG_X, DVec3::Z);

fn f32_point(p: DVec3) -> [f32; 3] {
    p.as_vec3().to_array()
}

/// A closed surface, each vertex mapped by `place` (metres, pelvis frame).
fn surface_mesh(
    name: &str,
    surface: &TriSurface,
    place: impl Fn(DVec3) -> DVec3,
    rgb: [f32; 3],
) -> RenderMesh {
    let positions = surface
        .vertices
        .iter()
        .map(|&v| f32_point(place(v)))
        .collect();
    RenderMesh::new(
        name,
        positions,
        surface.triangles.iter().flatten().copied().collect(),
        rgb,
    )
}

/// The pelvis: bone, landmarks, the four obstetric planes and the pelvic axis.
fn pelvis_meshes(pelvis: &Pelvis, bone_opacity: f32) -> Vec<RenderMesh> {
    let mut meshes =
        vec![surface_mesh("pelvis", &pelvis.surface, |v| v, BONE_RGB).with_opacity(bone_opacity)];
    meshes.extend(pelvis_markers(pelvis));
    meshes
}

/// The pelvis's landmarks, its four obstetric planes and the pelvic axis,
/// without the bone (the viewer lays them over a run).
pub(super) fn pelvis_markers(pelvis: &Pelvis) -> Vec<RenderMesh> {
    let mut meshes = Vec::new();
    for (name, p) in pelvis.landmarks.named() {
        let rgb = if CONVENTIONS_LANDMARKS.contains(&name) {
            LANDMARK_RGB
        } else {
            AUXILIARY_LANDMARK_RGB
        };
        meshes.push(RenderMesh::sphere(name, f32_point(p), PELVIS_MARKER_M, rgb));
    }
    for ((name, outline), rgb) in plane_outlines(pelvis).into_iter().zip(PLANE_RGB) {
        let outline: Vec<[f32; 3]> = outline.into_iter().map(f32_point).collect();
        meshes.push(RenderMesh::polygon(name, &outline, rgb).with_opacity(PLANE_OPACITY));
    }
    meshes.push(axis_tube(pelvis));
    meshes
}

/// The curve of Carus from the inlet centre to the outlet centre.
fn axis_tube(pelvis: &Pelvis) -> RenderMesh {
    let points: Vec<[f32; 3]> = carus_anatomy::pelvis::axis_samples(pelvis)
        .iter()
        .map(|s| s.point_mm.map(|x| (x * 1e-3) as f32))
        .collect();
    RenderMesh::tube("pelvic axis", &points, AXIS_RADIUS_M, AXIS_RGB)
}

/// Each obstetric plane's outline: an egg through the ends of its
/// antero-posterior and transverse diameters (projected into the plane),
/// quarter ellipses between them. It shows where each diameter is taken,
/// not the bony wall itself.
fn plane_outlines(pelvis: &Pelvis) -> [(&'static str, Vec<DVec3>); 4] {
    let l = &pelvis.landmarks;
    let p = &pelvis.planes;
    let right = (l.iliopectineal_right - l.iliopectineal_left).normalize();
    // The greatest transverse is measured on the surface through the plane's centre.
    let greatest_half = measure(pelvis).planes["greatest_dimensions"]
        .transverse_mm
        .map_or(0.0, |t| 0.5e-3 * t);
    let greatest_right = (right - right.dot(p.greatest.normal) * p.greatest.normal).normalize();
    [
        (
            "inlet plane",
            egg(
                p.inlet.normal,
                l.sacral_promontory,
                l.symphysis_upper,
                l.iliopectineal_left,
                l.iliopectineal_right,
            ),
        ),
        (
            "greatest dimensions plane",
            egg(
                p.greatest.normal,
                l.sacrum_s2_s3,
                l.symphysis_middle(),
                p.greatest.centre - greatest_half * greatest_right,
                p.greatest.centre + greatest_half * greatest_right,
            ),
        ),
        (
            "mid-pelvis plane",
            egg(
                p.mid.normal,
                l.sacrum_s4_s5,
                l.symphysis_lower,
                l.ischial_spine_left,
                l.ischial_spine_right,
            ),
        ),
        (
            "outlet plane",
            egg(
                p.outlet.normal,
                l.coccyx_tip,
                l.symphysis_lower,
                l.ischial_tuberosity_left,
                l.ischial_tuberosity_right,
            ),
        ),
    ]
}

/// Outline in the plane through `posterior` and `anterior` with `normal`:
/// four quarter ellipses centred where the transverse ends project onto
/// the antero-posterior line, through all four ends.
fn egg(normal: DVec3, posterior: DVec3, anterior: DVec3, left: DVec3, right: DVec3) -> Vec<DVec3> {
    let forward = (anterior - posterior).normalize();
    let across = normal.cross(forward).normalize();
    let across = if across.dot(right - left) < 0.0 {
        -across
    } else {
        across
    };
    let u = |q: DVec3| (q - posterior).dot(forward);
    let w = |q: DVec3| (q - posterior).dot(across);
    let centre = 0.5 * (u(left) + u(right));
    let (front, back) = (u(anterior) - centre, centre);
    let (to_right, to_left) = (w(right).abs(), w(left).abs());
    (0..OUTLINE_SAMPLES)
        .map(|k| {
            let (sin, cos) = (std::f64::consts::TAU * k as f64 / OUTLINE_SAMPLES as f64).sin_cos();
            let along = centre + cos * if cos > 0.0 { front } else { back };
            let side = sin * if sin > 0.0 { to_right } else { to_left };
            posterior + along * forward + side * across
        })
        .collect()
}

/// The head and its landmarks, face towards the viewer of the anterior view.
fn head_meshes(head: &FetalHead, opacity: f32) -> Vec<RenderMesh> {
    let place = |v: DVec3| HEAD_TO_PICTURE * v;
    let mut meshes =
        vec![surface_mesh("fetal head", &head.surface, place, HEAD_RGB).with_opacity(opacity)];
    meshes.extend(landmark_markers(
        head.landmarks.named(),
        place,
        HEAD_MARKER_M,
    ));
    meshes
}

fn landmark_markers<'a>(
    named: impl IntoIterator<Item = (&'a str, DVec3)>,
    place: impl Fn(DVec3) -> DVec3,
    radius: f32,
) -> Vec<RenderMesh> {
    named
        .into_iter()
        .map(|(name, p)| RenderMesh::sphere(name, f32_point(place(p)), radius, LANDMARK_RGB))
        .collect()
}

/// Head, trunk and limbs with the neck straight, in the head's picture frame.
fn fetus_meshes(fetus: &Fetus) -> Vec<RenderMesh> {
    let to_head = fetus.trunk_to_head();
    let place_trunk = |v: DVec3| HEAD_TO_PICTURE * to_head.transform_point3(v);
    let mut meshes = head_meshes(&fetus.head, 1.0);
    meshes.push(surface_mesh(
        "fetal trunk",
        &fetus.trunk.surface,
        place_trunk,
        TRUNK_RGB,
    ));
    for (name, chain) in fetus.limbs.named() {
        meshes.extend(capsules(name, chain, place_trunk));
    }
    meshes
}

/// A limb: a tube per segment and a sphere at each joint closing it.
fn capsules(name: &str, chain: &CapsuleChain, place: impl Fn(DVec3) -> DVec3) -> Vec<RenderMesh> {
    let mut meshes = Vec::new();
    for (a, b, radius) in chain.segments() {
        let ends = [f32_point(place(a)), f32_point(place(b))];
        meshes.push(RenderMesh::tube(name, &ends, radius as f32, TRUNK_RGB));
        for end in ends {
            meshes.push(RenderMesh::sphere(name, end, radius as f32, TRUNK_RGB));
        }
    }
    meshes
}

/// The floor's levator ani and perineal body in the faint pelvis, attached nodes marked.
fn floor_meshes(pelvis: &Pelvis, floor: &Mesh) -> Vec<RenderMesh> {
    let mut meshes = floor_parts(floor, |p| p);
    meshes.extend(
        floor
            .node_sets
            .get(ATTACHED)
            .into_iter()
            .flatten()
            .map(|&n| {
                RenderMesh::sphere(
                    "attached node",
                    f32_point(floor.nodes[n as usize].into()),
                    ATTACHED_MARKER_M,
                    ATTACHED_RGB,
                )
            }),
    );
    meshes.push(
        surface_mesh("pelvis", &pelvis.surface, |v| v, BONE_RGB).with_opacity(BONE_OPACITY_CONTEXT),
    );
    meshes
}

/// The outer faces of each element set of the floor (levator ani, perineal body).
fn floor_parts(floor: &Mesh, place: impl Fn(DVec3) -> DVec3) -> Vec<RenderMesh> {
    let positions: Vec<[f32; 3]> = floor
        .nodes
        .iter()
        .map(|&p| f32_point(place(p.into())))
        .collect();
    let mut meshes = Vec::new();
    for (set, rgb) in [
        (LEVATOR_ANI, LEVATOR_RGB),
        (PERINEAL_BODY, PERINEAL_BODY_RGB),
    ] {
        let Some(elements) = floor.element_sets.get(set) else {
            continue;
        };
        let triangles: Vec<u32> = floor.boundary_triangles(elements).concat();
        if !triangles.is_empty() {
            meshes.push(RenderMesh::new(
                set.replace('_', " "),
                positions.clone(),
                triangles,
                rgb,
            ));
        }
    }
    meshes
}

/// The scenario's starting scene: faint pelvis with its axis, the floor at
/// rest and the fetus (head and trunk) at its starting pose.
fn scene_meshes(scene: &LabourScene) -> Vec<RenderMesh> {
    let head_pose = scene.start[HEAD];
    let mut meshes = vec![surface_mesh(
        "fetal head",
        &scene.head.surface,
        |v| head_pose.point(v),
        HEAD_RGB,
    )];
    for (name, body, b) in [
        ("fetal trunk", &scene.trunk, TRUNK),
        ("fetal lower trunk", &scene.lower_trunk, LOWER_TRUNK),
    ] {
        if let (Some(body), Some(pose)) = (body, scene.start.get(b)) {
            meshes.push(surface_mesh(name, &body.surface, |v| pose.point(v), TRUNK_RGB));
        }
    }
    if let Some(floor) = &scene.floor {
        meshes.extend(floor_parts(&floor.mesh, |p| p));
    }
    meshes.push(axis_tube(&scene.pelvis));
    meshes.push(
        surface_mesh("pelvis", &scene.pelvis.surface, |v| v, BONE_RGB)
            .with_opacity(BONE_OPACITY_CONTEXT),
    );
    meshes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_outlines_pass_through_the_ends_of_their_diameters() {
        let pelvis = Pelvis::generate(&Default::default()).unwrap();
        let [(_, inlet), ..] = plane_outlines(&pelvis);
        let l = &pelvis.landmarks;
        let plane = pelvis.planes.inlet;
        for end in [l.sacral_promontory, l.symphysis_upper] {
            let nearest = inlet
                .iter()
                .map(|p| (*p - end).length())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < 1e-9,
                "an outline point misses {end} by {nearest} m"
            );
        }
        for end in [l.iliopectineal_left, l.iliopectineal_right] {
            let nearest = inlet
                .iter()
                .map(|p| (*p - plane.project(end)).length())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < 1e-3,
                "the outline passes {nearest} m from a transverse end"
            );
        }
        assert!(inlet.iter().all(|p| plane.signed_distance(*p).abs() < 1e-9));
    }

    #[test]
    fn the_head_picture_frame_turns_the_face_anterior() {
        let head = FetalHead::new(&Default::default()).unwrap();
        let face = HEAD_TO_PICTURE * head.landmarks.nasion;
        let left = HEAD_TO_PICTURE * head.landmarks.parietal_eminence_left;
        assert!(face.y > 0.0 && face.x.abs() < 1e-12);
        // The fetal left is on the mother's-left side of the pelvis frame (-x).
        assert!(left.x < 0.0);
        assert!((HEAD_TO_PICTURE.determinant() - 1.0).abs() < 1e-12);
    }

    #[derive(clap::Parser)]
    struct Command {
        #[command(flatten)]
        args: RenderArgs,
    }

    #[test]
    fn the_command_line_takes_views_and_a_size() {
        use clap::Parser;
        let plain = Command::try_parse_from(["render", "head", "--out", "head.png"])
            .unwrap()
            .args;
        assert_eq!(
            plain.views,
            [ViewName::Anterior, ViewName::Lateral, ViewName::Inferior]
        );
        assert_eq!(plain.size, 512);
        let chosen = Command::try_parse_from([
            "render",
            "pelvis",
            "p.toml",
            "--out",
            "p.png",
            "--views",
            "superior,oblique",
            "--size",
            "300",
        ])
        .unwrap()
        .args;
        assert_eq!(chosen.views, [ViewName::Superior, ViewName::Oblique]);
        assert_eq!(
            (chosen.size, chosen.file),
            (300, Some(PathBuf::from("p.toml")))
        );
        assert!(
            Command::try_parse_from(["render", "head", "--out", "h.png", "--size", "8"]).is_err()
        );
        assert!(Command::try_parse_from([
            "render",
            "head",
            "--out",
            "h.png",
            "--views",
            "posterior"
        ])
        .is_err());
    }

    #[test]
    fn a_missing_file_is_named() {
        let args = RenderArgs {
            part: RenderPart::Pelvis,
            file: Some(PathBuf::from("no/such/anatomy.toml")),
            out: std::env::temp_dir().join("carus-render-never-written.png"),
            views: vec![ViewName::Anterior],
            size: 32,
            json: false,
        };
        let Err(error) = run(&args) else {
            panic!("a missing file was accepted")
        };
        let message = format!("{error:#}");
        assert!(message.contains("no/such/anatomy.toml"), "{message}");
        // The scene takes a built-in's name as `carus run` does, and names them all when it is neither.
        let out = std::env::temp_dir().join(format!("carus-render-textbook-{}.png", std::process::id()));
        let scene = |file: &str| RenderArgs {
            part: RenderPart::Scene,
            file: Some(PathBuf::from(file)),
            out: out.clone(),
            views: vec![ViewName::Lateral],
            size: 32,
            json: false,
        };
        let message = format!("{:#}", run(&scene("no-such-scenario")).err().unwrap());
        assert!(message.contains("neither a built-in scenario (normal,") && message.contains("textbook) nor a file"), "{message}");
        assert!(matches!(run(&scene("textbook")).unwrap(), Status::Success));
        std::fs::remove_file(&out).unwrap();
        // A fetus whose head cannot be built names the diameter's line.
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("head.toml");
        std::fs::write(&file, "[head]\nbiparietal_mm = 95.0\nbitemporal_mm = 99.0\n").unwrap();
        let fetus = RenderArgs { part: RenderPart::Fetus, file: Some(file.clone()), out: dir.path().join("f.png"), views: vec![ViewName::Anterior], size: 32, json: false };
        let message = format!("{:#}", run(&fetus).err().unwrap());
        assert!(message.starts_with(&format!("{}:3: [head]: the diameters cannot be built: bitemporal_mm", file.display())), "{message}");
        assert!(!dir.path().join("f.png").exists());
    }

    #[test]
    fn render_head_writes_a_png_of_the_sheet_size() {
        let out =
            std::env::temp_dir().join(format!("carus-render-head-{}.png", std::process::id()));
        let args = RenderArgs {
            part: RenderPart::Head,
            file: None,
            out: out.clone(),
            views: vec![ViewName::Anterior, ViewName::Lateral, ViewName::Inferior],
            size: 64,
            json: false,
        };
        assert!(matches!(run(&args).unwrap(), Status::Success));
        let bytes = std::fs::read(&out).unwrap();
        let picture = carus_render::Image::decode_png(&bytes).unwrap();
        std::fs::remove_file(&out).unwrap();
        // Three 64 px tiles, an 8 px gap around and between, a label strip above.
        let sheet = ContactSheet::default();
        assert_eq!(picture.width(), 3 * 64 + 4 * sheet.gap);
        assert_eq!(
            picture.height(),
            64 + carus_render::LABEL_STRIP + 2 * sheet.gap
        );
        // Something was drawn: not every pixel is the white background.
        assert!(picture
            .pixels()
            .chunks_exact(4)
            .any(|p| p[..3] != [255, 255, 255]));
    }
}
