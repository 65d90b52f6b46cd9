//! Quantities derived at every sample (CARDINAL_MOVEMENTS.md, "Quantities
//! recorded at every output sample"), as a structure of arrays.
//!
//! The series is an output product: its fields carry the units of the
//! report (mm, degrees) in their names, as CONVENTIONS.md asks of JSON.
//! Geometry is evaluated in SI and converted once, here.

use crate::canal::BirthCanal;
use crate::history::{PoseHistory, PoseSample};
use glam::DVec3;
use serde::{Deserialize, Serialize};

const MM_PER_M: f64 = 1000.0;

/// Below this magnitude (N) the expulsion force has no usable direction,
/// so the trunk axis is carried over from a neighbouring sample.
const FORCE_DIRECTION_MIN_N: f64 = 1e-6;

/// Per-sample series, one entry per sample of the history.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub time_s: Vec<f64>,
    /// Sigma of the head's leading point minus sigma of the ischial-spine
    /// plane (clinical station, positive below the spines).
    pub station_mm: Vec<f64>,
    /// Occiput position: 0 = OA, +90 = ROT, -90 = LOT, +-180 = OP;
    /// unwrapped, so it runs on continuously past +-180.
    pub theta_deg: Vec<f64>,
    /// Attitude: positive in flexion (chin towards chest).
    pub phi_deg: Vec<f64>,
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

/// Angle in degrees of `direction` in the cross-section spanned by the
/// local anterior axis `a` and transverse axis `x`, measured from `a`
/// towards `x` (the mother's right): theta's convention.
pub fn cross_section_angle_deg(direction: DVec3, anterior: DVec3, transverse: DVec3) -> f64 {
    direction.dot(transverse).atan2(direction.dot(anterior)).to_degrees()
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
        let head_sigma: Vec<f64> = heads.iter().map(|h| axis.project(h.centre)).collect();
        let spine_axes = trunk_axes(history, &head_sigma);

        let mut series = Series {
            time_s: history.samples.iter().map(|s| s.time_s).collect(),
            station_mm: Vec::with_capacity(n),
            theta_deg: Vec::with_capacity(n),
            phi_deg: Vec::with_capacity(n),
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
        let mut skull = vec![DVec3::ZERO; head.skull_points_m.len()];
        for (i, sample) in history.samples.iter().enumerate() {
            let (h, sigma, k) = (&heads[i], head_sigma[i], spine_axes[i]);
            for (world, &body) in skull.iter_mut().zip(&head.skull_points_m) {
                *world = sample.head.point(body);
            }
            let leading = canal.deepest_sigma(&skull, sigma);
            series.station_mm.push((leading - canal.spines_sigma()) * MM_PER_M);
            let frame = axis.frame(sigma);
            series.theta_deg.push(cross_section_angle_deg(-h.o, frame.anterior, frame.transverse));
            series.phi_deg.push(signed_angle_about_deg(-k, h.v, h.b));
            let inlet = canal.inlet();
            series
                .left_parietal_below_inlet_mm
                .push(inlet.signed_distance(h.centre + half_bpd_m * h.b) * MM_PER_M);
            series
                .right_parietal_below_inlet_mm
                .push(inlet.signed_distance(h.centre - half_bpd_m * h.b) * MM_PER_M);
            series.head_delivered.push(canal.outlet().signed_distance(h.centre) > 0.0);
            series.expulsion_force_n.push(sample.expulsion_force_n.dot(-k));
            series
                .contact_force_n
                .push((sample.bone_contact_force_n + sample.floor_contact_force_n).length());
        }
        unwrap_deg(&mut series.theta_deg);
        if let Some(trunk) = &history.trunk {
            let shoulders: Vec<ShoulderState> = history
                .samples
                .iter()
                .filter_map(|s| s.trunk)
                .map(|pose| shoulder_state(canal, &pose, trunk))
                .collect();
            let mut theta: Vec<f64> = shoulders.iter().map(|s| s.theta_deg).collect();
            unwrap_deg(&mut theta);
            series.shoulders_sigma_mm = Some(shoulders.iter().map(|s| s.sigma_mm).collect());
            series.shoulders_theta_deg = Some(theta);
            series.shoulders_below_outlet_mm = Some(shoulders.iter().map(|s| s.below_outlet_mm).collect());
            series.trunk_below_outlet_mm = Some(shoulders.iter().map(|s| s.trunk_below_outlet_mm).collect());
        }
        series
    }

    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Rows for a CSV file: the column names, then one row per sample
    /// (`None` for a column that does not apply, booleans as 0 and 1).
    pub fn table(&self) -> (Vec<&'static str>, Vec<Vec<Option<f64>>>) {
        let mut columns: Vec<(&'static str, Vec<Option<f64>>)> = vec![
            ("time_s", self.time_s.iter().copied().map(Some).collect()),
            ("station_mm", self.station_mm.iter().copied().map(Some).collect()),
            ("theta_deg", self.theta_deg.iter().copied().map(Some).collect()),
            ("phi_deg", self.phi_deg.iter().copied().map(Some).collect()),
            ("head_sigma_mm", self.head_sigma_mm.iter().copied().map(Some).collect()),
            (
                "left_parietal_below_inlet_mm",
                self.left_parietal_below_inlet_mm.iter().copied().map(Some).collect(),
            ),
            (
                "right_parietal_below_inlet_mm",
                self.right_parietal_below_inlet_mm.iter().copied().map(Some).collect(),
            ),
            (
                "head_delivered",
                self.head_delivered.iter().map(|&d| Some(if d { 1.0 } else { 0.0 })).collect(),
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
        columns.push(("expulsion_force_n", self.expulsion_force_n.iter().copied().map(Some).collect()));
        columns.push(("contact_force_n", self.contact_force_n.iter().copied().map(Some).collect()));
        let names = columns.iter().map(|(name, _)| *name).collect();
        let rows = (0..self.len()).map(|i| columns.iter().map(|(_, c)| c[i]).collect()).collect();
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
        trunk_below_outlet_mm: canal.outlet().signed_distance(pose.point(trunk.centre_m)) * MM_PER_M,
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

    #[test]
    fn cross_section_angles_follow_the_clinical_positions() {
        // At the inlet a = +y, x = +x.
        let (a, x) = (DVec3::Y, DVec3::X);
        assert!((cross_section_angle_deg(DVec3::Y, a, x) - 0.0).abs() < 1e-12); // OA
        assert!((cross_section_angle_deg(DVec3::X, a, x) - 90.0).abs() < 1e-12); // ROT
        assert!((cross_section_angle_deg(-DVec3::X, a, x) + 90.0).abs() < 1e-12); // LOT
        assert!((cross_section_angle_deg(-DVec3::Y, a, x).abs() - 180.0).abs() < 1e-12); // OP
    }

    #[test]
    fn flexion_is_a_positive_rotation_of_the_vertex_about_b() {
        // Head frame (o, b, v) = (x, y, z) is right-handed: o x b = v.
        let (o, b, v) = (DVec3::X, DVec3::Y, DVec3::Z);
        assert!((v.cross(o) - b).length() < 1e-15);
        // Trunk along -v (neutral attitude): phi = 0.
        let k = -v;
        assert!(signed_angle_about_deg(-k, v, b).abs() < 1e-12);
        // Chin to chest: the forehead turns towards the trunk, so the
        // vertex tilts towards the face: v -> v cos + o sin.
        let angle = 20f64.to_radians();
        let flexed_v = v * angle.cos() + o * angle.sin();
        assert!((signed_angle_about_deg(-k, flexed_v, b) - 20.0).abs() < 1e-9);
    }
}
