//! Pose histories built by hand rather than by physics: the detector's test
//! cases, and demonstrations of what each movement looks like in the data.
//!
//! A history is planned in the canal's own terms: the head centre advances
//! along the pelvic axis (sigma, with a sinusoidal advance and a backward
//! drift between contractions), and theta, phi and the shoulders' angle are
//! smooth ramps over stretches of sigma. The trunk axis is kept along the
//! canal tangent at the head, so the planned phi is the measured phi.
//! Distances in the plans are in mm and angles in degrees, as clinicians
//! read them; the poses produced are SI.

use crate::canal::{BirthCanal, CanalPlanes};
use crate::history::{
    ContactSite, FetalPart, HeadGeometry, PoseHistory, PoseSample, RigidPose, TrunkGeometry,
};
use carus_anatomy::axis::Plane;
use glam::{DMat3, DQuat, DVec3};

const M_PER_MM: f64 = 1e-3;

/// A C-shaped canal with textbook proportions (synthetic fixture, not a
/// measured pelvis): inlet at the origin normal to z, then the planes of
/// greatest dimensions, spines and outlet 35, 65 and 95 mm lower, tilted
/// 15, 35 and 65 degrees forwards so the axis turns under the symphysis
/// (REFERENCE_DATA.md: the J-shaped path; outlet plane far steeper than
/// the inlet's). The spines lie about 66 mm and the outlet about 101 mm
/// along the axis.
pub fn reference_canal() -> BirthCanal {
    let tilted = |deg: f64| {
        let r = deg.to_radians();
        DVec3::new(0.0, r.sin(), -r.cos())
    };
    let planes = CanalPlanes {
        inlet: Plane {
            centre: DVec3::ZERO,
            normal: DVec3::NEG_Z,
        },
        greatest_dimensions: Plane {
            centre: DVec3::new(0.0, -0.004, -0.035),
            normal: tilted(15.0),
        },
        spines: Plane {
            centre: DVec3::new(0.0, 0.0, -0.065),
            normal: tilted(35.0),
        },
        outlet: Plane {
            centre: DVec3::new(0.0, 0.02, -0.095),
            normal: tilted(65.0),
        },
        right: DVec3::X,
    };
    BirthCanal::new(planes).expect("the reference planes are ordered and finite")
}

/// Semi-axes of the synthetic head (m): occipitofrontal 115 mm and
/// biparietal 95 mm (REFERENCE_DATA.md, term head), vertex height 100 mm.
const HEAD_SEMI_AXES_M: DVec3 = DVec3::new(0.0575, 0.0475, 0.05);

/// An ellipsoidal term head: body frame with o = +x, b = +y, v = +z and the
/// centre at the origin; 500 skull points spread evenly (Fibonacci lattice).
pub fn ellipsoid_head() -> HeadGeometry {
    let count = 500;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let skull_points_m = (0..count)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let angle = golden * i as f64;
            DVec3::new(r * angle.cos(), r * angle.sin(), z) * HEAD_SEMI_AXES_M
        })
        .collect();
    HeadGeometry {
        centre_m: DVec3::ZERO,
        occipitofrontal: DVec3::X,
        vertex: DVec3::Z,
        biparietal_mm: 2.0 * HEAD_SEMI_AXES_M.y / M_PER_MM,
        skull_points_m,
    }
}

/// The bisacromial midpoint's arc length behind the head centre (m); the
/// synthetic fetus keeps it on the axis.
const SHOULDERS_BEHIND_HEAD_M: f64 = 0.08;

/// A trunk with a 120 mm bisacromial diameter (REFERENCE_DATA.md), the
/// shoulders 70 mm from the trunk centre towards the head. Body frame:
/// +x the way the chest faces, +y the fetal left, +z towards the head.
pub fn simple_trunk() -> TrunkGeometry {
    TrunkGeometry {
        centre_m: DVec3::ZERO,
        right_acromion_m: DVec3::new(0.0, -0.06, 0.07),
        left_acromion_m: DVec3::new(0.0, 0.06, 0.07),
        spine: DVec3::NEG_Z,
    }
}

/// A smooth change of `by` over the head-centre sigma range `[from_mm, to_mm]`.
#[derive(Debug, Clone, Copy)]
pub struct Ramp {
    pub from_mm: f64,
    pub to_mm: f64,
    pub by: f64,
}

/// `initial` plus every ramp's share at head-centre sigma `sigma_mm`
/// (smoothstep inside a ramp, all of it past its end).
fn ramped(initial: f64, ramps: &[Ramp], sigma_mm: f64) -> f64 {
    initial
        + ramps
            .iter()
            .map(|r| {
                let u = ((sigma_mm - r.from_mm) / (r.to_mm - r.from_mm)).clamp(0.0, 1.0);
                r.by * u * u * (3.0 - 2.0 * u)
            })
            .sum::<f64>()
}

/// A planned run. The head centre's sigma is
/// `min(start + advance t, hold) - drift sin(2 pi t / period)` (mm), which
/// goes back between contractions when `drift * 2 pi / period > advance`
/// and only rocks once it is held; the
/// expulsion force along the spine is `force_mean - force_swing cos(2 pi t / period)`,
/// greatest when the head advances fastest.
#[derive(Debug, Clone)]
pub struct Plan {
    pub start_sigma_mm: f64,
    /// The run ends when the head centre first reaches this sigma...
    pub end_sigma_mm: f64,
    /// ...or at this time, whichever comes first.
    pub duration_s: f64,
    /// The head centre advances no further than this (an arrest).
    pub hold_sigma_mm: f64,
    pub advance_mm_per_s: f64,
    pub drift_mm: f64,
    pub period_s: f64,
    pub sample_interval_s: f64,
    pub force_mean_n: f64,
    pub force_swing_n: f64,
    pub theta_deg: f64,
    pub theta_ramps: Vec<Ramp>,
    pub phi_deg: f64,
    pub phi_ramps: Vec<Ramp>,
    /// Shoulders' angle on theta's scale and its ramps; `None`: no trunk.
    pub shoulders: Option<(f64, Vec<Ramp>)>,
    /// What the contact force presses on, recorded at every sample (on the
    /// head, or on the trunk once a plan with shoulders has the head out).
    pub contact: Option<ContactSite>,
}

impl Plan {
    fn sigma_mm(&self, t: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI / self.period_s;
        (self.start_sigma_mm + self.advance_mm_per_s * t).min(self.hold_sigma_mm)
            - self.drift_mm * (w * t).sin()
    }

    fn force_n(&self, t: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI / self.period_s;
        self.force_mean_n - self.force_swing_n * (w * t).cos()
    }

    /// Samples the plan with the synthetic ellipsoidal head and simple trunk.
    pub fn history(&self, canal: &BirthCanal) -> PoseHistory {
        self.history_with(canal, &ellipsoid_head(), &simple_trunk())
    }

    /// Samples the plan for the given head and trunk (body frames as in
    /// carus-anatomy: head x = o, y = b, z = v; trunk x ventral, y left,
    /// z towards the head) until the head centre first reaches
    /// `end_sigma_mm` or the time reaches `duration_s`. The trunk is
    /// recorded only when the plan has `shoulders`.
    pub fn history_with(
        &self,
        canal: &BirthCanal,
        head: &HeadGeometry,
        trunk: &TrunkGeometry,
    ) -> PoseHistory {
        let mut samples = Vec::new();
        for step in 0.. {
            let t = step as f64 * self.sample_interval_s;
            let sigma_mm = self.sigma_mm(t);
            samples.push(self.sample(canal, trunk, t, sigma_mm));
            if sigma_mm >= self.end_sigma_mm || t >= self.duration_s {
                break;
            }
        }
        PoseHistory {
            head: head.clone(),
            trunk: self.shoulders.as_ref().map(|_| trunk.clone()),
            canal: canal.clone(),
            samples,
        }
    }

    fn sample(
        &self,
        canal: &BirthCanal,
        body: &TrunkGeometry,
        t: f64,
        sigma_mm: f64,
    ) -> PoseSample {
        let axis = canal.axis();
        let sigma = sigma_mm * M_PER_MM;
        let frame = axis.frame(sigma);
        let theta = ramped(self.theta_deg, &self.theta_ramps, sigma_mm);
        let phi = ramped(self.phi_deg, &self.phi_ramps, sigma_mm);
        let head = RigidPose {
            position_m: axis.point(sigma),
            orientation: head_orientation(
                frame.tangent,
                frame.anterior,
                frame.transverse,
                theta,
                phi,
            ),
        };
        let trunk = self.shoulders.as_ref().map(|(initial, ramps)| {
            let back = ramped(*initial, ramps, sigma_mm).to_radians();
            let back = back.cos() * frame.anterior + back.sin() * frame.transverse;
            // Chest forwards (-back), fetal left = towards-head x chest, towards the head = t.
            let chest = -back;
            let left = frame.tangent.cross(chest);
            let orientation = DQuat::from_mat3(&DMat3::from_cols(chest, left, frame.tangent));
            let shoulders_body = 0.5 * (body.left_acromion_m + body.right_acromion_m);
            RigidPose {
                position_m: axis.point(sigma - SHOULDERS_BEHIND_HEAD_M)
                    - orientation * shoulders_body,
                orientation,
            }
        });
        // Spine k = -t; the force pushes along -k, down the canal.
        let force = self.force_n(t) * frame.tangent;
        let pressing = self.force_n(t).max(0.0);
        PoseSample {
            time_s: t,
            head,
            trunk,
            lower_trunk: None,
            expulsion_force_n: force,
            bone_contact_force_n: -0.6 * pressing * frame.tangent,
            floor_contact_force_n: -0.3 * pressing * frame.tangent,
            dominant_contact: self.contact,
            // Once the head is out, what the canal still holds is the trunk.
            dominant_part: self.contact.map(|_| match self.shoulders.is_some() && sigma > canal.outlet_sigma() {
                true => FetalPart::Trunk,
                false => FetalPart::Head,
            }),
        }
    }
}

/// Head orientation (body o = +x, b = +y, v = +z) for occiput position
/// `theta_deg` and attitude `phi_deg` relative to a trunk along `-tangent`:
/// the occiput points along `cos(theta) a + sin(theta) x`, the vertex down
/// the canal, then the head turns by phi about b (flexion positive).
pub fn head_orientation(
    tangent: DVec3,
    anterior: DVec3,
    transverse: DVec3,
    theta_deg: f64,
    phi_deg: f64,
) -> DQuat {
    let (theta, phi) = (theta_deg.to_radians(), phi_deg.to_radians());
    let o0 = -(theta.cos() * anterior + theta.sin() * transverse);
    let v0 = tangent;
    let b = v0.cross(o0);
    let v = v0 * phi.cos() + o0 * phi.sin();
    let o = o0 * phi.cos() - v0 * phi.sin();
    DQuat::from_mat3(&DMat3::from_cols(o, b, v)).normalize()
}

/// Head-centre sigma (mm) at which the leading point of a head in a
/// neutral attitude (vertex leading) is at `station_mm`: plans use it to
/// place their ramps at the stations the rules look at.
pub fn centre_sigma_at_station(canal: &BirthCanal, station_mm: f64) -> f64 {
    station_mm + canal.spines_sigma() / M_PER_MM - HEAD_SEMI_AXES_M.z / M_PER_MM
}

/// Contraction timing shared by the plans: 10 s period (time compressed
/// from the 150 s cycle of REFERENCE_DATA.md), 3 mm/s net advance with an
/// 8 mm sinusoidal swing, which drifts back about 4 mm between contractions.
fn contractions(start_sigma_mm: f64, end_sigma_mm: f64) -> Plan {
    Plan {
        start_sigma_mm,
        end_sigma_mm,
        duration_s: f64::INFINITY,
        hold_sigma_mm: f64::INFINITY,
        advance_mm_per_s: 3.0,
        drift_mm: 8.0,
        period_s: 10.0,
        sample_interval_s: 0.2,
        force_mean_n: 40.0,
        force_swing_n: 60.0,
        theta_deg: -90.0,
        theta_ramps: Vec::new(),
        phi_deg: 5.0,
        phi_ramps: Vec::new(),
        shoulders: None,
        contact: None,
    }
}

/// The textbook normal labour: head above the inlet in LOT, slightly
/// flexed (5 degrees); flexes to 30 degrees while entering the inlet,
/// engages, rotates to OA between stations 0 and +40 (the shoulders follow
/// half-way, to -45), extends by 70 degrees from station +35 until just
/// past the outlet, restitutes to -45 after delivery, then turns with the
/// shoulders to -90 (external rotation), and the trunk passes the outlet.
pub fn textbook(canal: &BirthCanal) -> PoseHistory {
    textbook_plan(canal).history(canal)
}

/// The plan of [`textbook`], to derive variants from (an arrest is the
/// same plan with `hold_sigma_mm` and `duration_s` set).
pub fn textbook_plan(canal: &BirthCanal) -> Plan {
    let outlet = canal.outlet_sigma() / M_PER_MM;
    let at_station = |s: f64| centre_sigma_at_station(canal, s);
    let mut plan = contractions(-60.0, outlet + 170.0);
    plan.phi_ramps = vec![
        Ramp {
            from_mm: -55.0,
            to_mm: -25.0,
            by: 25.0,
        },
        Ramp {
            from_mm: at_station(35.0),
            to_mm: outlet + 5.0,
            by: -70.0,
        },
    ];
    let rotation = (at_station(0.0), at_station(40.0));
    plan.theta_ramps = vec![
        Ramp {
            from_mm: rotation.0,
            to_mm: rotation.1,
            by: 90.0,
        },
        Ramp {
            from_mm: outlet + 10.0,
            to_mm: outlet + 30.0,
            by: -45.0,
        },
        Ramp {
            from_mm: outlet + 50.0,
            to_mm: outlet + 80.0,
            by: -45.0,
        },
    ];
    plan.shoulders = Some((
        -90.0,
        vec![
            Ramp {
                from_mm: rotation.0,
                to_mm: rotation.1,
                by: 45.0,
            },
            Ramp {
                from_mm: outlet + 50.0,
                to_mm: outlet + 80.0,
                by: -45.0,
            },
        ],
    ));
    plan.contact = Some(ContactSite::PelvicFloor);
    plan
}

/// A straight push: the head, LOT and 5 degrees flexed, is pushed straight
/// down the pelvis frame's -z from 60 mm above the inlet to 30 mm below
/// it, with no change of orientation and no trunk; the trunk axis comes
/// from the force. Only engagement and descent may be detected.
pub fn straight_push(canal: &BirthCanal) -> PoseHistory {
    let plan = contractions(-60.0, 30.0);
    let orientation = head_orientation(
        DVec3::NEG_Z,
        DVec3::Y,
        DVec3::X,
        plan.theta_deg,
        plan.phi_deg,
    );
    let head = ellipsoid_head();
    let mut samples = Vec::new();
    for step in 0.. {
        let t = step as f64 * plan.sample_interval_s;
        let depth_mm = plan.sigma_mm(t);
        let force = plan.force_n(t) * DVec3::NEG_Z;
        samples.push(PoseSample {
            time_s: t,
            head: RigidPose {
                position_m: DVec3::new(0.0, 0.0, -depth_mm * M_PER_MM),
                orientation,
            },
            trunk: None,
            lower_trunk: None,
            expulsion_force_n: force,
            bone_contact_force_n: 0.5 * plan.force_n(t).max(0.0) * DVec3::Z,
            floor_contact_force_n: DVec3::ZERO,
            dominant_contact: None,
            dominant_part: None,
        });
        if depth_mm >= plan.end_sigma_mm {
            break;
        }
    }
    PoseHistory {
        head,
        trunk: None,
        canal: canal.clone(),
        samples,
    }
}

/// Arrest above the inlet (as in a contracted inlet): the head, LOT, rocks
/// 5 mm up and down about a centre 35 mm above the inlet for ten
/// contractions without gaining ground, pressed against the symphysis.
pub fn inlet_arrest(canal: &BirthCanal) -> PoseHistory {
    let mut plan = contractions(-35.0, f64::INFINITY);
    plan.hold_sigma_mm = -35.0;
    plan.drift_mm = 5.0;
    plan.duration_s = 10.0 * plan.period_s;
    plan.contact = Some(ContactSite::Symphysis);
    plan.history(canal)
}

/// Shoulder arrest (large shoulders): the textbook labour held once the
/// head centre is 60 mm past the outlet, the head born and restituted but
/// the bisacromial midpoint still inside, rocking for five contractions
/// with the anterior shoulder against the symphysis.
pub fn shoulder_arrest(canal: &BirthCanal) -> PoseHistory {
    let mut plan = textbook_plan(canal);
    plan.hold_sigma_mm = canal.outlet_sigma() / M_PER_MM + 60.0;
    let reach_s = (plan.hold_sigma_mm - plan.start_sigma_mm) / plan.advance_mm_per_s;
    plan.duration_s = reach_s + 5.0 * plan.period_s;
    plan.contact = Some(ContactSite::Symphysis);
    plan.history(canal)
}

/// Rotation to direct occiput posterior: as the textbook labour up to the
/// mid-pelvis, but the occiput turns from LOT back to OP (-90 to -180)
/// between stations -10 and +30, and the run stops at station +40.
pub fn direct_occiput_posterior(canal: &BirthCanal) -> PoseHistory {
    let at_station = |s: f64| centre_sigma_at_station(canal, s);
    let mut plan = contractions(-60.0, at_station(40.0));
    plan.phi_ramps = vec![Ramp {
        from_mm: -55.0,
        to_mm: -25.0,
        by: 25.0,
    }];
    plan.theta_ramps = vec![Ramp {
        from_mm: at_station(-10.0),
        to_mm: at_station(30.0),
        by: -90.0,
    }];
    plan.history(canal)
}
