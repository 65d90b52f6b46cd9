//! Quantities derived at every sample (CARDINAL_MOVEMENTS.md, "Quantities
//! recorded at every output sample"), as a structure of arrays.
//!
//! The series is an output product: its fields carry the units of the
//! report (mm, degrees) in their names, as CONVENTIONS.md asks of JSON.
//! Geometry is evaluated in SI and converted once, here.

use crate::canal::BirthCanal;
use crate::history::{PoseHistory, PoseSample};
use carus_anatomy::axis::AxisFrame;
use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

const MM_PER_M: f64 = 1000.0;

/// Below this magnitude (N) the expulsion force has no usable direction,
/// so the trunk axis is carried over from a neighbouring sample.
const FORCE_DIRECTION_MIN_N: f64 = 1e-6;

/// Per-sample series, one entry per sample of the history.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub time_s: Vec<f64>,
    /// Sigma of the head's leading point (the skull point furthest along
    /// the canal tangent at the head centre) minus sigma of the
    /// ischial-spine plane: clinical station, positive below the spines.
    pub station_mm: Vec<f64>,
    /// Occiput position: 0 = OA, +90 = ROT, -90 = LOT, +-180 = OP;
    /// unwrapped, so it runs on continuously past +-180.
    pub theta_deg: Vec<f64>,
    /// Attitude: positive in flexion (chin towards chest).
    pub phi_deg: Vec<f64>,
    /// Tilt of the occiput direction -o out of the canal cross-section,
    /// positive when the occiput points down the canal. Theta is the
    /// projection of -o onto the cross-section, so it loses its meaning as
    /// this nears +-90 ([`THETA_ILL_CONDITIONED_TILT_DEG`]).
    #[serde(default)]
    pub occiput_tilt_deg: Vec<f64>,
    /// The head's turn about the canal axis on theta's scale, read so that
    /// it stays well conditioned whatever the tilt (`head_twist_deg`);
    /// equals theta for an untilted head. Unwrapped.
    #[serde(default)]
    pub head_twist_deg: Vec<f64>,
    /// Sigma of the head centre (arc length from the inlet centre).
    pub head_sigma_mm: Vec<f64>,
    /// Depth of the left parietal eminence (head centre + BPD/2 along b)
    /// below the inlet plane; negative above it.
    pub left_parietal_below_inlet_mm: Vec<f64>,
    /// Depth of the right parietal eminence (head centre - BPD/2 along b).
    pub right_parietal_below_inlet_mm: Vec<f64>,
    /// The head centre has passed the outlet plane.
    pub head_delivered: Vec<bool>,
    /// Sigma of the bisacromial midpoint (only with a trunk).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shoulders_sigma_mm: Option<Vec<f64>>,
    /// Bisacromial line's angle in the canal cross-section, given as the
    /// direction of the fetal back (perpendicular to the line) on theta's
    /// scale, so `theta - shoulders_theta` is the neck's twist; unwrapped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shoulders_theta_deg: Option<Vec<f64>>,
    /// Signed distance of the bisacromial midpoint past the outlet plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shoulders_below_outlet_mm: Option<Vec<f64>>,
    /// Signed distance of the trunk centre past the outlet plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trunk_below_outlet_mm: Option<Vec<f64>>,
    /// Expulsion force along the fetal spine towards the head (`F . -k`);
    /// negative when it pulls the fetus back.
    pub expulsion_force_n: Vec<f64>,
    /// Magnitude of the total contact force (bone and pelvic floor).
    pub contact_force_n: Vec<f64>,
}

/// The head's axes and derived points at one sample, pelvis frame.
struct HeadState {
    centre: DVec3,
    o: DVec3,
    v: DVec3,
    b: DVec3,
}

/// Occiput tilt beyond which theta is ill-conditioned: at 60 degrees the
/// occiput direction's projection onto the cross-section is half its
/// length, so a small turn of the head about an axis in the cross-section
/// moves theta by up to twice as much as it would at no tilt (1 / cos),
/// growing without bound towards 90 (docs/DETECTOR.md).
pub const THETA_ILL_CONDITIONED_TILT_DEG: f64 = 60.0;

/// The head's turn about the canal's tangent t, degrees on theta's scale:
/// the twist about t of the rotation that takes the head from the
/// occiput-anterior attitude with its vertex down the canal (o = -a,
/// v = t) to where it is, split as a twist about t after a swing about an
/// axis in the cross-section (flexion, asynclitism). For q = twist * swing
/// with the swing's axis normal to t, the twist's half-angle is
/// atan2(q.xyz . t, q.w) whatever the swing, so the reading does not blow
/// up as the occiput tilts (it is singular only with the vertex pointing
/// back up the canal). Equals theta for an untilted head.
fn head_twist_deg(h: &HeadState, frame: &AxisFrame) -> f64 {
    let at_oa = DMat3::from_cols(-frame.anterior, -frame.transverse, frame.tangent);
    let now = DMat3::from_cols(h.o, h.b, h.v);
    let q = DQuat::from_mat3(&(now * at_oa.transpose()));
    let q = if q.w < 0.0 { -q } else { q };
    (2.0 * q.xyz().dot(frame.tangent).atan2(q.w)).to_degrees()
}

/// Angle in degrees of `direction` in the cross-section spanned by the
/// local anterior axis `a` and transverse axis `x`, measured from `a`
/// towards `x` (the mother's right): theta's convention.
pub fn cross_section_angle_deg(direction: DVec3, anterior: DVec3, transverse: DVec3) -> f64 {
    direction
        .dot(transverse)
        .atan2(direction.dot(anterior))
        .to_degrees()
}

/// Signed angle in degrees from `from` to `to` about `axis` (right-hand
/// rule), using only their components normal to `axis`.
pub fn signed_angle_about_deg(from: DVec3, to: DVec3, axis: DVec3) -> f64 {
    axis.dot(from.cross(to)).atan2(from.dot(to)).to_degrees()
}

/// Removes the +-360 degree jumps of an angle series so it runs on
/// continuously (each step taken as the shortest turn).
pub fn unwrap_deg(angles: &mut [f64]) {
    for i in 1..angles.len() {
        let step = angles[i] - angles[i - 1];
        angles[i] = angles[i - 1] + (step + 180.0).rem_euclid(360.0) - 180.0;
    }
}

/// Wraps an angle into (-180, 180].
pub fn wrap_deg(angle: f64) -> f64 {
    let w = (angle + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

impl Series {
    /// Both parietal eminences below the inlet plane at sample `i`
    /// (engagement's test, CARDINAL_MOVEMENTS.md).
    pub fn engaged(&self, i: usize) -> bool {
        self.left_parietal_below_inlet_mm[i].min(self.right_parietal_below_inlet_mm[i]) > 0.0
    }

    /// Evaluates every quantity at every sample. The history must have
    /// passed [`PoseHistory::validate`].
    pub fn from_history(history: &PoseHistory) -> Series {
        let canal = &history.canal;
        let axis = canal.axis();
        let head = &history.head;
        let half_bpd_m = 0.5 * head.biparietal_mm / MM_PER_M;
        let n = history.samples.len();

        let heads: Vec<HeadState> = history
            .samples
            .iter()
            .map(|s| HeadState {
                centre: s.head.point(head.centre_m),
                o: s.head.direction(head.occipitofrontal),
                v: s.head.direction(head.vertex),
                b: s.head.direction(head.biparietal_axis()),
            })
            .collect();
        let head_sigma: Vec<f64> = heads.par_iter().map(|h| axis.project(h.centre)).collect();
        let leading_sigma: Vec<f64> = (0..n)
            .into_par_iter()
            .map(|i| {
                let pose = &history.samples[i].head;
                canal
                    .leading_point(&head.skull_points_m, pose, head_sigma[i])
                    .map_or(head_sigma[i], |(_, sigma)| sigma)
            })
            .collect();
        let spine_axes = trunk_axes(history, &head_sigma);

        let mut series = Series {
            time_s: history.samples.iter().map(|s| s.time_s).collect(),
            station_mm: Vec::with_capacity(n),
            theta_deg: Vec::with_capacity(n),
            phi_deg: Vec::with_capacity(n),
            occiput_tilt_deg: Vec::with_capacity(n),
            head_twist_deg: Vec::with_capacity(n),
            head_sigma_mm: head_sigma.iter().map(|s| s * MM_PER_M).collect(),
            left_parietal_below_inlet_mm: Vec::with_capacity(n),
            right_parietal_below_inlet_mm: Vec::with_capacity(n),
            head_delivered: Vec::with_capacity(n),
            shoulders_sigma_mm: None,
            shoulders_theta_deg: None,
            shoulders_below_outlet_mm: None,
            trunk_below_outlet_mm: None,
            expulsion_force_n: Vec::with_capacity(n),
            contact_force_n: Vec::with_capacity(n),
        };
        for (i, sample) in history.samples.iter().enumerate() {
            let (h, sigma, k) = (&heads[i], head_sigma[i], spine_axes[i]);
            series
                .station_mm
                .push((leading_sigma[i] - canal.spines_sigma()) * MM_PER_M);
            let frame = axis.frame(sigma);
            series.theta_deg.push(cross_section_angle_deg(
                -h.o,
                frame.anterior,
                frame.transverse,
            ));
            series.phi_deg.push(signed_angle_about_deg(-k, h.v, h.b));
            let along = (-h.o).dot(frame.tangent);
            let across = (-h.o - along * frame.tangent).length();
            series.occiput_tilt_deg.push(along.atan2(across).to_degrees());
            series.head_twist_deg.push(head_twist_deg(h, &frame));
            let inlet = canal.inlet();
            series
                .left_parietal_below_inlet_mm
                .push(inlet.signed_distance(h.centre + half_bpd_m * h.b) * MM_PER_M);
            series
                .right_parietal_below_inlet_mm
                .push(inlet.signed_distance(h.centre - half_bpd_m * h.b) * MM_PER_M);
            series
                .head_delivered
                .push(canal.outlet().signed_distance(h.centre) > 0.0);
            series
                .expulsion_force_n
                .push(sample.expulsion_force_n.dot(-k));
            series
                .contact_force_n
                .push((sample.bone_contact_force_n + sample.floor_contact_force_n).length());
        }
        unwrap_deg(&mut series.theta_deg);
        unwrap_deg(&mut series.head_twist_deg);
        if let Some(trunk) = &history.trunk {
            let shoulders: Vec<ShoulderState> = history
                .samples
                .par_iter()
                .filter_map(|s| s.trunk)
                .map(|pose| shoulder_state(canal, &pose, trunk))
                .collect();
            let mut theta: Vec<f64> = shoulders.iter().map(|s| s.theta_deg).collect();
            unwrap_deg(&mut theta);
            series.shoulders_sigma_mm = Some(shoulders.iter().map(|s| s.sigma_mm).collect());
            series.shoulders_theta_deg = Some(theta);
            series.shoulders_below_outlet_mm =
                Some(shoulders.iter().map(|s| s.below_outlet_mm).collect());
            series.trunk_below_outlet_mm =
                Some(shoulders.iter().map(|s| s.trunk_below_outlet_mm).collect());
        }
        series
    }

    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The steepest occiput tilt, absolute, over the samples from `start_s`
    /// to `end_s`; `None` when none lies there (or the series predates the
    /// tilt).
    pub fn steepest_occiput_tilt_deg(&self, start_s: f64, end_s: f64) -> Option<f64> {
        self.time_s
            .iter()
            .zip(&self.occiput_tilt_deg)
            .filter(|(t, _)| (start_s..=end_s).contains(*t))
            .map(|(_, tilt)| tilt.abs())
            .reduce(f64::max)
    }

    /// Rows for a CSV file: the column names, then one row per sample
    /// (`None` for a column that does not apply, booleans as 0 and 1).
    pub fn table(&self) -> (Vec<&'static str>, Vec<Vec<Option<f64>>>) {
        let mut columns: Vec<(&'static str, Vec<Option<f64>>)> = vec![
            ("time_s", self.time_s.iter().copied().map(Some).collect()),
            (
                "station_mm",
                self.station_mm.iter().copied().map(Some).collect(),
            ),
            (
                "theta_deg",
                self.theta_deg.iter().copied().map(Some).collect(),
            ),
            ("phi_deg", self.phi_deg.iter().copied().map(Some).collect()),
            (
                "occiput_tilt_deg",
                self.occiput_tilt_deg.iter().copied().map(Some).collect(),
            ),
            (
                "head_twist_deg",
                self.head_twist_deg.iter().copied().map(Some).collect(),
            ),
            (
                "head_sigma_mm",
                self.head_sigma_mm.iter().copied().map(Some).collect(),
            ),
            (
                "left_parietal_below_inlet_mm",
                self.left_parietal_below_inlet_mm
                    .iter()
                    .copied()
                    .map(Some)
                    .collect(),
            ),
            (
                "right_parietal_below_inlet_mm",
                self.right_parietal_below_inlet_mm
                    .iter()
                    .copied()
                    .map(Some)
                    .collect(),
            ),
            (
                "head_delivered",
                self.head_delivered
                    .iter()
                    .map(|&d| Some(if d { 1.0 } else { 0.0 }))
                    .collect(),
            ),
        ];
        let optional = [
            ("shoulders_sigma_mm", &self.shoulders_sigma_mm),
            ("shoulders_theta_deg", &self.shoulders_theta_deg),
            ("shoulders_below_outlet_mm", &self.shoulders_below_outlet_mm),
            ("trunk_below_outlet_mm", &self.trunk_below_outlet_mm),
        ];
        for (name, values) in optional {
            let column = match values {
                Some(v) => v.iter().copied().map(Some).collect(),
                None => vec![None; self.len()],
            };
            columns.push((name, column));
        }
        columns.push((
            "expulsion_force_n",
            self.expulsion_force_n.iter().copied().map(Some).collect(),
        ));
        columns.push((
            "contact_force_n",
            self.contact_force_n.iter().copied().map(Some).collect(),
        ));
        let names = columns.iter().map(|(name, _)| *name).collect();
        let rows = (0..self.len())
            .map(|i| columns.iter().map(|(_, c)| c[i]).collect())
            .collect();
        (names, rows)
    }
}

struct ShoulderState {
    sigma_mm: f64,
    theta_deg: f64,
    below_outlet_mm: f64,
    trunk_below_outlet_mm: f64,
}

fn shoulder_state(
    canal: &BirthCanal,
    pose: &crate::history::RigidPose,
    trunk: &crate::history::TrunkGeometry,
) -> ShoulderState {
    let right = pose.point(trunk.right_acromion_m);
    let left = pose.point(trunk.left_acromion_m);
    let midpoint = 0.5 * (left + right);
    let sigma = canal.axis().project(midpoint);
    let frame = canal.axis().frame(sigma);
    // The back lies at t x (right -> left), as the occiput lies at t x b
    // for a head whose vertex leads.
    let back = frame.tangent.cross(left - right);
    ShoulderState {
        sigma_mm: sigma * MM_PER_M,
        theta_deg: cross_section_angle_deg(back, frame.anterior, frame.transverse),
        below_outlet_mm: canal.outlet().signed_distance(midpoint) * MM_PER_M,
        trunk_below_outlet_mm: canal.outlet().signed_distance(pose.point(trunk.centre_m))
            * MM_PER_M,
    }
}

/// The trunk axis `k` at every sample: the trunk's spine where a trunk is
/// modelled, otherwise minus the expulsion force's direction
/// (CARDINAL_MOVEMENTS.md). A force that changes sign between contractions
/// would flip that direction, so its sign is chosen to point back up the
/// canal (`k . t <= 0` at the head), the side where the breech is; where
/// the force is too small to have a direction, the nearest earlier (or,
/// at the start, later) usable sample's axis is used, and the canal's own
/// backward tangent if no sample has one.
fn trunk_axes(history: &PoseHistory, head_sigma: &[f64]) -> Vec<DVec3> {
    if let Some(trunk) = &history.trunk {
        return history
            .samples
            .iter()
            .map(|s: &PoseSample| s.trunk.map_or(DVec3::ZERO, |t| t.direction(trunk.spine)))
            .collect();
    }
    let axis = history.canal.axis();
    let from_force: Vec<Option<DVec3>> = history
        .samples
        .iter()
        .zip(head_sigma)
        .map(|(s, &sigma)| {
            let f = s.expulsion_force_n;
            (f.length() > FORCE_DIRECTION_MIN_N).then(|| {
                let k = -f.normalize();
                if k.dot(axis.tangent(sigma)) > 0.0 {
                    -k
                } else {
                    k
                }
            })
        })
        .collect();
    let first = from_force.iter().flatten().next().copied();
    let mut last = first;
    from_force
        .iter()
        .zip(head_sigma)
        .map(|(k, &sigma)| {
            if k.is_some() {
                last = *k;
            }
            last.unwrap_or_else(|| -axis.tangent(sigma))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::history::{RigidPose, TrunkGeometry};
    use crate::synthetic::{ellipsoid_head, head_orientation, reference_canal, simple_trunk};

    use proptest::prelude::*;

    /// A two-sample history holding the given head pose (and trunk pose)
    /// twice, with the force pushing down the canal at the inlet.
    fn still(head: RigidPose, trunk: Option<(TrunkGeometry, RigidPose)>) -> PoseHistory {
        let trunk_pose = trunk.as_ref().map(|t| t.1);
        let sample = |time_s| PoseSample {
            time_s,
            head,
            trunk: trunk_pose,
            lower_trunk: None,
            expulsion_force_n: DVec3::new(0.0, 0.0, -50.0),
            bone_contact_force_n: DVec3::ZERO,
            floor_contact_force_n: DVec3::ZERO,
            dominant_contact: None,
            dominant_part: None,
        };
        PoseHistory {
            head: ellipsoid_head(),
            trunk: trunk.map(|t| t.0),
            canal: reference_canal(),
            samples: vec![sample(0.0), sample(1.0)],
        }
    }

    /// The synthetic head's body axes are o = +x, b = +y, v = +z; this is the
    /// rotation taking them to the given pelvis-frame o and v.
    fn axes(o: DVec3, v: DVec3) -> DQuat {
        DQuat::from_mat3(&DMat3::from_cols(o, v.cross(o), v))
    }

    fn at_inlet(orientation: DQuat) -> RigidPose {
        RigidPose {
            position_m: DVec3::new(0.0, 0.0, 0.01),
            orientation,
        }
    }

    fn first(history: &PoseHistory) -> (f64, f64, f64) {
        history.validate().unwrap();
        let s = Series::from_history(history);
        (s.station_mm[0], s.theta_deg[0], s.phi_deg[0])
    }

    #[test]
    fn occiput_to_the_mothers_left_is_minus_ninety() {
        // Occiput (-o) towards -x, vertex down the canal (-z).
        let (_, theta, _) = first(&still(at_inlet(axes(DVec3::X, DVec3::NEG_Z)), None));
        assert!((theta + 90.0).abs() < 1e-9, "LOT gave {theta}");
    }

    #[test]
    fn occiput_positions_at_the_inlet() {
        for (occiput, expected) in [(DVec3::Y, 0.0), (DVec3::X, 90.0), (DVec3::NEG_Y, 180.0)] {
            let (_, theta, _) = first(&still(at_inlet(axes(-occiput, DVec3::NEG_Z)), None));
            assert!(
                (wrap_deg(theta).abs() - expected).abs() < 1e-9,
                "occiput {occiput} gave {theta}"
            );
        }
    }

    /// The occiput's tilt out of the cross-section: none for a head whose
    /// occiput lies in it, +90 for one whose occiput points down the canal
    /// (where theta means nothing), and the textbook's flexed head stays
    /// well inside the range where theta is well conditioned.
    #[test]
    fn the_occiput_tilt_says_when_theta_means_little() {
        let tilt = |o: DVec3, v: DVec3| {
            let history = still(at_inlet(axes(o, v)), None);
            Series::from_history(&history).occiput_tilt_deg[0]
        };
        assert!(tilt(DVec3::X, DVec3::NEG_Z).abs() < 1e-9);
        // Occiput (-o) straight down the canal (-z at the inlet).
        let down = tilt(DVec3::Z, DVec3::X);
        assert!((down - 90.0).abs() < 1e-9, "{down}");
        let canal = reference_canal();
        let textbook = Series::from_history(&crate::synthetic::textbook(&canal));
        let steepest = textbook.steepest_occiput_tilt_deg(f64::MIN, f64::MAX).unwrap();
        assert!(steepest < THETA_ILL_CONDITIONED_TILT_DEG, "textbook tilt {steepest}");
        assert_eq!(textbook.steepest_occiput_tilt_deg(-2.0, -1.0), None);
    }

    #[test]
    fn chin_to_chest_is_positive_phi() {
        // OA head: face (o) posterior, -y. Flexing by 20 degrees turns the
        // forehead up towards the trunk (+z) and the vertex towards the
        // face side (-y); the trunk lies above, spine k = +z.
        let a = 20f64.to_radians();
        let o = DVec3::new(0.0, -a.cos(), a.sin());
        let v = DVec3::new(0.0, -a.sin(), -a.cos());
        let trunk = simple_trunk();
        // Trunk body: chest +x, left +y, head +z; here chest -y, head -z, left -x.
        let orientation =
            DQuat::from_mat3(&DMat3::from_cols(DVec3::NEG_Y, DVec3::NEG_X, DVec3::NEG_Z));
        let trunk_pose = RigidPose {
            position_m: DVec3::new(0.0, 0.0, 0.16),
            orientation,
        };
        let history = still(at_inlet(axes(o, v)), Some((trunk, trunk_pose)));
        let (_, theta, phi) = first(&history);
        assert!((phi - 20.0).abs() < 1e-9, "flexion gave phi = {phi}");
        assert!(theta.abs() < 1e-9, "OA gave theta = {theta}");
        // Without a trunk, k comes from the force (pushing down -z): the same phi.
        let (_, _, phi) = first(&still(at_inlet(axes(o, v)), None));
        assert!((phi - 20.0).abs() < 1e-9);
    }

    #[test]
    fn station_by_hand_above_the_inlet() {
        // Vertex leading, centre 60 mm above the inlet on the straight part
        // of the axis: the leading point (the synthetic head's 50 mm vertex
        // semi-axis; the lattice's point nearest the pole lies 0.1 mm inside
        // it) is 10 mm above the inlet.
        let pose = RigidPose {
            position_m: DVec3::new(0.0, 0.0, 0.06),
            orientation: axes(DVec3::X, DVec3::NEG_Z),
        };
        let history = still(pose, None);
        let (station, _, _) = first(&history);
        let expected = (-0.01 - history.canal.spines_sigma()) * 1000.0;
        assert!(
            (station - expected).abs() < 0.11,
            "station {station}, expected {expected}"
        );
    }

    /// The head's twist about the canal axis is theta for an untilted
    /// head; with the occiput tilted 80 degrees down the canal, a 10 degree
    /// tip of the head about the transverse axis swings theta by tens of
    /// degrees and the twist by less than the tip (a tip after a large
    /// swing does carry some twist: tan(twist / 2) = tan(5) tan(40) here),
    /// while a true turn about the canal axis moves both alike.
    #[test]
    fn the_head_twist_holds_where_theta_swings() {
        let series = |o: DVec3, v: DVec3, turn: DQuat| {
            Series::from_history(&still(at_inlet(turn * axes(o, v)), None))
        };
        // LOT, untilted: both -90.
        let s = series(DVec3::X, DVec3::NEG_Z, DQuat::IDENTITY);
        assert!((s.theta_deg[0] + 90.0).abs() < 1e-9 && (s.head_twist_deg[0] + 90.0).abs() < 1e-9);
        // LOT flexed 80 degrees: the occiput (-o) points mostly down (-z).
        let a = 80f64.to_radians();
        let (o, v) = (DVec3::new(a.cos(), 0.0, a.sin()), DVec3::new(a.sin(), 0.0, -a.cos()));
        let flexed = series(o, v, DQuat::IDENTITY);
        assert!((flexed.occiput_tilt_deg[0] - 80.0).abs() < 1e-9);
        assert!((flexed.theta_deg[0] + 90.0).abs() < 1e-9 && (flexed.head_twist_deg[0] + 90.0).abs() < 1e-9);
        // Tipped 10 degrees sideways about the transverse axis (+x at the
        // inlet), which swings the short projection of the occiput.
        let tipped = series(o, v, DQuat::from_rotation_x(10f64.to_radians()));
        let (dtheta, dtwist) = (tipped.theta_deg[0] + 90.0, tipped.head_twist_deg[0] + 90.0);
        assert!(dtheta.abs() > 30.0 && dtwist.abs() < 10.0, "theta moved {dtheta}, twist {dtwist}");
        // Turned 30 degrees about the canal axis (-z): both move by 30.
        let turned = series(o, v, DQuat::from_rotation_z(-30f64.to_radians()));
        let (dtheta, dtwist) = (turned.theta_deg[0] + 90.0, turned.head_twist_deg[0] + 90.0);
        assert!((dtheta - 30.0).abs() < 1e-6 && (dtwist - 30.0).abs() < 1e-6, "{dtheta} {dtwist}");
    }

    #[test]
    fn eminences_and_delivery_by_hand() {
        // LOT, b along -y, lies in the inlet plane: both eminences 10 mm above it.
        let history = still(at_inlet(axes(DVec3::X, DVec3::NEG_Z)), None);
        let s = Series::from_history(&history);
        assert!((s.left_parietal_below_inlet_mm[0] + 10.0).abs() < 1e-9);
        assert!((s.right_parietal_below_inlet_mm[0] + 10.0).abs() < 1e-9);
        assert!(!s.head_delivered[0]);
        // Tilted 10 degrees about o (asynclitism): the fetal left eminence
        // (-y side) goes down, the right one up, by BPD/2 sin(10 deg).
        let tilt = DQuat::from_rotation_x(10f64.to_radians());
        let history = still(at_inlet(tilt * axes(DVec3::X, DVec3::NEG_Z)), None);
        let s = Series::from_history(&history);
        let shift = 47.5 * 10f64.to_radians().sin();
        assert!((s.left_parietal_below_inlet_mm[0] - (shift - 10.0)).abs() < 1e-9);
        assert!((s.right_parietal_below_inlet_mm[0] - (-shift - 10.0)).abs() < 1e-9);
        // Centre just past the outlet plane: delivered.
        let outlet = *history.canal.outlet();
        let pose = RigidPose {
            position_m: outlet.centre + 1e-4 * outlet.normal,
            orientation: DQuat::IDENTITY,
        };
        assert!(Series::from_history(&still(pose, None)).head_delivered[0]);
    }

    #[test]
    fn shoulders_align_with_the_occiput_when_the_neck_is_untwisted() {
        // Trunk body: chest +x, left +y, head +z. Back towards the mother's
        // left (-x) like a LOT occiput: chest +x, head down -z, left = -z x x = -y.
        let trunk = simple_trunk();
        let orientation = DQuat::from_mat3(&DMat3::from_cols(DVec3::X, DVec3::NEG_Y, DVec3::NEG_Z));
        let pose = RigidPose {
            position_m: DVec3::new(0.0, 0.0, 0.16),
            orientation,
        };
        let history = still(at_inlet(axes(DVec3::X, DVec3::NEG_Z)), Some((trunk, pose)));
        let s = Series::from_history(&history);
        let shoulders = s.shoulders_theta_deg.as_ref().unwrap()[0];
        assert!((shoulders + 90.0).abs() < 1e-9, "shoulders at {shoulders}");
        assert!((s.theta_deg[0] - shoulders).abs() < 1e-9);
        assert!((s.shoulders_sigma_mm.as_ref().unwrap()[0] + 90.0).abs() < 1e-9);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Spinning the head by alpha about the canal tangent through its
        /// centre turns theta by +alpha (a = x cross t, so a positive turn
        /// about t takes a towards x) and leaves phi alone.
        #[test]
        fn spin_about_the_tangent_offsets_theta(
            sigma_mm in -50.0f64..150.0,
            theta in -170.0f64..170.0,
            phi in -40.0f64..40.0,
            alpha in -150.0f64..150.0,
        ) {
            let canal = reference_canal();
            let f = canal.axis().frame(sigma_mm / 1000.0);
            let q = head_orientation(f.tangent, f.anterior, f.transverse, theta, phi);
            let spun = DQuat::from_axis_angle(f.tangent, alpha.to_radians()) * q;
            let pose = |orientation| RigidPose { position_m: f.point, orientation };
            let mut before = still(pose(q), None);
            let mut after = still(pose(spun), None);
            for h in [&mut before, &mut after] {
                for s in &mut h.samples {
                    s.expulsion_force_n = 50.0 * f.tangent;
                }
            }
            let (_, t0, p0) = first(&before);
            let (_, t1, p1) = first(&after);
            prop_assert!((t0 - theta).abs() < 1e-6);
            prop_assert!(wrap_deg(t1 - t0 - alpha).abs() < 1e-6);
            prop_assert!((p0 - phi).abs() < 1e-6 && (p1 - phi).abs() < 1e-6);
        }

        /// A head turned by theta about the canal's tangent after any tilt
        /// about an axis in the cross-section (flexion, asynclitism, or a
        /// mix, up to 85 degrees) reads theta as its twist, anywhere along
        /// the canal, and its occiput tilts no more than the head was tilted.
        #[test]
        fn the_twist_of_a_tilted_head_is_its_turn_about_the_canal(
            sigma_mm in -50.0f64..150.0,
            theta in -179.0f64..179.0,
            tilt in 0.0f64..85.0,
            tilt_axis_deg in 0.0f64..360.0,
        ) {
            let canal = reference_canal();
            let f = canal.axis().frame(sigma_mm / 1000.0);
            // Occiput anterior, vertex down the canal: o = -a, v = t.
            let at_oa = DQuat::from_mat3(&DMat3::from_cols(-f.anterior, -f.transverse, f.tangent));
            let (s, c) = tilt_axis_deg.to_radians().sin_cos();
            let tilted = DQuat::from_axis_angle(c * f.anterior + s * f.transverse, tilt.to_radians());
            let q = DQuat::from_axis_angle(f.tangent, theta.to_radians()) * tilted * at_oa;
            let series = Series::from_history(&still(RigidPose { position_m: f.point, orientation: q }, None));
            prop_assert!(wrap_deg(series.head_twist_deg[0] - theta).abs() < 1e-6, "{}", series.head_twist_deg[0]);
            prop_assert!(series.occiput_tilt_deg[0].abs() <= tilt + 1e-6);
        }

        /// phi depends only on the head's orientation relative to the trunk:
        /// any common rigid motion of both leaves it unchanged.
        #[test]
        fn phi_ignores_a_common_rigid_motion(
            axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
            angle in -3.0f64..3.0,
            shift in (-0.05f64..0.05, -0.05f64..0.05, -0.05f64..0.05),
            phi in -40.0f64..40.0,
        ) {
            let head = head_orientation(DVec3::NEG_Z, DVec3::Y, DVec3::X, 30.0, phi);
            let trunk_pose = RigidPose { position_m: DVec3::new(0.0, 0.0, 0.16), orientation: DQuat::IDENTITY };
            let moved = DQuat::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
            let offset = DVec3::new(shift.0, shift.1, shift.2);
            let original = still(at_inlet(head), Some((simple_trunk(), RigidPose {
                position_m: trunk_pose.position_m,
                orientation: DQuat::from_mat3(&DMat3::from_cols(DVec3::NEG_Y, DVec3::NEG_X, DVec3::NEG_Z)),
            })));
            let mut shifted = original.clone();
            for s in &mut shifted.samples {
                for pose in [Some(&mut s.head), s.trunk.as_mut()].into_iter().flatten() {
                    pose.position_m = moved * pose.position_m + offset;
                    pose.orientation = moved * pose.orientation;
                }
            }
            let (_, _, p0) = first(&original);
            let (_, _, p1) = first(&shifted);
            prop_assert!((p0 - phi).abs() < 1e-6, "phi {} expected {}", p0, phi);
            prop_assert!((p1 - p0).abs() < 1e-6);
        }

    }

    proptest! {
        // Each case projects all 500 skull points: keep the count small.
        #![proptest_config(ProptestConfig::with_cases(16))]

        /// Where the canal is straight over the whole head (above the inlet),
        /// the leading point found along the tangent is the literal deepest
        /// skull point along the axis: the largest projected sigma.
        #[test]
        fn station_is_the_deepest_sigma_where_the_canal_is_straight(
            depth_mm in -200.0f64..-70.0,
            rotation in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        ) {
            let q = DQuat::from_xyzw(rotation.0, rotation.1, rotation.2, rotation.3);
            prop_assume!(q.length() > 0.1);
            let pose = RigidPose { position_m: DVec3::new(0.0, 0.0, -depth_mm / 1000.0), orientation: q.normalize() };
            let history = still(pose, None);
            let (station, _, _) = first(&history);
            let deepest = history.head.skull_points_m.iter()
                .map(|&p| history.canal.axis().project(pose.point(p)))
                .fold(f64::NEG_INFINITY, f64::max);
            prop_assert!((station - (deepest - history.canal.spines_sigma()) * 1000.0).abs() < 1e-6);
        }

    }

    proptest! {
        /// A quaternion and its negative are the same rotation: same series.
        #[test]
        fn quaternion_sign_does_not_matter(
            rotation in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        ) {
            let q = DQuat::from_xyzw(rotation.0, rotation.1, rotation.2, rotation.3);
            prop_assume!(q.length() > 0.1);
            let q = q.normalize();
            let a = Series::from_history(&still(at_inlet(q), None));
            let b = Series::from_history(&still(at_inlet(-q), None));
            prop_assert!((a.station_mm[0] - b.station_mm[0]).abs() < 1e-9);
            prop_assert!(wrap_deg(a.theta_deg[0] - b.theta_deg[0]).abs() < 1e-9);
            prop_assert!((a.phi_deg[0] - b.phi_deg[0]).abs() < 1e-9);
        }
    }

    #[test]
    fn unwrapping_follows_the_shortest_turn() {
        let mut a = vec![170.0, -170.0, -100.0, 170.0];
        unwrap_deg(&mut a);
        assert_eq!(a, vec![170.0, 190.0, 260.0, 170.0]);
    }

    #[test]
    fn wrapping_lands_in_the_half_open_interval() {
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(540.0), 180.0);
        assert_eq!(wrap_deg(-270.0), 90.0);
        assert_eq!(wrap_deg(45.0), 45.0);
    }
}
