//! A reproducible procedure that suggests the pelvis landmarks on a real,
//! segmented bony pelvis: extremal-point searches in slabs of the bones and
//! where neighbouring bones meet. It produced the shipped Visible Human
//! Female landmarks (docs/IMPORT.md lists the steps and the results); for a
//! new mesh its suggestions are a start to check by eye, not ground truth.
//!
//! Input: the vertices of each bone in the anatomical frame (metres; x to
//! the mother's right, y anterior, z cranial, as a landmarks file's axes
//! declare). Left and right arrays are indexed [left, right].

use std::collections::HashMap;

use glam::{DMat3, DVec3};

use super::NamedPart;
use crate::pelvis::PelvisLandmarks;

const MM: f64 = 1e-3;
/// Half-widths of the midline slabs through the symphysis and the sacrum.
const PUBIC_SLAB: f64 = 8.0 * MM;
const SACRAL_SLAB: f64 = 5.0 * MM;
/// Thickness taken as the lower or upper edge of a structure.
const EDGE_BAND: f64 = 4.0 * MM;
/// The promontory lies at least this far above the top of the symphysis.
const PROMONTORY_ABOVE_SYMPHYSIS: f64 = 40.0 * MM;
/// The brim is sought this far below and above the inlet plane: posteriorly
/// the arcuate lines run below the plane through promontory and symphysis.
const BRIM_BELOW: f64 = 20.0 * MM;
const BRIM_ABOVE: f64 = 3.0 * MM;
/// Levels (mm) either side searched for a wall's innermost point.
const WALL_WINDOW: i64 = 2;
/// Vertices of two bones closer than this are taken as their junction.
const JUNCTION: f64 = 2.5 * MM;
/// The ischial spines lie behind this antero-posterior level of the inlet frame.
const SPINE_MAX_ANTERIOR: f64 = 30.0 * MM;
/// Radius around the lowest point of an ischium searched for its inner surface.
const TUBEROSITY_RADIUS: f64 = 15.0 * MM;
/// Fractions of the anterior sacral curve (promontory to apex) at the
/// S2-S3 and S4-S5 junctions: cumulative heights of sacral bodies of about
/// 28, 24, 20, 15 and 12 mm (engineering estimate from adult female sacra).
const S2_S3_FRACTION: f64 = 52.0 / 99.0;
const S4_S5_FRACTION: f64 = 87.0 / 99.0;
/// Half-height of the band searched for the sacrum's lower lateral borders.
const BORDER_BAND: f64 = 5.0 * MM;

/// Vertices of each bone of a pelvis, anatomical frame, metres.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PelvisBones {
    pub sacrum: Vec<DVec3>,
    pub coccyx: Vec<DVec3>,
    /// [left, right]
    pub pubis: [Vec<DVec3>; 2],
    pub ilium: [Vec<DVec3>; 2],
    pub ischium: [Vec<DVec3>; 2],
}

/// Why landmarks could not be picked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PickError {
    #[error("no mesh part for the {0}: name the parts sacrum, coccyx, and ilium/ischium/pubis with _L/_R")]
    MissingBone(&'static str),
    #[error("found no {0}: is the mesh a whole pelvis in the declared axes?")]
    NotFound(&'static str),
}

impl PelvisBones {
    /// Sorts named parts (HuBMAP naming, e.g. `VH_F_pubis_compact_bone_L`)
    /// into bones, mapping file coordinates by `to_anatomical` after
    /// `scale`; spongy (inner) shells are left out.
    pub fn from_named_parts(parts: &[NamedPart], to_anatomical: DMat3, scale: f64) -> Result<Self, PickError> {
        let mut bones = PelvisBones::default();
        for part in parts {
            let name = part.name.to_ascii_lowercase();
            if name.contains("spongy") {
                continue;
            }
            let side = if name.ends_with("_l") || name.ends_with("left") {
                0
            } else {
                1
            };
            let target = if name.contains("sacrum") {
                &mut bones.sacrum
            } else if name.contains("coccyx") {
                &mut bones.coccyx
            } else if name.contains("pubis") {
                &mut bones.pubis[side]
            } else if name.contains("ilium") {
                &mut bones.ilium[side]
            } else if name.contains("ischium") {
                &mut bones.ischium[side]
            } else {
                continue;
            };
            target.extend(part.mesh.positions.iter().map(|&p| to_anatomical * (p * scale)));
        }
        for (bone, points) in [
            ("sacrum", &bones.sacrum),
            ("coccyx", &bones.coccyx),
            ("left pubis", &bones.pubis[0]),
            ("right pubis", &bones.pubis[1]),
            ("left ilium", &bones.ilium[0]),
            ("right ilium", &bones.ilium[1]),
            ("left ischium", &bones.ischium[0]),
            ("right ischium", &bones.ischium[1]),
        ] {
            if points.is_empty() {
                return Err(PickError::MissingBone(bone));
            }
        }
        Ok(bones)
    }
}

/// The best point of `points` by `score` (largest), or the named error.
fn best(
    points: impl IntoIterator<Item = DVec3>,
    what: &'static str,
    score: impl Fn(DVec3) -> f64,
) -> Result<DVec3, PickError> {
    points
        .into_iter()
        .max_by(|&a, &b| score(a).total_cmp(&score(b)))
        .ok_or(PickError::NotFound(what))
}

/// Points of `points` within `tolerance` of some point of `others`.
fn near(points: &[DVec3], others: &[DVec3], tolerance: f64) -> Vec<DVec3> {
    let cell = |p: DVec3| (p / tolerance).floor().as_i64vec3().to_array();
    let mut grid: HashMap<[i64; 3], Vec<DVec3>> = HashMap::new();
    for &q in others {
        grid.entry(cell(q)).or_default().push(q);
    }
    points
        .iter()
        .copied()
        .filter(|&p| {
            let c = cell(p);
            (-1..=1).any(|i| {
                (-1..=1).any(|j| {
                    (-1..=1).any(|k| {
                        grid.get(&[c[0] + i, c[1] + j, c[2] + k])
                            .is_some_and(|cell| cell.iter().any(|&q| q.distance(p) < tolerance))
                    })
                })
            })
        })
        .collect()
}

/// The inlet frame of the picking: origin at the obstetric conjugate's
/// midpoint, `ap` along it, `transverse` the anatomical x (mother's right)
/// made orthogonal to it,
/// `normal` = transverse x ap (cranial).
struct InletFrame {
    origin: DVec3,
    transverse: DVec3,
    ap: DVec3,
    normal: DVec3,
}

impl InletFrame {
    /// (transverse, antero-posterior, normal) coordinates.
    fn local(&self, p: DVec3) -> DVec3 {
        let q = p - self.origin;
        DVec3::new(q.dot(self.transverse), q.dot(self.ap), q.dot(self.normal))
    }
}

/// Picks every pelvis landmark (anatomical frame, metres). The steps, in
/// order, are documented in docs/IMPORT.md.
pub fn pick_landmarks(b: &PelvisBones) -> Result<PelvisLandmarks, PickError> {
    // 1. Midline: between the medial faces of the two pubic bones.
    let min_x = |v: &[DVec3]| v.iter().map(|p| p.x).fold(f64::MAX, f64::min);
    let max_x = |v: &[DVec3]| v.iter().map(|p| p.x).fold(f64::MIN, f64::max);
    let midline = 0.5 * (min_x(&b.pubis[1]) + max_x(&b.pubis[0]));
    let pubic: Vec<DVec3> = b
        .pubis
        .iter()
        .flatten()
        .copied()
        .filter(|p| (p.x - midline).abs() < PUBIC_SLAB)
        .collect();

    // 2. Lower inner border of the symphysis: the back of its lowest band.
    let lowest = pubic.iter().map(|p| p.z).fold(f64::MAX, f64::min);
    let symphysis_lower = best(
        pubic.iter().copied().filter(|p| p.z < lowest + EDGE_BAND),
        "lower symphysis border",
        |p| -p.y,
    )?;

    // 3. Obstetric conjugate: the shortest distance from the upper sacrum
    //    (midline) to the symphysis gives the promontory and the upper inner border.
    let top = pubic.iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let sacral: Vec<DVec3> = b
        .sacrum
        .iter()
        .copied()
        .filter(|p| (p.x - midline).abs() < SACRAL_SLAB && p.z > top + PROMONTORY_ABOVE_SYMPHYSIS)
        .collect();
    let (sacral_promontory, symphysis_upper) = sacral
        .iter()
        .flat_map(|&s| pubic.iter().map(move |&q| (s, q)))
        .min_by(|a, b| a.0.distance(a.1).total_cmp(&b.0.distance(b.1)))
        .ok_or(PickError::NotFound("sacral promontory"))?;

    let ap = (symphysis_upper - sacral_promontory).normalize();
    let transverse = (DVec3::X - DVec3::X.dot(ap) * ap).normalize();
    let frame = InletFrame {
        origin: 0.5 * (sacral_promontory + symphysis_upper),
        transverse,
        ap,
        normal: transverse.cross(ap),
    };
    let a_promontory = frame.local(sacral_promontory).y;
    let a_symphysis = frame.local(symphysis_upper).y;

    // 4. Widest inlet transverse: at each millimetre of the conjugate, the
    //    innermost bone on each side within the brim slab; the widest level.
    let hip: Vec<DVec3> = b
        .ilium
        .iter()
        .chain(&b.pubis)
        .chain(&b.ischium)
        .flatten()
        .copied()
        .chain(b.sacrum.iter().copied())
        .collect();
    let mut levels: HashMap<i64, (Option<DVec3>, Option<DVec3>)> = HashMap::new();
    for &p in &hip {
        let l = frame.local(p);
        if l.z < -BRIM_BELOW || l.z > BRIM_ABOVE || l.y < a_promontory || l.y > a_symphysis {
            continue;
        }
        let entry = levels.entry((l.y / MM).floor() as i64).or_default();
        let slot = if l.x > 0.0 { &mut entry.1 } else { &mut entry.0 };
        let inner = |q: &DVec3| frame.local(*q).x.abs();
        if slot.as_ref().is_none_or(|q| l.x.abs() < inner(q)) {
            *slot = Some(p);
        }
    }
    // A wall can miss a vertex in a one-millimetre level: each side takes
    // its innermost point within two levels either way.
    let innermost = |level: i64, side: usize| {
        (level - WALL_WINDOW..=level + WALL_WINDOW)
            .filter_map(|k| levels.get(&k).and_then(|pair| if side == 1 { pair.1 } else { pair.0 }))
            .min_by(|a, b| frame.local(*a).x.abs().total_cmp(&frame.local(*b).x.abs()))
    };
    let mut keys: Vec<i64> = levels.keys().copied().collect();
    keys.sort_unstable();
    let mut widest: Option<(f64, DVec3, DVec3)> = None;
    for level in keys {
        if let (Some(left), Some(right)) = (innermost(level, 0), innermost(level, 1)) {
            let width = frame.local(right).x - frame.local(left).x;
            if widest.is_none_or(|(w, _, _)| width > w) {
                widest = Some((width, left, right));
            }
        }
    }
    let (_, iliopectineal_left, iliopectineal_right) = widest.ok_or(PickError::NotFound("inlet transverse"))?;

    // Steps 5-9 on each side: [sacroiliac, iliopubic, ischiopubic, spine, tuberosity].
    let one_side = |side: usize| -> Result<[DVec3; 5], PickError> {
        let sign = if side == 1 { 1.0 } else { -1.0 };
        let medial = |p: DVec3| -sign * frame.local(p).x;
        // 5. Sacroiliac joint at the brim: the front-top end of the sacrum's
        //    junction with the ilium.
        let joint = near(&b.sacrum, &b.ilium[side], JUNCTION);
        let sacroiliac = best(joint, "sacroiliac joint", |p| frame.local(p).y + frame.local(p).z)?;
        // 6. Iliopubic eminence: the top of the pubis's junction with the ilium.
        let iliopubic = near(&b.pubis[side], &b.ilium[side], JUNCTION);
        let iliopubic = best(iliopubic, "iliopubic eminence", |p| frame.local(p).z)?;
        // 7. Ischiopubic junction: the lowest part of the pubis's junction
        //    with the ischium, its most medial (inner) point.
        let junction = near(&b.pubis[side], &b.ischium[side], JUNCTION);
        let bottom = junction.iter().map(|&p| frame.local(p).z).fold(f64::MAX, f64::min);
        let ischiopubic = best(
            junction.into_iter().filter(|&p| frame.local(p).z < bottom + 6.0 * MM),
            "ischiopubic junction",
            medial,
        )?;
        // 8. Ischial spine: the most medial point of the ischium's back part.
        let spine = best(
            b.ischium[side]
                .iter()
                .copied()
                .filter(|&p| frame.local(p).y < SPINE_MAX_ANTERIOR),
            "ischial spine",
            medial,
        )?;
        // 9. Ischial tuberosity: the inner surface around the ischium's lowest point.
        let lowest = best(b.ischium[side].iter().copied(), "ischial tuberosity", |p| {
            -frame.local(p).z
        })?;
        let tuberosity = best(
            b.ischium[side]
                .iter()
                .copied()
                .filter(|p| p.distance(lowest) < TUBEROSITY_RADIUS),
            "ischial tuberosity",
            medial,
        )?;
        Ok([sacroiliac, iliopubic, ischiopubic, spine, tuberosity])
    };
    let [left, right] = [one_side(0)?, one_side(1)?];

    // 10. Sacral apex: the front of the sacrum's lowest midline band.
    let sacral_midline: Vec<DVec3> = b
        .sacrum
        .iter()
        .copied()
        .filter(|p| (p.x - midline).abs() < PUBIC_SLAB)
        .collect();
    let sacral_bottom = sacral_midline.iter().map(|p| p.z).fold(f64::MAX, f64::min);
    let sacral_apex = best(
        sacral_midline
            .iter()
            .copied()
            .filter(|p| p.z < sacral_bottom + EDGE_BAND),
        "sacral apex",
        |p| p.y,
    )?;
    // 11. Coccyx tip: the point of the coccyx farthest from the sacral apex.
    let coccyx_tip = best(b.coccyx.iter().copied(), "coccyx tip", |p| p.distance(sacral_apex))?;

    // 12. Anterior sacral curve, promontory to apex: in 2 mm steps along the
    //     chord, the midline point standing farthest forward of it.
    let chord = sacral_apex - sacral_promontory;
    let along = chord.normalize();
    let forward = (DVec3::Y - DVec3::Y.dot(along) * along).normalize();
    let mut steps: HashMap<i64, DVec3> = HashMap::new();
    for &p in &sacral_midline {
        let s = (p - sacral_promontory).dot(along);
        if s <= 0.0 || s >= chord.length() {
            continue;
        }
        let slot = steps.entry((s / (2.0 * MM)).floor() as i64).or_insert(p);
        if (p - sacral_promontory).dot(forward) > (*slot - sacral_promontory).dot(forward) {
            *slot = p;
        }
    }
    let mut keys: Vec<i64> = steps.keys().copied().collect();
    keys.sort_unstable();
    let curve: Vec<DVec3> = std::iter::once(sacral_promontory)
        .chain(keys.iter().map(|k| steps[k]))
        .chain(std::iter::once(sacral_apex))
        .collect();
    let mut lengths = vec![0.0];
    for w in curve.windows(2) {
        lengths.push(lengths[lengths.len() - 1] + w[0].distance(w[1]));
    }
    let total = lengths[lengths.len() - 1];
    let at_fraction = |f: f64| {
        let k = (0..curve.len()).min_by(|&a, &b| {
            (lengths[a] - f * total)
                .abs()
                .total_cmp(&(lengths[b] - f * total).abs())
        });
        curve[k.unwrap_or(0)]
    };
    let sacrum_s2_s3 = at_fraction(S2_S3_FRACTION);
    let sacrum_s4_s5 = at_fraction(S4_S5_FRACTION);

    // 13. Lower lateral borders of the sacrum: its most lateral points at
    //     the level of the S4-S5 junction.
    let level = (sacrum_s4_s5 - sacral_promontory).dot(along);
    let band: Vec<DVec3> = b
        .sacrum
        .iter()
        .copied()
        .filter(|p| ((*p - sacral_promontory).dot(along) - level).abs() < BORDER_BAND)
        .collect();
    let sacral_border_left = best(band.iter().copied(), "sacral border", |p| midline - p.x)?;
    let sacral_border_right = best(band.iter().copied(), "sacral border", |p| p.x - midline)?;

    Ok(PelvisLandmarks {
        sacral_promontory,
        symphysis_upper,
        symphysis_lower,
        iliopectineal_left,
        iliopectineal_right,
        sacroiliac_left: left[0],
        sacroiliac_right: right[0],
        iliopubic_eminence_left: left[1],
        iliopubic_eminence_right: right[1],
        sacrum_s2_s3,
        sacrum_s4_s5,
        sacral_apex,
        coccyx_tip,
        ischial_spine_left: left[3],
        ischial_spine_right: right[3],
        ischial_tuberosity_left: left[4],
        ischial_tuberosity_right: right[4],
        sacral_border_left,
        sacral_border_right,
        ischiopubic_left: left[2],
        ischiopubic_right: right[2],
    })
}

/// Writes picked landmarks (anatomical frame, metres) as a landmarks file
/// for a mesh stored in `units` with `axes`: the inverse of what
/// [`super::import_pelvis`] does with them.
pub fn to_landmarks_file(
    landmarks: &PelvisLandmarks,
    mesh: &std::path::Path,
    units: super::Units,
    axes: super::AxesDeclaration,
    description: Option<String>,
) -> Result<super::LandmarksFile, super::ImportError> {
    let from_anatomical = axes.to_anatomical(mesh)?.transpose();
    let scale = 1.0 / units.to_metres();
    Ok(super::LandmarksFile {
        description,
        mesh: mesh.to_path_buf(),
        units,
        axes,
        landmarks: landmarks
            .named()
            .iter()
            .map(|(name, p)| (name.to_string(), (from_anatomical * (*p * scale)).to_array()))
            .collect(),
    })
}
