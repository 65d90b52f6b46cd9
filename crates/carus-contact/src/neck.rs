//! The fetal neck: a six-degree-of-freedom spring between the head and the
//! trunk at the atlanto-occipital pivot, with different stiffness in flexion
//! and extension and in compression and tension (REFERENCE_DATA.md, from
//! Lapeer et al. 2019 / Sadulaev 2019).

use glam::{DMat3, DQuat, DVec3};
use parry3d_f64::math::SymmetricEigen3;
use serde::{Deserialize, Serialize};

use crate::error::{check_non_negative, ContactError};
use crate::law::semi_implicit_step_limit;
use crate::rigid::{RigidBodyModel, RigidBodyState, Wrench};

/// Where the neck's rotational springs are at rest (`[neck] rest_attitude`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NeckRest {
    /// At the attitude the head is joined in, the scenario's start: the
    /// fetus holds the attitude it presents in, flexed in a vertex
    /// presentation, deflexed in a face presentation ("attitude" is the
    /// posture of the fetus, which the presentation is named by; Williams
    /// Obstetrics, chapter "Normal Labor"). No measured resting moment of a fetal
    /// neck was found, so the springs resist departures from that posture.
    #[default]
    Start,
    /// At the anatomical neutral attitude, the head in line with the trunk:
    /// the passive reading of the stiffness figures, which are measured
    /// from neutral. A head joined away from neutral is then pulled
    /// towards it from the first step (a face presentation, joined 80 deg
    /// extended, by 80 x `extension_nm_per_deg`).
    Neutral,
}

/// Stiffness and damping of the neck. Angles in degrees as the source gives
/// them. Also a scenario's `[neck]` table: a key left out keeps its default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NeckStiffness {
    /// REFERENCE_DATA.md: flexion 0.01 N m per degree (Lapeer et al. 2019 / Sadulaev 2019).
    pub flexion_nm_per_deg: f64,
    /// REFERENCE_DATA.md: extension 0.04 N m per degree.
    pub extension_nm_per_deg: f64,
    /// REFERENCE_DATA.md: lateral bending 0.02 N m per degree.
    pub lateral_bending_nm_per_deg: f64,
    /// REFERENCE_DATA.md: axial rotation 0.01 N m per degree.
    pub axial_rotation_nm_per_deg: f64,
    /// REFERENCE_DATA.md: compression 1064.5 N/m.
    pub compression_n_per_m: f64,
    /// REFERENCE_DATA.md: tension 3361.8 N/m.
    pub tension_n_per_m: f64,
    /// Shear across the neck axis, N/m. No source gives it; the tension
    /// value (the stiffer of the two axial ones) keeps the pivot shared.
    pub shear_n_per_m: f64,
    /// Rotational dashpot, N m s/rad. Numerical: about critical damping of
    /// the flexion mode of a term head (k = 0.573 N m/rad, I ~ 5e-4 kg m^2:
    /// 2 sqrt(k I) ~ 0.034), so the neck does not ring between contractions.
    pub rotational_damping_nm_s_per_rad: f64,
    /// Linear dashpot at the pivot, N s/m. Numerical: about critical for
    /// the head (0.6 kg) on the compression spring, 2 sqrt(k m) ~ 50.
    pub linear_damping_n_s_per_m: f64,
    /// End of the flexion range, degrees of flexion from the anatomical
    /// neutral attitude (head in line with the trunk). The fetus in labour,
    /// on MRI during descent (Ferrandini, Nguyen & Dao 2025, Comput.
    /// Methods Biomech. Biomed. Engin. 28:1915): the skull flexes at most
    /// 12 deg on the cervical spine and the cervical spine at most 7 deg
    /// on the torso. This joint is the whole of the head's flexion on the
    /// trunk (the trunk body begins at T1), so its range is the sum, 19
    /// deg. Until the twentieth session it was 66 deg, the active range
    /// of children aged 8-10 (Lynch-Caris et al. 2008, J. Biomech. 41),
    /// for want of a fetal figure; the outcome turns on it (docs/LABOUR.md,
    /// twentieth session). Beyond it the neck stiffens (see
    /// `end_range_stiffness_nm_per_deg`): a physical limit, not a guide.
    pub flexion_limit_deg: f64,
    /// End of the extension range, degrees from neutral. Lynch-Caris et
    /// al. 2008: extension 85 +- 14 deg (same cohort and caveat).
    pub extension_limit_deg: f64,
    /// End of the lateral bending range, degrees to either side of the
    /// joining pose (the fetus is joined unbent). Öhman & Beckung 2008
    /// (Pediatr. Phys. Ther. 20:53, passive range of motion of 38 infants
    /// aged 2-10 months): lateral flexion 70 deg, the youngest measured
    /// figure found.
    pub lateral_bending_limit_deg: f64,
    /// End of the axial rotation range, degrees to either side of the
    /// joining pose (the fetus is joined untwisted). Öhman & Beckung 2008:
    /// rotation 110 deg.
    pub axial_rotation_limit_deg: f64,
    /// Stiffness added beyond any limit, N m per degree. Numerical (the
    /// limit is what is cited; this only enforces it, like a contact
    /// penalty): the largest moment about the pivot the head meets, about
    /// 7 N m (140 N, REFERENCE_DATA.md, at a 50 mm lever, the head's
    /// radius), carries the neck at most 7 degrees past the limit, and the
    /// head on that spring (I ~ 1.5e-3 kg m^2 about the pivot) turns at
    /// omega ~ 200 rad/s, omega dt = 0.2 at the 1 ms rigid step.
    pub end_range_stiffness_nm_per_deg: f64,
    /// Shortening at which the neck's column bottoms out, mm: the
    /// compression spring is the lax first part of a stiffening response
    /// (the spine's neutral zone, Panjabi 1992, J. Spinal Disord. 5:383),
    /// and on its own it lets the push of REFERENCE_DATA.md shorten the
    /// neck by more than its length (120 N over 1064.5 N/m is 113 mm; the
    /// neck is 37 mm from the pivot to T1, the cervical spine at birth, in
    /// carus-anatomy's trunk). Engineering estimate: 6 mm, a sixth of that
    /// length (set as a quarter of the 24 mm neck estimated before the
    /// thirtieth session, and kept when the neck took its measured length
    /// so that one change is measured at a time), well short of
    /// the 70 % strain at which developing cervical spines failed in
    /// compression (Nuckley et al. 2007, Spine 32(6), baboon). No neonatal
    /// figure was found; the outcome turns on it (docs/LABOUR.md,
    /// sixteenth session).
    pub compression_limit_mm: f64,
    /// Axial stiffness added beyond `compression_limit_mm`, N/m. Numerical,
    /// like `end_range_stiffness_nm_per_deg` (the limit is what is
    /// estimated; this only enforces it): the largest push of
    /// REFERENCE_DATA.md, 140 N, carries the neck 4.3 mm past it. A stop
    /// five times stiffer rings at the 0.5 ms rigid step: halving the step
    /// moved the normal head 1.2 mm in 10 s, against 0.04 mm with this one
    /// (docs/LABOUR.md, sixteenth session).
    pub end_range_compression_n_per_m: f64,
    /// Where the rotational springs rest ([`NeckRest`]): `start` (the
    /// default) or `neutral`. The range limits are measured from neutral
    /// either way. docs/LABOUR.md gives the outcomes of both.
    pub rest_attitude: NeckRest,
}


impl Default for NeckStiffness {
    fn default() -> Self {
        NeckStiffness {
            flexion_nm_per_deg: 0.01,
            extension_nm_per_deg: 0.04,
            lateral_bending_nm_per_deg: 0.02,
            axial_rotation_nm_per_deg: 0.01,
            compression_n_per_m: 1064.5,
            tension_n_per_m: 3361.8,
            shear_n_per_m: 3361.8,
            rotational_damping_nm_s_per_rad: 0.034,
            linear_damping_n_s_per_m: 50.0,
            flexion_limit_deg: 19.0,
            extension_limit_deg: 85.0,
            lateral_bending_limit_deg: 70.0,
            axial_rotation_limit_deg: 110.0,
            end_range_stiffness_nm_per_deg: 1.0,
            compression_limit_mm: 6.0,
            end_range_compression_n_per_m: 3.0e4,
            rest_attitude: NeckRest::Start,
        }
    }
}

/// The semi-implicit Euler stability limit of a spring `k` with a dashpot
/// `c` on a body of inverse mass `inverse_mass` (per kg, or per kg m^2 for
/// a rotation): omega^2 = k / m, zeta = c / (2 m omega).
fn damped_stable_step(k: f64, inverse_mass: f64, c: f64) -> f64 {
    let omega = (k * inverse_mass).sqrt();
    if omega == 0.0 {
        return f64::INFINITY;
    }
    semi_implicit_step_limit(omega, 0.5 * c * inverse_mass / omega)
}

/// Largest eigenvalue of a symmetric 3 x 3 matrix (parry's closed-form
/// symmetric eigensolver, as the rigid bodies' principal axes use).
fn largest_eigenvalue(a: DMat3) -> f64 {
    SymmetricEigen3::eigenvalues(a).max_element()
}

/// The longest stable rigid step of a joint ([`Neck::stable_step`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableStep {
    pub dt_s: f64,
    /// The [`NeckStiffness`] field that sets it: a spring's, or a damper's.
    pub limited_by: &'static str,
    /// That field's value.
    pub stiffness: f64,
}

impl StableStep {
    /// The limit of a spring of stiffness `k` (`spring` names its field
    /// and value) with a damper on a point of `inverse_mass`, set by the
    /// damper when it alone would allow a shorter step than the spring
    /// alone (2 / (c / m) below 2 / omega), by the spring otherwise.
    fn of(spring: (&'static str, f64), k: f64, damper: (&'static str, f64), inverse_mass: f64) -> StableStep {
        let (limited_by, stiffness) = match damper.1 * inverse_mass > (k * inverse_mass).sqrt() {
            true => damper,
            false => spring,
        };
        StableStep { dt_s: damped_stable_step(k, inverse_mass, damper.1), limited_by, stiffness }
    }
}

/// The head's anatomical axes in the head's body frame (CONVENTIONS.md):
/// o occipitofrontal, v vertex, b = v x o. Flexion (chin to chest) is a
/// positive rotation about b; lateral bending and axial rotation are taken
/// about the floating axis and the neck axis (see `JointAxes`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeadAxes {
    pub occipitofrontal: DVec3,
    pub vertex: DVec3,
}

impl HeadAxes {
    fn biparietal(&self) -> DVec3 {
        self.vertex.cross(self.occipitofrontal)
    }
}

/// Where the neck sits: the two bodies, the atlanto-occipital pivot
/// (world), the head's axes in its body frame, and the world direction of
/// the neck from the trunk towards the head (minus the trunk axis k of
/// CARDINAL_MOVEMENTS.md).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NeckGeometry {
    pub head: usize,
    pub trunk: usize,
    pub pivot: DVec3,
    pub axes: HeadAxes,
    pub neck_axis: DVec3,
    /// Flexion (positive) or extension of the head relative to the trunk
    /// in the joining pose, degrees from the anatomical neutral attitude:
    /// the range limits are measured from neutral, the springs from the
    /// joining pose.
    pub joined_flexion_deg: f64,
}

/// A neck joining body `head` and body `trunk` at the atlanto-occipital
/// pivot. Its rest state is the relative pose the two had when it was made.
/// Serializable: its rest pose is part of a run's checkpoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Neck {
    pub head: usize,
    pub trunk: usize,
    pub stiffness: NeckStiffness,
    pivot_in_head: DVec3,
    pivot_in_trunk: DVec3,
    axes: HeadAxes,
    /// Unit neck axis in the trunk frame, from the trunk towards the head
    /// (minus the trunk axis k of CARDINAL_MOVEMENTS.md).
    neck_axis_in_trunk: DVec3,
    /// Rest orientation of the head relative to the trunk.
    rest: DQuat,
    /// Flexion of the rest pose from the anatomical neutral attitude, rad.
    #[serde(default)]
    rest_flexion_rad: f64,
}

/// The neck's joint coordinate system, in the trunk frame at rest (Grood &
/// Suntay 1983, J. Biomech. Eng. 105:136, the convention of joint angles in
/// biomechanics): axial rotation about the neck axis, fixed in the trunk,
/// because the atlas turns on the axis (C1-C2) below the joint where the
/// head nods; flexion about the head's biparietal axis, fixed in the head
/// (the atlanto-occipital joint); lateral bending about the floating axis
/// perpendicular to both. So a flexed head turned on the spine, as in
/// internal rotation and restitution, meets the axial stiffness alone; a
/// rotation vector in the head's own axes would read that turn partly as
/// lateral bending once the head is flexed.
#[derive(Debug, Clone, Copy)]
struct JointAxes {
    lateral: DVec3,
    flexion: DVec3,
    axial: DVec3,
}

/// A turn of the head from rest as its three joint angles (rad), with the
/// axes they turn about in the present pose (trunk frame).
#[derive(Debug, Clone, Copy)]
struct JointAngles {
    lateral: f64,
    flexion: f64,
    axial: f64,
    axial_axis: DVec3,
    floating_axis: DVec3,
    biparietal_axis: DVec3,
}

impl JointAngles {
    /// Splits `turn` (trunk frame) as axial, then lateral, then flexion:
    /// `turn = R(axial) R(floating) R(biparietal)`.
    fn of(turn: DQuat, axes: JointAxes) -> Self {
        let JointAxes { lateral: x, flexion: y, axial: z } = axes;
        let (tx, ty, tz) = (turn * x, turn * y, turn * z);
        let lateral = z.dot(ty).clamp(-1.0, 1.0).asin();
        let flexion = (-z.dot(tx)).atan2(z.dot(tz));
        let axial = (-x.dot(ty)).atan2(y.dot(ty));
        let floating_axis = axial.cos() * x + axial.sin() * y;
        JointAngles { lateral, flexion, axial, axial_axis: z, floating_axis, biparietal_axis: ty }
    }

    /// The moment on the head (trunk frame) whose power against the three
    /// angle rates is minus `torques` (lateral, flexion, axial) times those
    /// rates: the conservative moment of springs on the joint angles. The
    /// three axes are not orthogonal once the neck bends sideways, so it is
    /// built on their dual basis; that basis degenerates only at 90 degrees
    /// of lateral bending, far outside the neck's range.
    fn restoring_moment(&self, torques: DVec3) -> DVec3 {
        let (z, a, b) = (self.axial_axis, self.floating_axis, self.biparietal_axis);
        let det = z.dot(a.cross(b));
        let det = if det.abs() < 1e-9 { 1e-9_f64.copysign(det) } else { det };
        -(torques.z * a.cross(b) + torques.x * b.cross(z) + torques.y * z.cross(a)) / det
    }
}

/// The neck's angles from the pose it was joined in, degrees, in its joint
/// coordinate system (see `JointAxes`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NeckAngles {
    /// Flexion (positive) or extension (negative) about the head's
    /// biparietal axis.
    pub flexion_deg: f64,
    /// Lateral bending about the floating axis (o when the head is not
    /// turned).
    pub lateral_bending_deg: f64,
    /// Axial rotation (twist) about the neck axis: what internal rotation
    /// winds up and restitution undoes.
    pub axial_rotation_deg: f64,
}

/// The neck's state and what it does to the two bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeckLoad {
    pub on_head: Wrench,
    pub on_trunk: Wrench,
    pub angles: NeckAngles,
    /// Compression (positive) or stretch (negative) along the neck axis, m.
    pub compression_m: f64,
    /// Elastic moment the neck exerts on the head, world, N m.
    pub elastic_moment_on_head: DVec3,
}

impl Neck {
    /// Joins the head and the trunk of `geometry` as they are now in `state`.
    pub fn new(
        model: &RigidBodyModel,
        state: &RigidBodyState,
        geometry: NeckGeometry,
        stiffness: NeckStiffness,
    ) -> Result<Self, ContactError> {
        let NeckGeometry { head, trunk, pivot, axes, neck_axis, joined_flexion_deg } = geometry;
        for b in [head, trunk] {
            if b >= model.len() {
                return Err(ContactError::NoSuchBody { body: b, count: model.len() });
            }
        }
        for (name, value) in [
            ("flexion_nm_per_deg", stiffness.flexion_nm_per_deg),
            ("extension_nm_per_deg", stiffness.extension_nm_per_deg),
            ("lateral_bending_nm_per_deg", stiffness.lateral_bending_nm_per_deg),
            ("axial_rotation_nm_per_deg", stiffness.axial_rotation_nm_per_deg),
            ("compression_n_per_m", stiffness.compression_n_per_m),
            ("tension_n_per_m", stiffness.tension_n_per_m),
            ("shear_n_per_m", stiffness.shear_n_per_m),
            ("rotational_damping_nm_s_per_rad", stiffness.rotational_damping_nm_s_per_rad),
            ("linear_damping_n_s_per_m", stiffness.linear_damping_n_s_per_m),
            ("flexion_limit_deg", stiffness.flexion_limit_deg),
            ("extension_limit_deg", stiffness.extension_limit_deg),
            ("lateral_bending_limit_deg", stiffness.lateral_bending_limit_deg),
            ("axial_rotation_limit_deg", stiffness.axial_rotation_limit_deg),
            ("end_range_stiffness_nm_per_deg", stiffness.end_range_stiffness_nm_per_deg),
            ("compression_limit_mm", stiffness.compression_limit_mm),
            ("end_range_compression_n_per_m", stiffness.end_range_compression_n_per_m),
        ] {
            check_non_negative(name, value, true)?;
        }
        let o = axes.occipitofrontal.normalize_or_zero();
        let v = axes.vertex.normalize_or_zero();
        if o == DVec3::ZERO || v == DVec3::ZERO || o.dot(v).abs() > 1e-6 {
            return Err(ContactError::InvalidParameter {
                name: "head axes",
                value: o.dot(v),
                hint: "occipitofrontal and vertex axes must be non-zero and perpendicular",
            });
        }
        let axis = neck_axis.normalize_or_zero();
        if axis == DVec3::ZERO {
            return Err(ContactError::InvalidParameter { name: "neck_axis", value: 0.0, hint: "must be a non-zero direction" });
        }
        let axes = HeadAxes { occipitofrontal: o, vertex: v };
        let (qh, qt) = (state.orientation[head], state.orientation[trunk]);
        // Flexion turns the head about its own biparietal axis, so neutral
        // is the joining pose unflexed about it, in the head's frame.
        let joined = (qt.inverse() * qh).normalize();
        let (rest, rest_flexion_rad) = match stiffness.rest_attitude {
            NeckRest::Start => (joined, joined_flexion_deg.to_radians()),
            NeckRest::Neutral => {
                let unflex = DQuat::from_axis_angle(axes.biparietal().normalize(), -joined_flexion_deg.to_radians());
                ((joined * unflex).normalize(), 0.0)
            }
        };
        // The joint coordinate system needs the head's biparietal axis
        // across the neck: a head joined tipped more than 60 degrees onto
        // its side is not an anatomical pose.
        let along_neck = (qh * axes.biparietal()).dot(axis);
        if along_neck.abs() > 60f64.to_radians().sin() {
            return Err(ContactError::InvalidParameter {
                name: "head pose at the neck",
                value: along_neck,
                hint: "the biparietal axis lies along the neck; tilt the head less than 60 degrees sideways from the trunk",
            });
        }
        Ok(Neck {
            head,
            trunk,
            stiffness,
            pivot_in_head: state.pose(head).inverse_point(pivot),
            pivot_in_trunk: state.pose(trunk).inverse_point(pivot),
            axes,
            neck_axis_in_trunk: qt.inverse() * axis,
            rest,
            rest_flexion_rad,
        })
    }

    /// The joint coordinate system at rest, in the trunk frame.
    fn joint_axes(&self) -> JointAxes {
        let axial = self.neck_axis_in_trunk;
        let biparietal = self.rest * self.axes.biparietal();
        let flexion = (biparietal - biparietal.dot(axial) * axial).normalize_or_zero();
        JointAxes { lateral: flexion.cross(axial), flexion, axial }
    }

    /// The longest rigid step at which the joint's springs are stable with
    /// the bodies as they stand in `state`, and the stiffness that sets it.
    /// Each spring is taken on its own, as [`crate::ContactLaw::critical_time_step`]
    /// takes a contact (the semi-implicit Euler bound with its dashpot's
    /// damping): compression and tension on the pair's inverse mass at the
    /// pivot along the neck axis, shear on its largest value across it, and
    /// the stiffest rotational spring with its end of range about the axis
    /// the pair turns most easily about.
    pub fn stable_step(&self, model: &RigidBodyModel, state: &RigidBodyState) -> StableStep {
        let s = &self.stiffness;
        let (h, t) = (self.head, self.trunk);
        // Velocity of a body's point r from its centre per unit impulse
        // there: 1/m + [r]x^T I^-1 [r]x.
        let point_inverse_mass = |b: usize, in_body: DVec3| {
            let q = state.orientation[b];
            let r = q * in_body;
            let cross = DMat3::from_cols_array(&[0.0, r.z, -r.y, -r.z, 0.0, r.x, r.y, -r.x, 0.0]);
            DMat3::from_diagonal(DVec3::splat(1.0 / model.mass_kg[b]))
                + cross.transpose() * model.inverse_inertia_world(b, q) * cross
        };
        let w = point_inverse_mass(h, self.pivot_in_head) + point_inverse_mass(t, self.pivot_in_trunk);
        let axis = state.orientation[t] * self.neck_axis_in_trunk;
        let across = DMat3::IDENTITY - DMat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z);
        let along_inverse_mass = axis.dot(w * axis);
        let across_inverse_mass = largest_eigenvalue(across * w * across);
        let damper = ("linear_damping_n_s_per_m", s.linear_damping_n_s_per_m);
        // Past its limit the column's stop adds to the spring.
        let compression = match s.end_range_compression_n_per_m > s.compression_n_per_m {
            true => ("end_range_compression_n_per_m", s.end_range_compression_n_per_m),
            false => ("compression_n_per_m", s.compression_n_per_m),
        };
        let linear = [
            (compression, s.compression_n_per_m + s.end_range_compression_n_per_m, along_inverse_mass),
            (("tension_n_per_m", s.tension_n_per_m), s.tension_n_per_m, along_inverse_mass),
            (("shear_n_per_m", s.shear_n_per_m), s.shear_n_per_m, across_inverse_mass),
        ]
        .map(|(spring, k, inverse_mass)| StableStep::of(spring, k, damper, inverse_mass));

        let (name, k) = [
            ("flexion_nm_per_deg", s.flexion_nm_per_deg),
            ("extension_nm_per_deg", s.extension_nm_per_deg),
            ("lateral_bending_nm_per_deg", s.lateral_bending_nm_per_deg),
            ("axial_rotation_nm_per_deg", s.axial_rotation_nm_per_deg),
        ]
        .into_iter()
        .fold(("", 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let end_range = s.end_range_stiffness_nm_per_deg;
        let turning_inverse_inertia = largest_eigenvalue(
            model.inverse_inertia_world(h, state.orientation[h]) + model.inverse_inertia_world(t, state.orientation[t]),
        );
        // Past a limit the end-of-range spring adds to the joint's own.
        let spring = match end_range > k {
            true => ("end_range_stiffness_nm_per_deg", end_range),
            false => (name, k),
        };
        let rotational = StableStep::of(
            spring,
            (k + end_range) * 180.0 / std::f64::consts::PI,
            ("rotational_damping_nm_s_per_rad", s.rotational_damping_nm_s_per_rad),
            turning_inverse_inertia,
        );
        linear.into_iter().chain([rotational]).fold(
            StableStep { dt_s: f64::INFINITY, limited_by: "", stiffness: 0.0 },
            |a, b| if b.dt_s < a.dt_s { b } else { a },
        )
    }

    /// Spring and dashpot loads on both bodies at the current state.
    pub fn load(&self, model: &RigidBodyModel, state: &RigidBodyState) -> NeckLoad {
        let s = &self.stiffness;
        let (h, t) = (self.head, self.trunk);
        let (qh, qt) = (state.orientation[h], state.orientation[t]);

        // Rotation of the head away from rest, in the joint coordinate
        // system (see `JointAngles`), and the generalised torques of the
        // springs on its three angles.
        let turn = (qt.inverse() * qh * self.rest.inverse()).normalize();
        let angles = JointAngles::of(turn, self.joint_axes());
        let per_rad = 180.0 / std::f64::consts::PI;
        let k_flex = if angles.flexion >= 0.0 { s.flexion_nm_per_deg } else { s.extension_nm_per_deg };
        // End of range, measured from the anatomical neutral attitude.
        let from_neutral = (angles.flexion + self.rest_flexion_rad) * per_rad;
        let beyond = (from_neutral - s.flexion_limit_deg).max(0.0) + (from_neutral + s.extension_limit_deg).min(0.0);
        // Sideways and twist, symmetric about the joining pose.
        let past = |angle_rad: f64, limit_deg: f64| (angle_rad.abs() * per_rad - limit_deg).max(0.0).copysign(angle_rad);
        let k_end = s.end_range_stiffness_nm_per_deg;
        let torques = DVec3::new(
            per_rad * s.lateral_bending_nm_per_deg * angles.lateral
                + k_end * past(angles.lateral, s.lateral_bending_limit_deg),
            per_rad * k_flex * angles.flexion + k_end * beyond,
            per_rad * s.axial_rotation_nm_per_deg * angles.axial + k_end * past(angles.axial, s.axial_rotation_limit_deg),
        );
        let elastic = qt * angles.restoring_moment(torques);
        let relative_spin = state.angular_velocity(model, h) - state.angular_velocity(model, t);
        let moment_on_head = elastic - s.rotational_damping_nm_s_per_rad * relative_spin;

        // Linear spring between the two bodies' copies of the pivot.
        let on_head_point = state.pose(h).point(self.pivot_in_head);
        let on_trunk_point = state.pose(t).point(self.pivot_in_trunk);
        let axis = qt * self.neck_axis_in_trunk;
        let gap = on_trunk_point - on_head_point;
        let compression = gap.dot(axis);
        let k_axial = if compression >= 0.0 { s.compression_n_per_m } else { s.tension_n_per_m };
        let bottomed = (compression - 1e-3 * s.compression_limit_mm).max(0.0);
        let axial = k_axial * compression + s.end_range_compression_n_per_m * bottomed;
        let shear = gap - compression * axis;
        let relative_velocity = state.point_velocity(model, t, on_trunk_point) - state.point_velocity(model, h, on_head_point);
        let on_trunk = -axial * axis - s.shear_n_per_m * shear - s.linear_damping_n_s_per_m * relative_velocity;

        let head_wrench = Wrench::at_point(-on_trunk, on_head_point, state.position[h])
            + Wrench { force: DVec3::ZERO, torque: moment_on_head };
        let trunk_wrench = Wrench::at_point(on_trunk, on_trunk_point, state.position[t])
            + Wrench { force: DVec3::ZERO, torque: -moment_on_head };
        NeckLoad {
            on_head: head_wrench,
            on_trunk: trunk_wrench,
            angles: NeckAngles {
                flexion_deg: angles.flexion * per_rad,
                lateral_bending_deg: angles.lateral * per_rad,
                axial_rotation_deg: angles.axial * per_rad,
            },
            compression_m: compression,
            elastic_moment_on_head: elastic,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid::{MassProperties, RigidPose};

    /// Head above trunk along z, pivot between them, head axes o = +y, v = +z.
    fn setup() -> (RigidBodyModel, RigidBodyState, Neck) {
        let mut model = RigidBodyModel::default();
        let props = |m: f64| MassProperties { mass_kg: m, inertia_kg_m2: DMat3::from_diagonal(DVec3::splat(1e-3)), rotation_locked: false };
        let head = model.add(props(0.6)).unwrap();
        let trunk = model.add(props(2.5)).unwrap();
        let state = RigidBodyState::at_rest(
            &model,
            &[RigidPose::new(DVec3::new(0.0, 0.0, 0.05), DQuat::IDENTITY), RigidPose::new(DVec3::new(0.0, 0.0, -0.1), DQuat::IDENTITY)],
        )
        .unwrap();
        let axes = HeadAxes { occipitofrontal: DVec3::Y, vertex: DVec3::Z };
        let geometry = NeckGeometry { head, trunk, pivot: DVec3::ZERO, axes, neck_axis: DVec3::Z, joined_flexion_deg: 0.0 };
        let neck = Neck::new(&model, &state, geometry, NeckStiffness::default()).unwrap();
        (model, state, neck)
    }

    /// Turns the head by `deg` about the world `axis` through the pivot.
    fn turn_head(state: &mut RigidBodyState, axis: DVec3, deg: f64) {
        let q = DQuat::from_axis_angle(axis, deg.to_radians());
        state.orientation[0] = q * state.orientation[0];
        state.position[0] = q * state.position[0];
    }

    #[test]
    fn torque_angle_slopes_match_the_per_degree_stiffness() {
        let s = NeckStiffness::default();
        // b = v x o = z x y = -x: flexion is a positive turn about -x.
        let cases = [
            (-DVec3::X, 2.0, s.flexion_nm_per_deg),
            (-DVec3::X, -2.0, s.extension_nm_per_deg),
            (DVec3::Y, 2.0, s.lateral_bending_nm_per_deg),
            (DVec3::Y, -2.0, s.lateral_bending_nm_per_deg),
            (DVec3::Z, 2.0, s.axial_rotation_nm_per_deg),
        ];
        for (axis, deg, k) in cases {
            let (model, mut state, neck) = setup();
            turn_head(&mut state, axis, deg);
            let load = neck.load(&model, &state);
            let about_axis = load.elastic_moment_on_head.dot(axis);
            // Restoring, with slope k per degree.
            assert!((about_axis + k * deg).abs() < 1e-9 * k, "axis {axis} deg {deg}: {about_axis}");
            // The turn about the pivot leaves the pivot shared: no linear force.
            assert!(load.on_head.force.length() < 1e-9);
            // Equal and opposite moments about the pivot (action-reaction).
            let total = load.on_head.torque + load.on_trunk.torque;
            assert!(total.length() < 1e-12);
        }
        // Asymmetry: extension is four times as stiff as flexion.
        let (model, mut state, neck) = setup();
        turn_head(&mut state, -DVec3::X, 5.0);
        let flex = neck.load(&model, &state);
        assert!((flex.angles.flexion_deg - 5.0).abs() < 1e-9);
        let (model2, mut state2, neck2) = setup();
        turn_head(&mut state2, -DVec3::X, -5.0);
        let ext = neck2.load(&model2, &state2);
        let ratio = ext.elastic_moment_on_head.length() / flex.elastic_moment_on_head.length();
        assert!((ratio - 4.0).abs() < 1e-9, "ratio {ratio}");
    }

    #[test]
    fn the_neck_stiffens_beyond_its_range_of_motion() {
        let s = NeckStiffness::default();
        // b = -x: flexion is a positive turn about -x.
        let moment = |deg: f64| {
            let (model, mut state, neck) = setup();
            turn_head(&mut state, -DVec3::X, deg);
            neck.load(&model, &state).elastic_moment_on_head.dot(-DVec3::X)
        };
        // Inside the range: the linear spring alone.
        let inside = s.flexion_limit_deg - 4.0;
        assert!((moment(inside) + inside * s.flexion_nm_per_deg).abs() < 1e-9);
        assert!((moment(-80.0) - 80.0 * s.extension_nm_per_deg).abs() < 1e-9);
        // Beyond it: the end-range stiffness adds, from the limit on.
        let over = s.flexion_limit_deg + 4.0;
        let expected = -over * s.flexion_nm_per_deg - 4.0 * s.end_range_stiffness_nm_per_deg;
        assert!((moment(over) - expected).abs() < 1e-9, "{} vs {expected}", moment(over));
        let under = -(s.extension_limit_deg + 3.0);
        let expected = -under * s.extension_nm_per_deg + 3.0 * s.end_range_stiffness_nm_per_deg;
        assert!((moment(under) - expected).abs() < 1e-9);
        // The limits count from neutral, not from the joining pose: a neck
        // joined 80 degrees extended (a face presentation) meets its
        // extension limit after 5 more degrees.
        let (model, mut state, _) = setup();
        let axes = HeadAxes { occipitofrontal: DVec3::Y, vertex: DVec3::Z };
        let geometry = NeckGeometry { head: 0, trunk: 1, pivot: DVec3::ZERO, axes, neck_axis: DVec3::Z, joined_flexion_deg: -80.0 };
        let neck = Neck::new(&model, &state, geometry, s).unwrap();
        turn_head(&mut state, -DVec3::X, -7.0);
        let m = neck.load(&model, &state).elastic_moment_on_head.dot(-DVec3::X);
        let expected = 7.0 * s.extension_nm_per_deg + 2.0 * s.end_range_stiffness_nm_per_deg;
        assert!((m - expected).abs() < 1e-9, "{m} vs {expected}");
    }

    /// At rest at neutral, a neck joined 15 deg flexed reads 15 deg of
    /// flexion at once and pulls the head back by 15 x the flexion
    /// stiffness; at rest at the start it reads none.
    #[test]
    fn a_neck_at_rest_at_neutral_pulls_a_joined_flexion_back() {
        let s = NeckStiffness::default();
        let axes = HeadAxes { occipitofrontal: DVec3::Y, vertex: DVec3::Z };
        let geometry = NeckGeometry { head: 0, trunk: 1, pivot: DVec3::ZERO, axes, neck_axis: DVec3::Z, joined_flexion_deg: 15.0 };
        let (model, mut state, _) = setup();
        turn_head(&mut state, -DVec3::X, 15.0);
        let at = |rest_attitude| {
            let neck = Neck::new(&model, &state, geometry, NeckStiffness { rest_attitude, ..s }).unwrap();
            neck.load(&model, &state)
        };
        let start = at(NeckRest::Start);
        assert!(start.angles.flexion_deg.abs() < 1e-9 && start.elastic_moment_on_head.length() < 1e-12, "{start:?}");
        let neutral = at(NeckRest::Neutral);
        let a = neutral.angles;
        assert!((a.flexion_deg - 15.0).abs() < 1e-9 && a.lateral_bending_deg.abs() < 1e-9 && a.axial_rotation_deg.abs() < 1e-9, "{a:?}");
        // About the head's biparietal axis, turned about itself: -x still.
        let about_biparietal = neutral.elastic_moment_on_head.dot(-DVec3::X);
        assert!((about_biparietal + 15.0 * s.flexion_nm_per_deg).abs() < 1e-9, "{about_biparietal}");

        // Joined turned 40 deg on the spine as well, then flexed about its
        // own (turned) biparietal axis: neutral undoes the flexion alone,
        // so the joining pose reads 15 deg of flexion and nothing else.
        let (model, mut state, _) = setup();
        turn_head(&mut state, DVec3::Z, 40.0);
        let biparietal = DQuat::from_axis_angle(DVec3::Z, 40f64.to_radians()) * -DVec3::X;
        turn_head(&mut state, biparietal, 15.0);
        let neck = Neck::new(&model, &state, geometry, NeckStiffness { rest_attitude: NeckRest::Neutral, ..s }).unwrap();
        let a = neck.load(&model, &state).angles;
        assert!((a.flexion_deg - 15.0).abs() < 1e-9 && a.lateral_bending_deg.abs() < 1e-9 && a.axial_rotation_deg.abs() < 1e-9, "{a:?}");
    }

    #[test]
    fn the_neck_stiffens_beyond_its_sideways_and_twist_ranges() {
        let s = NeckStiffness::default();
        // About the floating axis (y at rest) and the neck axis (z), either way.
        let cases = [
            (DVec3::Y, s.lateral_bending_limit_deg, s.lateral_bending_nm_per_deg),
            (DVec3::Z, s.axial_rotation_limit_deg, s.axial_rotation_nm_per_deg),
        ];
        for (axis, limit, k) in cases {
            for side in [1.0, -1.0] {
                let moment = |deg: f64| {
                    let (model, mut state, neck) = setup();
                    turn_head(&mut state, axis, side * deg);
                    neck.load(&model, &state).elastic_moment_on_head.dot(axis)
                };
                let inside = limit - 5.0;
                assert!((moment(inside) + side * inside * k).abs() < 1e-9, "{axis} {side}: inside");
                let over = limit + 3.0;
                let expected = -side * (over * k + 3.0 * s.end_range_stiffness_nm_per_deg);
                assert!((moment(over) - expected).abs() < 1e-9, "{axis} {side}: {} vs {expected}", moment(over));
            }
        }
    }

    #[test]
    fn a_flexed_head_turned_on_the_spine_meets_the_axial_stiffness_alone() {
        let s = NeckStiffness::default();
        let (model, mut state, neck) = setup();
        // Chin towards the chest by 15 degrees (inside the range), then a
        // 20 degree turn about the trunk's neck axis (z), as in internal
        // rotation.
        turn_head(&mut state, -DVec3::X, 15.0);
        turn_head(&mut state, DVec3::Z, 20.0);
        let load = neck.load(&model, &state);
        let a = load.angles;
        assert!((a.flexion_deg - 15.0).abs() < 1e-9, "{a:?}");
        assert!(a.lateral_bending_deg.abs() < 1e-9, "{a:?}");
        assert!((a.axial_rotation_deg - 20.0).abs() < 1e-9, "{a:?}");
        let about_neck = load.elastic_moment_on_head.dot(DVec3::Z);
        assert!((about_neck + 20.0 * s.axial_rotation_nm_per_deg).abs() < 1e-9, "{about_neck}");
        // The flexion spring acts about the head's turned biparietal axis.
        let biparietal = DQuat::from_axis_angle(DVec3::Z, 20f64.to_radians()) * -DVec3::X;
        let about_biparietal = load.elastic_moment_on_head.dot(biparietal);
        assert!((about_biparietal + 15.0 * s.flexion_nm_per_deg).abs() < 1e-9, "{about_biparietal}");
    }

    #[test]
    fn a_head_joined_lying_on_its_side_is_refused() {
        let (model, mut state, _) = setup();
        // Tipped 70 degrees about o (lateral): b = -x swings towards the neck axis z.
        turn_head(&mut state, DVec3::Y, 70.0);
        let axes = HeadAxes { occipitofrontal: DVec3::Y, vertex: DVec3::Z };
        let geometry = NeckGeometry { head: 0, trunk: 1, pivot: DVec3::ZERO, axes, neck_axis: DVec3::Z, joined_flexion_deg: 0.0 };
        let err = Neck::new(&model, &state, geometry, NeckStiffness::default()).unwrap_err();
        assert!(err.to_string().contains("sideways"), "{err}");
    }

    /// Elastic energy of the neck's rotation springs inside their range.
    fn rotational_energy(load: &NeckLoad, s: &NeckStiffness) -> f64 {
        let load = load.angles;
        let k_flex = if load.flexion_deg >= 0.0 { s.flexion_nm_per_deg } else { s.extension_nm_per_deg };
        let per_rad = 180.0 / std::f64::consts::PI;
        0.5 * per_rad
            * (k_flex * load.flexion_deg.to_radians().powi(2)
                + s.lateral_bending_nm_per_deg * load.lateral_bending_deg.to_radians().powi(2)
                + s.axial_rotation_nm_per_deg * load.axial_rotation_deg.to_radians().powi(2))
    }

    proptest::proptest! {
        /// The moment is conservative: turning the head a little about any
        /// axis changes the springs' energy by minus the moment's work.
        #[test]
        fn the_moment_is_minus_the_gradient_of_the_spring_energy(
            flexion in 1.0f64..18.0,
            lateral in -40.0f64..40.0,
            axial in -80.0f64..80.0,
            ux in -1.0f64..1.0, uy in -1.0f64..1.0, uz in -1.0f64..1.0,
        ) {
            let u = DVec3::new(ux, uy, uz);
            proptest::prop_assume!(u.length() > 0.1);
            let u = u.normalize();
            let s = NeckStiffness::default();
            let (model, mut state, neck) = setup();
            turn_head(&mut state, -DVec3::X, flexion);
            turn_head(&mut state, DVec3::Y, lateral);
            turn_head(&mut state, DVec3::Z, axial);
            let load = neck.load(&model, &state);
            let h = 1e-4;
            let mut ahead = state.clone();
            turn_head(&mut ahead, u, h);
            let mut behind = state.clone();
            turn_head(&mut behind, u, -h);
            let slope = (rotational_energy(&neck.load(&model, &ahead), &s)
                - rotational_energy(&neck.load(&model, &behind), &s))
                / (2.0 * h.to_radians());
            let work_rate = load.elastic_moment_on_head.dot(u);
            proptest::prop_assert!((slope + work_rate).abs() < 1e-6, "slope {slope} moment {work_rate}");
        }
    }

    /// The step bound is sharp: a neck stepped just below it oscillates,
    /// just above it blows up.
    #[test]
    fn the_stable_step_is_where_the_neck_starts_to_blow_up() {
        let (model, state, mut neck) = setup();
        neck.stiffness.shear_n_per_m = 1e6;
        let limit = neck.stable_step(&model, &state);
        assert_eq!(limit.limited_by, "shear_n_per_m");
        // Head at (0, 0, 0.05), trunk at (0, 0, -0.1), pivot at the origin,
        // I = 1e-3: across the neck 1/0.6 + 0.05^2/1e-3 + 1/2.5 + 0.1^2/1e-3.
        let inverse_mass: f64 = 1.0 / 0.6 + 2.5 + 0.4 + 10.0;
        let omega = (1e6 * inverse_mass).sqrt();
        let zeta = 0.5 * neck.stiffness.linear_damping_n_s_per_m * inverse_mass / omega;
        assert!((limit.dt_s - 2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)).abs() < 1e-12);

        let largest_gap = |dt: f64| {
            let mut s = state.clone();
            s.position[0].x += 1e-4;
            let mut largest: f64 = 0.0;
            for _ in 0..2000 {
                let load = neck.load(&model, &s);
                s.step(&model, &[load.on_head, load.on_trunk], dt).unwrap();
                largest = largest.max(s.pose(0).point(neck.pivot_in_head).distance(s.pose(1).point(neck.pivot_in_trunk)));
            }
            largest
        };
        assert!(largest_gap(0.95 * limit.dt_s) < 2e-4);
        assert!(largest_gap(1.05 * limit.dt_s) > 1e-2);
    }

    #[test]
    fn the_largest_eigenvalue_of_a_turned_diagonal_is_its_largest_entry() {
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
        for d in [DVec3::new(3.0, 1.0, 2.0), DVec3::new(1.0, 1.0, 5.0), DVec3::new(2.0, 2.0, 2.0), DVec3::new(0.0, 4.0, 0.0)] {
            let r = DMat3::from_quat(q);
            let a = r * DMat3::from_diagonal(d) * r.transpose();
            assert!((largest_eigenvalue(a) - d.max_element()).abs() < 1e-12, "{d}");
        }
    }

    #[test]
    fn compression_and_tension_differ() {
        for (dz, k) in [(1e-3, 1064.5), (-1e-3, 3361.8)] {
            let (model, mut state, neck) = setup();
            // Trunk pushed towards the head (dz > 0): compression.
            state.position[1].z += dz;
            let load = neck.load(&model, &state);
            assert!((load.compression_m - dz).abs() < 1e-15);
            assert!((load.on_trunk.force.z + k * dz).abs() < 1e-9, "{:?}", load.on_trunk.force);
            assert!((load.on_head.force + load.on_trunk.force).length() < 1e-12);
        }
    }

    #[test]
    fn the_neck_bottoms_out_past_its_compression_limit() {
        let (model, mut state, neck) = setup();
        let s = neck.stiffness;
        let limit = 1e-3 * s.compression_limit_mm;
        // 2 mm past the limit: the spring over the whole shortening, the
        // stop over the 2 mm.
        state.position[1].z += limit + 2e-3;
        let load = neck.load(&model, &state);
        let expected = s.compression_n_per_m * (limit + 2e-3) + s.end_range_compression_n_per_m * 2e-3;
        assert!((load.on_trunk.force.z + expected).abs() < 1e-9, "{:?}", load.on_trunk.force);
        // The stop holds the largest push within 5 mm of the limit, where
        // the spring alone would let it through by 13 cm.
        let push = 140.0;
        let past = (push - s.compression_n_per_m * limit) / (s.compression_n_per_m + s.end_range_compression_n_per_m);
        assert!(past > 0.0 && past < 5e-3, "{past}");
        assert!(push / s.compression_n_per_m > 0.1);
        // Past the limit it adds to the spring in the stable step along the
        // neck (here with no stiffer spring across it or in turning).
        let (model, state, mut axial_only) = setup();
        axial_only.stiffness.shear_n_per_m = 0.0;
        axial_only.stiffness.end_range_stiffness_nm_per_deg = 0.0;
        let step = axial_only.stable_step(&model, &state);
        assert_eq!(step.limited_by, "end_range_compression_n_per_m");
        // The value named is the field's own, as the scenario gives it; the
        // step counts both springs.
        assert_eq!(step.stiffness, s.end_range_compression_n_per_m);
        axial_only.stiffness.end_range_compression_n_per_m = 0.0;
        assert!(axial_only.stable_step(&model, &state).dt_s > 2.0 * step.dt_s);
    }

    /// A damper that alone allows a shorter step than its spring is named
    /// as the limit, with its own value.
    #[test]
    fn a_damper_stronger_than_its_spring_sets_the_step() {
        let (model, state, mut neck) = setup();
        neck.stiffness.linear_damping_n_s_per_m *= 1e4;
        let step = neck.stable_step(&model, &state);
        assert_eq!((step.limited_by, step.stiffness), ("linear_damping_n_s_per_m", neck.stiffness.linear_damping_n_s_per_m));
        neck.stiffness.linear_damping_n_s_per_m = 0.0;
        neck.stiffness.rotational_damping_nm_s_per_rad *= 1e5;
        assert_eq!(neck.stable_step(&model, &state).limited_by, "rotational_damping_nm_s_per_rad");
    }

    #[test]
    fn relative_spin_is_damped() {
        let (model, mut state, neck) = setup();
        state.set_angular_velocity(&model, 0, DVec3::new(0.0, 0.0, 2.0));
        let load = neck.load(&model, &state);
        let c = NeckStiffness::default().rotational_damping_nm_s_per_rad;
        assert!((load.on_head.torque.z + 2.0 * c).abs() < 1e-12);
    }
}
