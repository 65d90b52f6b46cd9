//! Pictures of the key moments: the pelvis semi-transparent, the fetus
//! opaque where the history places it (the trunk see-through when forces
//! are drawn), the floor coloured by stretch;
//! every picture of a report from one camera scale, so sizes compare.

use base64::engine::general_purpose::STANDARD;
use base64::Engine as _;
use carus_analysis::{PoseHistory, RigidPose};
use carus_anatomy::TriSurface;
use carus_render::{Bounds, Camera, ColourMap, RenderError, RenderMesh, Renderer, Scene, View};
use glam::DVec3;

use crate::input::{FloorFrame, FloorSurface, ReportScene};
use carus_analysis::moments::KeyMoment;

/// The views of every key moment: from the mother's right (the curve of
/// Carus in profile) and from below (the outlet, as the accoucheur sees it).
pub const VIEWS: [View; 2] = [View::Lateral, View::Inferior];
/// Picture size, px.
pub const PICTURE_SIZE: (u32, u32) = (440, 400);
/// Bone colour (sRGB) and opacity: see-through so the fetus shows inside.
const PELVIS_RGB: [f32; 3] = [0.89, 0.85, 0.76];
const PELVIS_OPACITY: f32 = 0.35;
const HEAD_RGB: [f32; 3] = [0.93, 0.72, 0.62];
const TRUNK_RGB: [f32; 3] = [0.86, 0.64, 0.56];
/// Name of the pelvis's mesh, which stays still while the fetus moves.
pub const PELVIS: &str = "pelvis";
/// Name of the trunk's mesh, which the camera's fit leaves out.
const TRUNK: &str = "fetal trunk";
const LOWER_TRUNK: &str = "fetal lower trunk";
/// Name of the pelvic floor's mesh.
pub const FLOOR: &str = "pelvic floor";
/// Arrow length per newton of force, m: 10 mm per 20 N, so the canal's
/// pushes of tens of newtons are a head's radius or less and the default
/// expulsion's 120 N peak is 60 mm, beside a 95 mm head.
pub const ARROW_M_PER_N: f64 = 0.5e-3;

/// The floor's and the trunk's opacity while forces are drawn: the floor
/// pushes from around the head, and the trunk's push reaches the head
/// through the neck, inside the trunk; see-through they show the arrows
/// they would hide.
pub const OPACITY_UNDER_FORCES: f32 = 0.45;

/// Makes the floor and the trunk among `meshes` see-through, for arrows
/// drawn with them.
pub fn see_through_under_forces(meshes: &mut [RenderMesh]) {
    for mesh in meshes.iter_mut().filter(|m| [FLOOR, TRUNK, LOWER_TRUNK].contains(&m.name.as_str())) {
        mesh.colour[3] = OPACITY_UNDER_FORCES;
    }
}

/// The fontanelles' markers, sized as the fontanelles are told apart by
/// touch (the posterior a small triangle, the anterior a diamond about
/// 2.5 cm across), radius m, and coloured apart: the posterior dark, the
/// anterior light. Drawing sizes, not anatomy.
pub const POSTERIOR_FONTANELLE_M: f32 = 5.0e-3;
pub const ANTERIOR_FONTANELLE_M: f32 = 7.0e-3;
pub const POSTERIOR_FONTANELLE_RGB: [f32; 3] = [0.10, 0.14, 0.42];
pub const ANTERIOR_FONTANELLE_RGB: [f32; 3] = [0.98, 0.88, 0.35];

/// Muscle colour for a floor without recorded stretch.
const FLOOR_RGB: [f32; 3] = [0.78, 0.50, 0.50];
/// Smallest upper end of the stretch colour scale, so a floor at rest is
/// not stretched over the whole map by rounding noise.
pub const MIN_STRETCH_TOP: f64 = 1.05;

/// One picture as it goes into the page.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    pub view: View,
    /// `data:image/png;base64,...`
    pub data_uri: String,
}

/// The pictures of one moment, or why there are none.
#[derive(Debug, Clone, PartialEq)]
pub struct MomentPictures {
    pub moment: KeyMoment,
    /// The forces drawn as arrows: what pushes, its size in newtons and its
    /// arrow's colour, largest first (empty: none drawn).
    pub forces: Vec<(String, f64, [f32; 3])>,
    /// Time of the floor frame drawn, when it is not the moment's own.
    pub floor_time_s: Option<f64>,
    pub pictures: Result<Vec<Picture>, String>,
}

/// The stretch range of the colour scale, shared by every picture (and
/// the viewer): of the frames before `untrusted_from_s`, when an element
/// had turned inside out (the stretches after it are no tissue's, and
/// would wash out the colours before: docs/LABOUR.md), or of them all
/// when none comes before.
pub fn stretch_range(floor: &FloorSurface, untrusted_from_s: Option<f64>) -> Option<[f64; 2]> {
    untrusted_from_s
        .and_then(|t| stretch_range_of(floor.frames.iter().filter(|f| f.time_s < t)))
        .or_else(|| stretch_range_of(&floor.frames))
}

/// The floor frame recorded nearest `time_s`, which a picture of that
/// moment draws; none when no frame was recorded.
pub fn nearest_frame(floor: &FloorSurface, time_s: f64) -> Option<&FloorFrame> {
    floor.frames.iter().min_by(|a, b| (a.time_s - time_s).abs().total_cmp(&(b.time_s - time_s).abs()))
}

/// The colour scale's stretch range over `frames`: from 1 (rest) to the
/// largest stretch, at least [`MIN_STRETCH_TOP`]; none without a number.
fn stretch_range_of<'a>(frames: impl IntoIterator<Item = &'a FloorFrame>) -> Option<[f64; 2]> {
    let top = frames
        .into_iter()
        .flat_map(|f| f.stretch.iter().copied())
        .filter(|s| s.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    (top.is_finite()).then(|| [1.0, top.max(MIN_STRETCH_TOP)])
}

/// Draws every moment from every view. Failures of single pictures are
/// kept per moment; the caller turns them into warnings.
pub fn draw(
    renderer: &mut Renderer,
    scene: &ReportScene,
    history: &PoseHistory,
    moments: &[KeyMoment],
    range: Option<[f64; 2]>,
) -> Vec<MomentPictures> {
    let posed: Vec<(Vec<RenderMesh>, Option<f64>)> = moments
        .iter()
        .map(|m| meshes_at(scene, history, m, range))
        .collect();
    let bounds = fitting_bounds(posed.iter().flat_map(|(meshes, _)| meshes.iter()));
    moments
        .iter()
        .zip(posed)
        .map(|(moment, (meshes, floor_time_s))| MomentPictures {
            moment: *moment,
            forces: scene.forces.iter().find(|f| f.sample == moment.sample).map_or_else(Vec::new, |f| f.listed.clone()),
            floor_time_s,
            pictures: bounds
                .ok_or_else(|| "the scene has no vertices".to_string())
                .and_then(|b| render_views(renderer, meshes, &b).map_err(|e| e.to_string())),
        })
        .collect()
}

/// What a camera is fitted to: every mesh but the trunk's. The trunk
/// reaches far above the inlet early and far below the outlet late;
/// fitting it would shrink the canal, so it may run off the picture's edge.
pub fn fitting_bounds<'a>(meshes: impl IntoIterator<Item = &'a RenderMesh>) -> Option<Bounds> {
    meshes
        .into_iter()
        .filter(|mesh| mesh.name != TRUNK && mesh.name != LOWER_TRUNK)
        .filter_map(RenderMesh::bounds)
        .reduce(Bounds::union)
}

fn render_views(
    renderer: &mut Renderer,
    meshes: Vec<RenderMesh>,
    bounds: &Bounds,
) -> Result<Vec<Picture>, RenderError> {
    let uploaded = renderer.upload(&Scene::new(meshes))?;
    VIEWS
        .iter()
        .map(|&view| {
            let camera = Camera::standard(view, bounds);
            let image =
                renderer.render_uploaded(&uploaded, &camera, PICTURE_SIZE.0, PICTURE_SIZE.1)?;
            Ok(Picture {
                view,
                data_uri: format!(
                    "data:image/png;base64,{}",
                    STANDARD.encode(image.encode_png()?)
                ),
            })
        })
        .collect()
}

/// The meshes of one moment (opaque fetus first, then the see-through
/// pelvis), and the time of the floor frame used when it differs from the
/// moment's.
fn meshes_at(
    scene: &ReportScene,
    history: &PoseHistory,
    moment: &KeyMoment,
    stretch_range: Option<[f64; 2]>,
) -> (Vec<RenderMesh>, Option<f64>) {
    let (mut meshes, frame_time) = meshes_at_sample(scene, history, moment.sample, stretch_range);
    if let Some(forces) = scene.forces.iter().find(|f| f.sample == moment.sample) {
        see_through_under_forces(&mut meshes);
        meshes.extend(forces.arrows.iter().cloned());
    }
    // A frame within half the captions' tenth of a second of its
    // moment needs no note.
    (meshes, frame_time.filter(|t| (t - moment.time_s).abs() >= FLOOR_NOTE_FROM_S))
}

/// The meshes of the history's sample `sample`: the fetus where it was
/// (opaque), the floor at its recorded frame nearest in time, coloured by
/// stretch over `stretch_range`, and the see-through pelvis last; with the
/// floor frame's time. The report's pictures and the viewer draw these.
pub fn meshes_at_sample(
    scene: &ReportScene,
    history: &PoseHistory,
    sample: usize,
    stretch_range: Option<[f64; 2]>,
) -> (Vec<RenderMesh>, Option<f64>) {
    let sample = &history.samples[sample];
    let time_s = sample.time_s;
    let mut meshes = vec![posed_mesh(
        "fetal head",
        &scene.head,
        &sample.head,
        HEAD_RGB,
    )];
    if let Some(fontanelles) = &scene.fontanelles {
        let marker = |name, at, radius, rgb| RenderMesh::sphere(name, sample.head.point(at).as_vec3().to_array(), radius, rgb);
        meshes.push(marker("posterior fontanelle", fontanelles.posterior, POSTERIOR_FONTANELLE_M, POSTERIOR_FONTANELLE_RGB));
        meshes.push(marker("anterior fontanelle", fontanelles.anterior, ANTERIOR_FONTANELLE_M, ANTERIOR_FONTANELLE_RGB));
    }
    if let (Some(trunk), Some(pose)) = (&scene.trunk, &sample.trunk) {
        meshes.push(posed_mesh(TRUNK, trunk, pose, TRUNK_RGB));
    }
    if let (Some(lower), Some(pose)) = (&scene.lower_trunk, &sample.lower_trunk) {
        meshes.push(posed_mesh(LOWER_TRUNK, lower, pose, TRUNK_RGB));
    }
    let mut floor_time_s = None;
    if let Some(floor) = &scene.floor {
        let (mesh, frame_time) = floor_mesh(floor, time_s, stretch_range);
        floor_time_s = frame_time;
        meshes.push(mesh);
    }
    if let Some(pelvis) = &scene.pelvis {
        meshes.push(
            RenderMesh::new(
                PELVIS,
                to_f32(pelvis.vertices.iter().copied()),
                indices(&pelvis.triangles),
                PELVIS_RGB,
            )
            .with_opacity(PELVIS_OPACITY),
        );
    }
    (meshes, floor_time_s)
}

fn posed_mesh(name: &str, surface: &TriSurface, pose: &RigidPose, rgb: [f32; 3]) -> RenderMesh {
    RenderMesh::new(
        name,
        to_f32(surface.vertices.iter().map(|&v| pose.point(v))),
        indices(&surface.triangles),
        rgb,
    )
}

/// How far a floor frame may lie from its moment, s, before the caption
/// gives the frame's own time.
const FLOOR_NOTE_FROM_S: f64 = 0.05;

/// The floor at the frame nearest `time_s`, coloured by its stretch; at
/// rest and plain when no frame was recorded.
fn floor_mesh(
    floor: &FloorSurface,
    time_s: f64,
    range: Option<[f64; 2]>,
) -> (RenderMesh, Option<f64>) {
    let nearest = nearest_frame(floor, time_s);
    let triangles = indices(&floor.triangles);
    match (nearest, range) {
        (Some(frame), Some(range)) => (
            RenderMesh::new(
                FLOOR,
                to_f32(frame.positions_m.iter().copied()),
                triangles,
                FLOOR_RGB,
            )
            .with_scalars(
                frame.stretch.iter().map(|&s| s as f32).collect(),
                [range[0] as f32, range[1] as f32],
                ColourMap::Viridis,
            ),
            Some(frame.time_s),
        ),
        _ => (
            RenderMesh::new(
                FLOOR,
                to_f32(floor.rest_positions_m.iter().copied()),
                triangles,
                FLOOR_RGB,
            ),
            None,
        ),
    }
}

fn to_f32(points: impl Iterator<Item = DVec3>) -> Vec<[f32; 3]> {
    points.map(|p| p.as_vec3().to_array()).collect()
}

fn indices(triangles: &[[u32; 3]]) -> Vec<u32> {
    triangles.iter().flatten().copied().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stretch_scale_starts_at_rest_and_never_collapses() {
        let frame = |s: Vec<f64>| FloorFrame {
            time_s: 0.0,
            positions_m: vec![DVec3::ZERO; s.len()],
            stretch: s,
        };
        let floor = |frames| FloorSurface {
            triangles: vec![],
            rest_positions_m: vec![DVec3::ZERO; 2],
            frames,
        };
        assert_eq!(stretch_range(&floor(vec![]), None), None);
        assert_eq!(
            stretch_range(&floor(vec![frame(vec![1.0, 1.0])]), None),
            Some([1.0, MIN_STRETCH_TOP])
        );
        let two = floor(vec![frame(vec![1.0, 1.3]), FloorFrame { time_s: 1.0, ..frame(vec![1.6, 1.1]) }]);
        assert_eq!(stretch_range(&two, None), Some([1.0, 1.6]));
        // From an element turned inside out at 1 s, the later frames are
        // left out of the scale; with none before, all count.
        assert_eq!(stretch_range(&two, Some(1.0)), Some([1.0, 1.3]));
        assert_eq!(stretch_range(&two, Some(0.0)), Some([1.0, 1.6]));
    }
}
