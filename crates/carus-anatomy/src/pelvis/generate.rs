//! The surface of a generated pelvis: a thick bony shell swept down the
//! birth canal through ring cross-sections, with the landmarks as vertices.
//!
//! The inner (canal) wall is a grid: columns go once round the canal
//! (counter-clockwise seen from above, column 0 at the front midline) and
//! rows go down it from the iliac crest through the key rings of the true
//! pelvis: inlet, plane of greatest dimensions, mid-pelvis, sacral apex,
//! outlet. Each key ring passes through its landmarks; rows between them are
//! Catmull-Rom blends down each column. Above the inlet each column is the
//! iliac blade: a concave profile from the brim out and up to the crest
//! ring. A cell mask cuts out what is not bone (the front of the false
//! pelvis, the pubic arch, the obturator foramina, the sciatic notches
//! between sacrum and ischium, the gap between the posterior iliac spines),
//! the outer bone surface is the wall pushed outwards by a smooth bone
//! thickness, and walls along the mask's edges close the shell.

use glam::{DVec2, DVec3};

use super::diameters::DiameterError;
use super::interpolate::{catmull_rom, SuperRing, HALF_TURN};
use super::layout::{point, Layout};
use super::{PelvisLandmarks, SoftWalls};
use crate::surface::TriSurface;

/// Grid columns per 1/64 of a turn round the canal.
const RESOLUTION: usize = 2;
/// Depths down the wall, in key-ring units (`kappa`): the crest at 0, the
/// brim (inlet) at 2, then the key rings of the true pelvis.
const INLET: usize = 2;
const GREATEST: usize = 3;
const MID: usize = 4;
const APEX: usize = 5;
const OUTLET: usize = 6;
/// Grid rows between consecutive depths 0, 1, ..., 6 (times RESOLUTION).
const ROWS_BETWEEN: [usize; 6] = [3, 3, 5, 5, 5, 5];

/// A ring through control points given on the mother's left side at
/// distances `da` from the front midline, mirrored to the right.
struct ControlRing {
    knots: Vec<f64>,
    points: Vec<DVec3>,
}

impl ControlRing {
    /// `(da, |x|, (y, z))` from the front (da = 0) to the back (da = 32).
    fn new(left: &[(f64, f64, DVec2)]) -> Self {
        let mut pairs: Vec<(f64, DVec3)> = Vec::new();
        for &(da, half_width, sagittal) in left {
            if da <= 0.0 || da >= HALF_TURN {
                let s = if da <= 0.0 { 0.0 } else { -HALF_TURN };
                pairs.push((s, point(0.0, sagittal)));
            } else {
                pairs.push((da, point(-half_width, sagittal)));
                pairs.push((-da, point(half_width, sagittal)));
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        ControlRing { knots: pairs.iter().map(|p| p.0).collect(), points: pairs.iter().map(|p| p.1).collect() }
    }

    fn at(&self, s: f64) -> DVec3 {
        catmull_rom(&self.knots, &self.points, Some(2.0 * HALF_TURN), s)
    }
}

enum Ring {
    Super(SuperRing),
    Control(ControlRing),
}

impl Ring {
    fn at(&self, s: f64) -> DVec3 {
        match self {
            Ring::Super(r) => r.at(s),
            Ring::Control(r) => r.at(s),
        }
    }
}

/// Superellipse exponent of the rings below the inlet (slightly fuller than
/// an ellipse; engineering choice).
const MID_RING_EXPONENT: f64 = 2.2;

/// The mid-pelvis ring through the lower symphysis, the spines and S4-S5;
/// the pelvic floor's attachment follows it from the pubis to the spines.
pub(crate) fn mid_ring(l: &PelvisLandmarks) -> SuperRing {
    SuperRing {
        front: l.symphysis_lower,
        back: l.sacrum_s4_s5,
        left: l.ischial_spine_left,
        right: l.ischial_spine_right,
        exponent: MID_RING_EXPONENT,
    }
}

fn yz(p: DVec3) -> DVec2 {
    DVec2::new(p.y, p.z)
}

/// Half-widths of the iliac crest (widest) and of the anterior superior
/// iliac spines, inner surface, as shares of the inlet transverse T.
/// Engineering values, chosen so that the default pelvis (T = 130 mm)
/// measures about 275 mm between the outer lips of the crests and about
/// 230 mm between the anterior superior iliac spines: within the adult
/// female bony ranges quoted for this work (inter-crest 250-290 mm,
/// inter-ASIS 220-250 mm), below the classical external pelvimetry over the
/// skin (distantia cristarum about 280 mm, distantia spinarum about 250 mm),
/// and close to the Visible Human Female pelvis shipped with Carus, whose
/// crests are about 2.1 T apart (docs/ANATOMY.md, "Iliac wings").
const CREST_HALF_WIDTH: f64 = 0.98;
const ASIS_HALF_WIDTH: f64 = 0.84;

/// The iliac crest, inner surface, from the anterior superior iliac spine
/// (ASIS, 1/64 turn 12) round the side, where it is highest, to the posterior
/// superior iliac spine (PSIS, 27) beside the sacrum; the points in front of
/// the ASIS and behind the PSIS only steer the ring (no bone there).
/// Heights and depths in inlet AP `a`, widths in inlet transverse `t`: the
/// engineering shape of the Visible Human Female crest in this frame (ASIS
/// about 0.2 a in front of the inlet centre and 0.3 a above it, crest highest
/// 0.6 a above the inlet a quarter of `a` behind its centre, PSIS 0.85 a
/// behind the centre and 0.3 a up; docs/ANATOMY.md, "Iliac wings").
fn crest_ring(a: f64, t: f64) -> ControlRing {
    ControlRing::new(&[
        (0.0, 0.0, DVec2::new(0.5 * a, 0.2 * a)),
        (12.0, ASIS_HALF_WIDTH * t, DVec2::new(0.2 * a, 0.3 * a)),
        (14.0, 0.9 * t, DVec2::new(0.03 * a, 0.5 * a)),
        (17.0, 0.95 * t, DVec2::new(-0.25 * a, 0.62 * a)),
        (20.0, CREST_HALF_WIDTH * t, DVec2::new(-0.45 * a, 0.58 * a)),
        (23.0, 0.8 * t, DVec2::new(-0.68 * a, 0.52 * a)),
        (27.0, 0.42 * t, DVec2::new(-0.85 * a, 0.38 * a)),
        (32.0, 0.0, DVec2::new(-0.85 * a, 0.25 * a)),
    ])
}

/// How the blade of the iliac fossa leaves the brim (share of the brim-to-
/// crest step taken outwards, and upwards, by the middle control point of
/// the profile): it runs out nearly flat from the arcuate line and turns up
/// to meet the crest steeply, so the fossa is concave inside and the blade
/// convex outside. Engineering values: at 60 % of its height the Visible
/// Human Female fossa has gone 85 % of the way out to the crest; these
/// shares give 88 %.
const FOSSA_FLARE: f64 = 0.75;
const FOSSA_LIFT: f64 = 0.25;

/// A point of the iliac blade's inner surface: a quadratic Bezier from the
/// brim `brim` (u = 0) to the crest `crest` (u = 1).
fn fossa(brim: DVec3, crest: DVec3, u: f64) -> DVec3 {
    let step = crest - brim;
    let middle = brim + FOSSA_FLARE * DVec3::new(step.x, step.y, 0.0) + FOSSA_LIFT * DVec3::new(0.0, 0.0, step.z);
    (1.0 - u) * (1.0 - u) * brim + 2.0 * u * (1.0 - u) * middle + u * u * crest
}

/// The key rings of a pelvis laid out by [`super::layout::layout`]: the iliac
/// crest, then the rings the canal wall is blended through from the brim
/// down (their index is their key-ring depth `kappa`). The first of those,
/// at kappa 1, is no surface of its own: it sets the slope of the canal wall
/// just below the brim (the Catmull-Rom tangent at the inlet is half the
/// step from it to the plane of greatest dimensions). Above the brim the
/// wall is the iliac blade of [`fossa`].
fn key_rings(layout: &Layout) -> (ControlRing, [Ring; 6]) {
    let l = &layout.landmarks;
    let a = (l.symphysis_upper - l.sacral_promontory).length();
    let t = (l.iliopectineal_right - l.iliopectineal_left).length();
    let y_t = layout.inlet_transverse_y;
    let ot = (l.ischial_tuberosity_right - l.ischial_tuberosity_left).length();
    let i = (l.ischial_spine_right - l.ischial_spine_left).length();
    let tuberosity = layout.tuberosity;
    let forward = DVec2::new(1.0, 0.0);
    let symmetric = |front: DVec2, back: DVec2, lateral: DVec2, half_width: f64, exponent: f64| SuperRing {
        front: point(0.0, front),
        back: point(0.0, back),
        left: point(-half_width, lateral),
        right: point(half_width, lateral),
        exponent,
    };
    // The canal wall leaves the brim upwards and outwards towards this ring
    // (engineering proportions).
    let brim_slope = symmetric(
        DVec2::new(0.65 * a, 0.25 * a),
        DVec2::new(-0.62 * a, 0.2 * a),
        DVec2::new(y_t + 0.05 * a, 0.22 * a),
        0.72 * t,
        2.3,
    );
    let inlet = symmetric(yz(l.symphysis_upper), yz(l.sacral_promontory), DVec2::new(y_t, 0.0), 0.5 * t, layout.inlet_exponent);
    let greatest = symmetric(
        yz(l.symphysis_middle()),
        yz(l.sacrum_s2_s3),
        layout.greatest_lateral,
        layout.greatest_half_width,
        MID_RING_EXPONENT,
    );
    let mid = mid_ring(l);
    let junction = yz(l.ischiopubic_left);
    let border = DVec3::new(-layout.lower_lateral_angle.x, layout.lower_lateral_angle.y, layout.lower_lateral_angle.z);
    let ischium = 0.5 * (layout.spine + tuberosity);
    let ischium_half_width = 0.25 * (i + ot) + 0.004;
    let apex = ControlRing::new(&[
        (0.0, 0.0, junction + 0.02 * forward),
        (8.0, -l.ischiopubic_left.x, junction),
        (16.0, ischium_half_width, ischium),
        (22.0, 0.5 * (ischium_half_width - border.x), 0.5 * (ischium + yz(border))),
        (28.0, -border.x, yz(border)),
        (32.0, 0.0, yz(l.sacral_apex)),
    ]);
    let coccyx = yz(l.coccyx_tip);
    let outlet = ControlRing::new(&[
        (0.0, 0.0, tuberosity + 0.3 * ot * forward),
        (8.0, 0.35 * ot, tuberosity + 0.21 * ot * forward),
        (16.0, 0.5 * ot, tuberosity),
        (24.0, 0.3 * ot, 0.5 * (tuberosity + coccyx)),
        (29.0, 0.008, coccyx + 0.004 * (yz(l.sacral_apex) - coccyx).normalize()),
        (32.0, 0.0, coccyx),
    ]);
    let canal = [
        Ring::Super(brim_slope),
        Ring::Super(inlet),
        Ring::Super(greatest),
        Ring::Super(mid),
        Ring::Control(apex),
        Ring::Control(outlet),
    ];
    (crest_ring(a, t), canal)
}

/// Where each landmark of the canal wall sits on the grid: (signed turn
/// position, key ring). The sacral borders lie on the outer surface
/// ([`slide_sacral_borders`]).
fn landmark_sites(l: &PelvisLandmarks) -> [(f64, usize, DVec3); 19] {
    [
        (0.0, INLET, l.symphysis_upper),
        (32.0, INLET, l.sacral_promontory),
        (16.0, INLET, l.iliopectineal_left),
        (-16.0, INLET, l.iliopectineal_right),
        (8.0, INLET, l.iliopubic_eminence_left),
        (-8.0, INLET, l.iliopubic_eminence_right),
        (24.0, INLET, l.sacroiliac_left),
        (-24.0, INLET, l.sacroiliac_right),
        (32.0, GREATEST, l.sacrum_s2_s3),
        (0.0, MID, l.symphysis_lower),
        (32.0, MID, l.sacrum_s4_s5),
        (16.0, MID, l.ischial_spine_left),
        (-16.0, MID, l.ischial_spine_right),
        (8.0, APEX, l.ischiopubic_left),
        (-8.0, APEX, l.ischiopubic_right),
        (32.0, APEX, l.sacral_apex),
        (32.0, OUTLET, l.coccyx_tip),
        (16.0, OUTLET, l.ischial_tuberosity_left),
        (-16.0, OUTLET, l.ischial_tuberosity_right),
    ]
}

/// The front of the false pelvis, above the brim in front of the iliac
/// wings' anterior borders: open bone, closed in the body by the lower
/// abdominal wall. Their border runs from the crest down to the pubis: the
/// anterior superior iliac spine (da 11.5) juts forward over a notch, the
/// anterior inferior spine bulges below it, and the border reaches the
/// superior pubic ramus beside the iliopubic eminence (da 5).
fn front_of_false_pelvis(da: f64, kappa: f64) -> bool {
    let inlet = INLET as f64;
    let u = (inlet - kappa) / inlet;
    let border = [(0.0, 5.0), (0.35, 8.5), (0.6, 11.0), (0.85, 13.0), (1.0, 11.5)];
    let k = border.iter().rposition(|&(at, _)| at <= u).unwrap_or(0).min(border.len() - 2);
    let ((u0, f0), (u1, f1)) = (border[k], border[k + 1]);
    let front = f0 + (f1 - f0) * ((u - u0) / (u1 - u0)).clamp(0.0, 1.0);
    kappa < inlet && da <= front
}

/// How far round from the front midline the pubic arch is open at depth
/// `kappa`: from the lower symphysis border (mid ring, front) through the
/// ischiopubic junctions (apex ring, da 8) to the tuberosities (outlet
/// ring, da 16).
fn pubic_arch(kappa: f64) -> f64 {
    let mid = MID as f64;
    if kappa <= mid {
        0.0
    } else {
        8.0 * (kappa - mid)
    }
}

/// The obturator foramen, kept two units clear of the arch: an oval from
/// just below the superior pubic ramus to just above the ischiopubic ramus
/// (kappa 2.85-4.15, da 6-13), taller than wide as in female pelves.
fn in_obturator_foramen(da: f64, kappa: f64) -> bool {
    let (u, v) = ((da - 9.5) / 3.5, (kappa - 3.5) / 0.65);
    u * u + v * v < 1.0 && da - pubic_arch(kappa) > 2.0
}

/// Which cells are bone, by distance `da` from the front midline and depth
/// `kappa` in key-ring units (engineering shapes of the bony outline).
fn is_bone(da: f64, kappa: f64) -> bool {
    let inlet = INLET as f64;
    if kappa < inlet {
        // Iliac wings, back to the posterior superior iliac spine (da 27).
        return !front_of_false_pelvis(da, kappa) && da < 27.0;
    }
    let mid = MID as f64;
    let apex = APEX as f64;
    if da < pubic_arch(kappa) {
        return false;
    }
    // Sciatic notches between the ischium and the sacrum, with the ischial
    // spine a tooth reaching back to da 16 at the mid ring.
    if kappa > inlet + 0.5 {
        let sacrum_edge = if kappa <= apex { 24.0 + 4.0 * (kappa - inlet - 0.5) / 2.5 } else { 28.0 + 2.0 * (kappa - apex) };
        let ischium_back = if (kappa - mid).abs() < 0.2 {
            16.0
        } else if kappa < mid {
            22.0 - 8.0 * ((kappa - inlet - 0.5) / 1.2).min(1.0)
        } else {
            14.5 + 5.5 * (kappa - mid - 0.2) / 1.8
        };
        if da > ischium_back && da < sacrum_edge {
            return false;
        }
    }
    !in_obturator_foramen(da, kappa)
}

/// The soft wall that closes a cell the bone leaves open, if one does.
fn closure(da: f64, kappa: f64) -> Option<SoftWall> {
    if front_of_false_pelvis(da, kappa) {
        Some(SoftWall::AbdominalWall)
    } else if kappa >= INLET as f64 && in_obturator_foramen(da, kappa) {
        Some(SoftWall::ObturatorMembrane)
    } else {
        None
    }
}

/// The soft tissues [`SoftWalls`] holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SoftWall {
    AbdominalWall,
    ObturatorMembrane,
}

/// The open cells that soft tissue closes, on the bone's own grid (so they
/// meet the bone edge to edge), facing the canal as its inner wall does.
/// The obturator membranes lie on the canal wall (the obturator internus
/// lines it); the abdominal wall rises from the bone's outer surface, the
/// front of the pubic crests where the recti insert, so a head or shoulder
/// may ride over the symphysis, inside the uterus, but not pass down in
/// front of the pubis.
fn soft_walls(inner: &[DVec3], outer: &[DVec3], bone: &[bool], kappa: &[f64], columns: usize, da: impl Fn(f64) -> f64) -> SoftWalls {
    let rows = kappa.len();
    let index = |r: usize, i: usize| (r * columns + i % columns) as u32;
    let mut triangles = [Vec::new(), Vec::new()];
    // The abdominal wall's columns in the crest's row, to carry on up.
    let mut at_crest = Vec::new();
    for r in 0..rows - 1 {
        for i in 0..columns {
            if bone[r * columns + i] {
                continue;
            }
            let Some(wall) = closure(da(i as f64 + 0.5), 0.5 * (kappa[r] + kappa[r + 1])) else {
                continue;
            };
            let quad = [index(r, i), index(r, i + 1), index(r + 1, i + 1), index(r + 1, i)];
            let on = if wall == SoftWall::AbdominalWall { outer } else { inner };
            triangles[wall as usize].extend(split_quad(on, quad));
            if r == 0 && wall == SoftWall::AbdominalWall {
                at_crest.push(i);
            }
        }
    }
    // Above the crest the wall goes on up, over the whole fetus: from the
    // crest's row to ABDOMINAL_WALL_RISE_M above it.
    let n = outer.len() as u32;
    let mut with_rise = outer.to_vec();
    with_rise.extend((0..columns).map(|i| outer[i] + ABDOMINAL_WALL_RISE_M * DVec3::Z));
    let above = |i: usize| n + (i % columns) as u32;
    let [mut abdominal, obturator] = triangles;
    for i in at_crest {
        abdominal.extend(split_quad(&with_rise, [above(i), above(i + 1), index(0, i + 1), index(0, i)]));
    }
    SoftWalls { abdominal_wall: compact(&with_rise, abdominal), obturator_membranes: compact(inner, obturator) }
}

/// How far the abdominal wall rises above the iliac crests, m, along the
/// inlet's normal: past any fetal part (engineering choice: the wall goes
/// on to the ribs; only that no shoulder passes over it matters here).
const ABDOMINAL_WALL_RISE_M: f64 = 0.25;

/// The surface of `triangles` over the grid points `at`, keeping only the
/// points they use.
fn compact(at: &[DVec3], mut triangles: Vec<[u32; 3]>) -> TriSurface {
    let mut remap = vec![u32::MAX; at.len()];
    let mut vertices = Vec::new();
    for t in &mut triangles {
        for v in t.iter_mut() {
            if remap[*v as usize] == u32::MAX {
                remap[*v as usize] = vertices.len() as u32;
                vertices.push(at[*v as usize]);
            }
            *v = remap[*v as usize];
        }
    }
    TriSurface::new(vertices, triangles)
}

/// Extra thickness of the iliac crest over the blade, m (engineering value:
/// the crest is a rim with inner and outer lips, thicker than the fossa).
const CREST_RIM: f64 = 0.004;

/// Extra thickness of the body of the ilium, where the blade meets the brim
/// at the side (the bone above and behind the acetabulum), m (engineering
/// value).
const ILIAC_BODY: f64 = 0.012;

/// Smoothstep from 0 at `lo` to 1 at `hi`.
fn smooth(lo: f64, hi: f64, x: f64) -> f64 {
    let s = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// Bone thickness (inner to outer surface), m: engineering values, thicker
/// at the sacrum's base and the tuberosities, thin in the iliac blades with
/// a thicker rim along the crest.
fn thickness(da: f64, kappa: f64) -> f64 {
    let blade = 0.006 + 0.004 * smooth(1.0, 2.0, kappa) + CREST_RIM * (1.0 - smooth(0.0, 0.4, kappa));
    let body = ILIAC_BODY * smooth(0.8, 1.9, kappa) * (1.0 - smooth(2.1, 2.8, kappa)) * smooth(8.0, 11.0, da) * (1.0 - smooth(18.0, 21.0, da));
    let sacrum = 0.03 * smooth(20.0, 24.0, da) * smooth(1.5, 2.2, kappa) * (1.0 - smooth(2.5, 6.0, kappa));
    let tuberosity = 0.008 * smooth(4.5, 5.5, kappa) * (1.0 - smooth(20.0, 24.0, da)) * smooth(10.0, 14.0, da);
    blade + body + sacrum + tuberosity
}

/// Passes of [`relax_outer`] (numerical: twice the 20 the default pelvis
/// needs to be free of crossings, more than the contracted inlet's 25; 47
/// random clinical diameter sets all clean: docs/ANATOMY.md,
/// "Self-intersections").
const OUTER_RELAX_PASSES: usize = 40;
/// The relaxed outer wall stays at least this share of the bone's
/// thickness from the canal wall (numerical).
const OUTER_THICKNESS_KEPT: f64 = 0.7;

/// Relaxes the outer wall towards its neighbours' average, pass by pass.
/// Pushed straight out by the bone's thickness, the outer wall folds
/// through itself wherever the canal wall bends towards it more tightly
/// than that (the ridge of the brim, between the iliac fossa and the
/// canal); averaging unties such folds as it smooths an offset curve's
/// loops. The canal wall does not move, the sacrum's plate (whose dorsal
/// border carries the sacral landmarks) moves as little as it is a plate,
/// and no vertex comes nearer the canal wall than `OUTER_THICKNESS_KEPT`
/// of its thickness.
fn relax_outer(inner: &[DVec3], outer: &mut [DVec3], depth: &[f64], plate: &[f64], rows: usize, columns: usize) {
    for _ in 0..OUTER_RELAX_PASSES {
        let before = outer.to_vec();
        let at = |r: usize, i: isize| before[r * columns + i.rem_euclid(columns as isize) as usize];
        for r in 1..rows - 1 {
            for i in 0..columns {
                let (ii, k) = (i as isize, r * columns + i);
                let average = (at(r - 1, ii) + at(r + 1, ii) + at(r, ii - 1) + at(r, ii + 1)) / 4.0;
                let moved = before[k].lerp(average, 0.5 * (1.0 - plate[k]));
                // Not nearer the canal wall than the kept share of the thickness.
                let out = (before[k] - inner[k]).normalize_or_zero();
                let short = OUTER_THICKNESS_KEPT * depth[k] - (moved - inner[k]).dot(out);
                outer[k] = if short > 0.0 { moved + short * out } else { moved };
            }
        }
    }
}

/// Builds the closed, outward-facing bone surface of a laid-out pelvis and
/// places the sacral borders on it so the outlet oblique is
/// `outlet_oblique_mm`; returns the surface and the final landmarks.
pub(crate) fn canal_surface(layout: &Layout, outlet_oblique_mm: f64) -> Result<(TriSurface, PelvisLandmarks, SoftWalls), DiameterError> {
    let (crest, canal) = key_rings(layout);
    let columns = 2 * HALF_TURN as usize * RESOLUTION;
    let mut kappa = Vec::new();
    for (k, &between) in ROWS_BETWEEN.iter().enumerate() {
        let n = between * RESOLUTION;
        kappa.extend((0..n).map(|s| k as f64 + s as f64 / n as f64));
    }
    kappa.push(OUTLET as f64);
    let rows = kappa.len();
    let key_row = |k: usize| kappa.iter().position(|&x| x == k as f64).expect("key rings are rows");
    let signed = |i: usize| {
        let s = i as f64 / RESOLUTION as f64;
        if s <= HALF_TURN {
            s
        } else {
            s - 2.0 * HALF_TURN
        }
    };
    let column = |s: f64| ((s * RESOLUTION as f64).round() as isize).rem_euclid(columns as isize) as usize;

    // Inner wall: below the brim the canal's key rings round each column,
    // blended down it; above it the iliac blade from the brim to the crest.
    let key_knots: Vec<f64> = (0..canal.len()).map(|k| (k + 1) as f64).collect();
    let brim = INLET as f64;
    let mut inner = vec![DVec3::ZERO; rows * columns];
    for i in 0..columns {
        let keys: Vec<DVec3> = canal.iter().map(|r| r.at(signed(i))).collect();
        let top = crest.at(signed(i));
        for (r, &k) in kappa.iter().enumerate() {
            inner[r * columns + i] =
                if k < brim { fossa(keys[INLET - 1], top, (brim - k) / brim) } else { catmull_rom(&key_knots, &keys, None, k) };
        }
    }
    for (s, ring, p) in landmark_sites(&layout.landmarks) {
        inner[key_row(ring) * columns + column(s)] = p;
    }

    // Bone cells, with diagonal-only contacts filled so every vertex is manifold.
    let da = |i: f64| {
        let s = (i / RESOLUTION as f64).rem_euclid(2.0 * HALF_TURN);
        s.min(2.0 * HALF_TURN - s)
    };
    let mut bone = vec![false; (rows - 1) * columns];
    for r in 0..rows - 1 {
        for i in 0..columns {
            bone[r * columns + i] = is_bone(da(i as f64 + 0.5), 0.5 * (kappa[r] + kappa[r + 1]));
        }
    }
    fill_pinches(&mut bone, rows - 1, columns);

    // Outer surface: the wall pushed away from the canal by the bone thickness.
    let behind = point(0.0, layout.sacrum_behind);
    let at = |i: isize, r: usize| inner[r * columns + i.rem_euclid(columns as isize) as usize];
    let mut outer = vec![DVec3::ZERO; rows * columns];
    let mut depth = vec![0.0; rows * columns];
    let mut plate = vec![0.0; rows * columns];
    for (r, &kappa) in kappa.iter().enumerate().take(rows) {
        for i in 0..columns {
            let (ii, k) = (i as isize, r * columns + i);
            let around = at(ii + 1, r) - at(ii - 1, r);
            let down = at(ii, (r + 1).min(rows - 1)) - at(ii, r.saturating_sub(1));
            let normal = down.cross(around).normalize_or_zero();
            // The sacrum and coccyx are a plate: their dorsal surface stands
            // straight behind the ventral one (square to the sacral chord).
            plate[k] = smooth(20.0, 24.0, da(i as f64)) * smooth(2.0, 2.6, kappa);
            let away = normal.lerp(behind, plate[k]).normalize_or_zero();
            depth[k] = thickness(da(i as f64), kappa);
            outer[k] = inner[k] + depth[k] * away;
        }
    }
    relax_outer(&inner, &mut outer, &depth, &plate, rows, columns);
    let landmark_vertices: Vec<usize> =
        landmark_sites(&layout.landmarks).iter().map(|&(s, ring, _)| key_row(ring) * columns + column(s)).collect();
    let (inner, mut outer) = cut_corners(&inner, &outer, &bone, rows, columns, &landmark_vertices);
    let grid = Grid { rows, columns, bone: &bone };
    let rows_along = key_row(INLET) + SACRAL_BORDER_TOP * RESOLUTION..=rows - 2;
    let landmarks = slide_sacral_borders(&layout.landmarks, &mut outer, &grid, rows_along, outlet_oblique_mm)?;
    let closures = soft_walls(&inner, &outer, &bone, &kappa, columns, da);
    Ok((assemble(&inner, &outer, &bone, rows, columns), landmarks, closures))
}

/// First grid row below the inlet where the sacrum stands free of the ilium
/// (the top of the greater sciatic notch, kappa 2.6 in [`is_bone`]), per RESOLUTION.
const SACRAL_BORDER_TOP: usize = 3;

/// The cell mask with its size.
struct Grid<'a> {
    rows: usize,
    columns: usize,
    bone: &'a [bool],
}

/// The sacral end of the sacrotuberous ligament. The ligament's attachment
/// is broad: from the posterior superior iliac spine and the posterior
/// sacroiliac ligaments down the lateral border of the sacrum to the upper
/// coccyx (Gray's Anatomy, the sacrotuberous ligament). The generated
/// sacrum's lateral border is the outer (dorsal) corner of its side wall,
/// facing the sciatic notch; the `sacral_border` landmarks slide along it,
/// from the upper coccyx (rows `rows_along`, bottom first) up to the level of
/// S2-S3, to where the outlet oblique (ligament midpoint to the opposite
/// ischiopubic junction) is exact. The nearest vertex of that border is moved
/// onto the point (less than half a cell), so the landmark is a vertex of the
/// outer surface.
fn slide_sacral_borders(
    l: &PelvisLandmarks,
    outer: &mut [DVec3],
    grid: &Grid,
    rows_along: std::ops::RangeInclusive<usize>,
    outlet_oblique_mm: f64,
) -> Result<PelvisLandmarks, DiameterError> {
    let columns = grid.columns;
    let back = columns / 2;
    // Left side (s > 0): the lateral vertex of the run of bone cells from the
    // back midline, in the cell row below each vertex row, bottom first.
    let mut border: Vec<usize> = rows_along
        .filter(|&r| r < grid.rows - 1)
        .map(|r| {
            let mut i = back;
            while i > 1 && grid.bone[r * columns + i - 1] {
                i -= 1;
            }
            r * columns + i
        })
        .collect();
    border.reverse();
    // Oblique for a left border point p: ligament midpoint to the right junction.
    let tuberosity = l.ischial_tuberosity_left;
    let junction = l.ischiopubic_right;
    let target = outlet_oblique_mm * 1e-3;
    let offset = |p: DVec3| 0.5 * (p + tuberosity) - junction;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut found = None;
    for k in 0..border.len().saturating_sub(1) {
        let (a, b) = (outer[border[k]], outer[border[k + 1]]);
        // |A + s B| along the segment, s in [0, 1].
        let (big_a, big_b) = (offset(a), 0.5 * (b - a));
        let s_min = if big_b.length_squared() > 0.0 {
            (-big_a.dot(big_b) / big_b.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let seg_lo = (big_a + s_min * big_b).length();
        let seg_hi = big_a.length().max((big_a + big_b).length());
        lo = lo.min(seg_lo);
        hi = hi.max(seg_hi);
        if found.is_none() && (seg_lo..=seg_hi).contains(&target) {
            // Roots of |B|^2 s^2 + 2 A.B s + |A|^2 - target^2 = 0 in [0, 1], lower first.
            let (qa, qb, qc) = (big_b.length_squared(), 2.0 * big_a.dot(big_b), big_a.length_squared() - target * target);
            let s = if qa > 0.0 {
                let root = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
                let (r1, r2) = ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa));
                if (0.0..=1.0).contains(&r1) { r1 } else { r2.clamp(0.0, 1.0) }
            } else {
                0.0
            };
            let vertex = if s < 0.5 { border[k] } else { border[k + 1] };
            found = Some((vertex, a + s * (b - a)));
        }
    }
    let Some((vertex, left)) = found else {
        return Err(DiameterError::OutOfReach {
            key: "outlet_oblique_mm",
            value: outlet_oblique_mm,
            reason: "the sacrotuberous ligament's sacral end would have to leave the sacral border (upper coccyx to the top of the greater sciatic notch)",
            min: lo * 1e3,
            max: hi * 1e3,
        });
    };
    let right = DVec3::new(-left.x, left.y, left.z);
    let (r, i) = (vertex / columns, vertex % columns);
    outer[vertex] = left;
    outer[r * columns + (columns - i) % columns] = right;
    Ok(PelvisLandmarks { sacral_border_left: left, sacral_border_right: right, ..*l })
}

/// How far (in grid cells) a staircase corner of the mask moves along the
/// wall towards the diagonal, turning steps into chamfers.
const CORNER_CUT: f64 = 0.35;

/// Smooths the mask's staircase edges: a vertex with one bone cell of its
/// four moves towards that cell, one with three moves towards the missing
/// one, both along the wall (bilinear in the grid), landmarks excepted.
fn cut_corners(
    inner: &[DVec3],
    outer: &[DVec3],
    bone: &[bool],
    rows: usize,
    columns: usize,
    fixed: &[usize],
) -> (Vec<DVec3>, Vec<DVec3>) {
    let cell = |r: isize, i: isize| {
        r >= 0 && (r as usize) < rows - 1 && bone[r as usize * columns + i.rem_euclid(columns as isize) as usize]
    };
    let sample = |grid: &[DVec3], r: f64, i: f64| {
        let (r0, i0) = (r.floor().clamp(0.0, (rows - 2) as f64), i.floor());
        let (fr, fi) = (r - r0, i - i0);
        let at = |dr: usize, di: isize| {
            grid[(r0 as usize + dr) * columns + (i0 as isize + di).rem_euclid(columns as isize) as usize]
        };
        (at(0, 0) * (1.0 - fi) + at(0, 1) * fi) * (1.0 - fr) + (at(1, 0) * (1.0 - fi) + at(1, 1) * fi) * fr
    };
    let (mut new_inner, mut new_outer) = (inner.to_vec(), outer.to_vec());
    for r in 1..rows - 1 {
        for i in 0..columns {
            if fixed.contains(&(r * columns + i)) {
                continue;
            }
            let (ri, ii) = (r as isize, i as isize);
            // The four cells round vertex (r, i), with their offsets from it.
            let around = [(-1, -1), (-1, 0), (0, -1), (0, 0)].map(|(dr, di)| (cell(ri + dr, ii + di), dr, di));
            let count = around.iter().filter(|c| c.0).count();
            let odd_one = match count {
                1 => around.iter().find(|c| c.0),
                3 => around.iter().find(|c| !c.0),
                _ => None,
            };
            if let Some(&(_, dr, di)) = odd_one {
                // Towards the odd cell's centre, which sits at +-0.5 in each direction.
                let (sr, si) = (if dr < 0 { -1.0 } else { 1.0 }, if di < 0 { -1.0 } else { 1.0 });
                let (rr, ic) = (r as f64 + CORNER_CUT * sr, i as f64 + CORNER_CUT * si);
                new_inner[r * columns + i] = sample(inner, rr, ic);
                new_outer[r * columns + i] = sample(outer, rr, ic);
            }
        }
    }
    (new_inner, new_outer)
}

/// Makes bone any void cell that sits between two bone cells touching only
/// at a corner (such a vertex would pinch the surface).
fn fill_pinches(bone: &mut [bool], cell_rows: usize, columns: usize) {
    let cell = |bone: &[bool], r: usize, i: usize| bone[r * columns + i % columns];
    loop {
        let mut changed = false;
        for r in 0..cell_rows.saturating_sub(1) {
            for i in 0..columns {
                let (a, b) = (cell(bone, r, i), cell(bone, r, i + 1));
                let (c, d) = (cell(bone, r + 1, i), cell(bone, r + 1, i + 1));
                if a && d && !b && !c {
                    bone[r * columns + (i + 1) % columns] = true;
                    changed = true;
                } else if b && c && !a && !d {
                    bone[r * columns + i] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
}

/// The two triangles of the quad `a b c d` (counter-clockwise as seen
/// from the side its normal points to) along the diagonal whose triangles
/// both face the quad's way (the cross product of its diagonals). Where
/// the mask's corner cuts leave a quad bent over one diagonal, splitting
/// along the other would turn a triangle round, and a canal point beside
/// it would read as inside the bone.
fn split_quad(at: &[DVec3], [a, b, c, d]: [u32; 4]) -> [[u32; 3]; 2] {
    let p = |k: u32| at[k as usize];
    let facing = (p(c) - p(a)).cross(p(d) - p(b));
    let agreement = |t: [u32; 3]| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).normalize_or_zero().dot(facing);
    let along_ac = [[a, b, c], [a, c, d]];
    let along_bd = [[a, b, d], [b, c, d]];
    let worst = |pair: [[u32; 3]; 2]| agreement(pair[0]).min(agreement(pair[1]));
    if worst(along_bd) > worst(along_ac) {
        along_bd
    } else {
        along_ac
    }
}

/// Triangulates the bone cells: inner wall facing the canal, outer wall
/// facing away, and side walls along every edge between bone and void.
fn assemble(inner: &[DVec3], outer: &[DVec3], bone: &[bool], rows: usize, columns: usize) -> TriSurface {
    let n = rows * columns;
    let index = |r: usize, i: usize| (r * columns + i % columns) as u32;
    let is_bone = |r: isize, i: usize| r >= 0 && (r as usize) < rows - 1 && bone[r as usize * columns + i % columns];
    let mut triangles = Vec::new();
    for r in 0..rows - 1 {
        for i in 0..columns {
            if !bone[r * columns + i] {
                continue;
            }
            let (a, b, c, d) = (index(r, i), index(r, i + 1), index(r + 1, i + 1), index(r + 1, i));
            let off = n as u32;
            let [t1, t2] = split_quad(inner, [a, b, c, d]);
            triangles.push(t1);
            triangles.push(t2);
            let [t1, t2] = split_quad(outer, [a, b, c, d]);
            triangles.push([t1[0] + off, t1[2] + off, t1[1] + off]);
            triangles.push([t2[0] + off, t2[2] + off, t2[1] + off]);
            let ri = r as isize;
            let edges = [
                (a, b, is_bone(ri - 1, i)),
                (b, c, is_bone(ri, i + 1)),
                (c, d, is_bone(ri + 1, i)),
                (d, a, is_bone(ri, i + columns - 1)),
            ];
            for (p, q, neighbour) in edges {
                if !neighbour {
                    triangles.push([q, p, p + off]);
                    triangles.push([q, p + off, q + off]);
                }
            }
        }
    }
    let points: Vec<DVec3> = inner.iter().chain(outer).copied().collect();
    compact(&points, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pelvis::layout::layout;
    use crate::pelvis::PelvisDiameters;

    /// A quad bent over its a-c diagonal (b pushed past it, as a corner cut
    /// can leave one) is split along b-d, where both triangles face the
    /// quad's way; a flat quad keeps the a-c split.
    #[test]
    fn a_bent_quad_is_split_where_neither_triangle_turns_round() {
        let normal = |at: &[DVec3], t: [u32; 3]| {
            let p = |k: u32| at[k as usize];
            (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]))
        };
        let flat = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        assert_eq!(split_quad(&flat, [0, 1, 2, 3]), [[0, 1, 2], [0, 2, 3]]);
        // b pulled across the a-c diagonal: the a-b-c triangle would face -z.
        let bent = [DVec3::ZERO, DVec3::new(0.3, 0.7, 0.0), DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        assert!(normal(&bent, [0, 1, 2]).z < 0.0);
        let split = split_quad(&bent, [0, 1, 2, 3]);
        assert_eq!(split, [[0, 1, 3], [1, 2, 3]]);
        assert!(split.iter().all(|&t| normal(&bent, t).z > 0.0));
    }

    /// Every column of the iliac blade, from the anterior to the posterior
    /// superior iliac spine, bows out and down from the brim-to-crest chord:
    /// the fossa is concave inside, the blade convex outside.
    #[test]
    fn the_iliac_fossa_is_concave_inside() {
        let layout = layout(&PelvisDiameters::default()).unwrap();
        let (crest, canal) = key_rings(&layout);
        for da in 12..=27 {
            let s = da as f64;
            let (brim, top) = (canal[INLET - 1].at(s), crest.at(s));
            let (middle, chord) = (fossa(brim, top, 0.5), 0.5 * (brim + top));
            assert!(middle.z < chord.z - 0.002, "{da}: {middle} against {chord}");
            assert!(middle.truncate().length() > chord.truncate().length() + 0.002, "{da}: {middle} against {chord}");
        }
    }
}
