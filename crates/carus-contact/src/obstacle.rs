//! Contact of a rigid fetal body with a rigid obstacle: the bony pelvis,
//! a static collider in the pelvis frame (BVH built once), or another fetal
//! body, in its own frame (crate::pair). The body is a set of surface
//! samples in its frame. Each step every sample is projected on the
//! obstacle with a bounded search (broad phase: the BVH, pruned by the
//! search depth; narrow phase: the exact closest point, signed by the
//! pseudo-normal), and penetrating samples get the contact law's forces.

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::clearance::{Clearance, DEFAULT_SKIN_M};
use crate::collider::{SurfacePoint, TriangleCollider};
use crate::error::{check_non_negative, ContactError};
use crate::law::{ContactLaw, DESIGN_EXPULSION_FORCE_N, DESIGN_HEAD_RADIUS_M, DESIGN_PENETRATION_M};
use crate::rigid::{RigidPose, Wrench};
use crate::sampling::SurfaceSamples;

/// Names of pelvic regions (symphysis, sacrum, ischial spine, ...) and one
/// label per pelvis triangle, so a report can say what the fetus met.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionTable {
    pub names: Vec<String>,
    pub labels: Vec<u16>,
}

/// A rigid surface that bodies' samples are pressed against, in its own
/// frame: the bony pelvis (with its regions) in the pelvis frame, or the
/// fetal head in its centre-of-mass frame for the trunk's samples.
#[derive(Debug)]
pub struct RigidObstacle {
    surface: TriangleCollider,
    regions: Option<RegionTable>,
    search_depth_m: f64,
    skin_m: f64,
}

/// Default depth down to which penetration is searched, m: five times the
/// design penetration of the penalty law, so a sample is never lost at the
/// loads the law is sized for, while the bounded search stays cheap.
pub const DEFAULT_SEARCH_DEPTH_M: f64 = 5.0 * DESIGN_PENETRATION_M;

impl RigidObstacle {
    /// Builds the collider from a closed surface (metres, its own frame,
    /// outward normals) named `what` in errors, and optionally a region
    /// label per triangle.
    pub fn new(
        what: &'static str,
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
        regions: Option<RegionTable>,
    ) -> Result<Self, ContactError> {
        let surface = TriangleCollider::new(what, vertices, triangles)?;
        if let Some(table) = &regions {
            if table.labels.len() != triangles.len() {
                return Err(ContactError::RegionTableLength {
                    what,
                    labels: table.labels.len(),
                    triangles: triangles.len(),
                });
            }
            if let Some((triangle, &label)) =
                table.labels.iter().enumerate().find(|(_, &l)| l as usize >= table.names.len())
            {
                return Err(ContactError::RegionLabelOutOfRange { triangle, label, names: table.names.len() });
            }
        }
        Ok(RigidObstacle { surface, regions, search_depth_m: DEFAULT_SEARCH_DEPTH_M, skin_m: DEFAULT_SKIN_M })
    }

    /// Sets how deep below the surface a sample is still found, m, for a
    /// law as stiff as bone's; a softer law searches down to twice its own
    /// sink at the design load if that is deeper ([`obstacle_contacts`]).
    pub fn with_search_depth(mut self, depth_m: f64) -> Result<Self, ContactError> {
        self.search_depth_m = check_non_negative("search_depth_m", depth_m, false)?;
        Ok(self)
    }

    /// Sets the query skin, m: how far beyond the search depth a query
    /// looks, so that samples clear of the bone are skipped until they have
    /// moved that far (results are the same for any skin; only cost changes).
    pub fn with_skin(mut self, skin_m: f64) -> Result<Self, ContactError> {
        self.skin_m = check_non_negative("skin_m", skin_m, true)?;
        Ok(self)
    }

    pub fn surface(&self) -> &TriangleCollider {
        &self.surface
    }

    pub fn search_depth_m(&self) -> f64 {
        self.search_depth_m
    }

    /// Name of region `label`, when a region table was given.
    pub fn region_name(&self, label: u16) -> Option<&str> {
        self.regions.as_ref().and_then(|r| r.names.get(label as usize)).map(String::as_str)
    }

    fn region_of(&self, triangle: u32) -> Option<u16> {
        self.regions.as_ref().map(|r| r.labels[triangle as usize])
    }
}

/// Where a body is and how it moves (world = pelvis frame). The body frame's
/// origin is the centre of mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMotion {
    pub pose: RigidPose,
    pub linear_velocity: DVec3,
    pub angular_velocity: DVec3,
}

impl BodyMotion {
    /// A body standing still at `pose`.
    pub fn at_rest(pose: RigidPose) -> Self {
        BodyMotion { pose, linear_velocity: DVec3::ZERO, angular_velocity: DVec3::ZERO }
    }
}

/// What one body's contact remembers between steps: per sample, the anchor
/// of its friction stick spring on the obstacle (the obstacle's frame: the
/// pelvis frame for the pelvis; none when the sample is not in contact),
/// the side of the obstacle it pressed from, and how far it may move
/// before it must be queried again.
/// Serializable, so a checkpoint can resume a run bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyContactState {
    anchors: Vec<Option<DVec3>>,
    /// Per sample in contact, its contact normal at the last query: the
    /// side of the wall it came from. A soft law (the trunk's cover) sinks
    /// deeper than half a thin bone (the pubic rami, the iliac blade), where
    /// the nearest surface becomes the far face; the sample is still pushed
    /// back out of the side it came in by. Absent from a state saved before
    /// it was kept: none remembered, as at a fresh start.
    #[serde(default)]
    sides: Vec<Option<DVec3>>,
    /// Samples last found inside the obstacle deeper than the search band.
    too_deep: Vec<bool>,
    clearance: Clearance,
}

impl BodyContactState {
    pub fn new(samples: &SurfaceSamples) -> Self {
        BodyContactState {
            anchors: vec![None; samples.len()],
            sides: vec![None; samples.len()],
            too_deep: vec![false; samples.len()],
            clearance: Clearance::new(samples.len()),
        }
    }

    /// Number of samples currently in contact.
    pub fn active(&self) -> usize {
        self.anchors.iter().filter(|a| a.is_some()).count()
    }

    /// Number of samples the state is kept for (that of the body's
    /// [`SurfaceSamples`] it was made for): a saved state read back must
    /// match its body.
    /// `None` when its per-sample parts disagree in length (an edited save).
    pub fn sample_count(&self) -> Option<usize> {
        let n = self.anchors.len();
        let sides = self.sides.len() == n || self.sides.is_empty();
        (sides && self.too_deep.len() == n && self.clearance.len() == n).then_some(n)
    }
}

/// One penetrating sample and the forces on the body there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub sample: u32,
    /// The sample's position (on the body) in the obstacle's frame (the
    /// pelvis frame for the pelvis), m.
    pub body_point: DVec3,
    /// Closest point on the obstacle, m.
    pub obstacle_point: DVec3,
    /// The obstacle's outward normal, its frame (from the bone towards the fetus).
    pub normal: DVec3,
    /// Penetration depth, m (positive).
    pub depth: f64,
    pub triangle: u32,
    /// Pelvic region label of `triangle`, when a table was given.
    pub region: Option<u16>,
    pub normal_force: DVec3,
    pub friction_force: DVec3,
    pub sliding: bool,
}

impl Contact {
    /// Total force on the body at this contact, N.
    pub fn force(&self) -> DVec3 {
        self.normal_force + self.friction_force
    }

    /// Moment of this contact's force about `pivot`, N m: r x f with r from
    /// the pivot to the body point.
    pub fn moment_about(&self, pivot: DVec3) -> DVec3 {
        (self.body_point - pivot).cross(self.force())
    }
}

/// Every contact of one body this step, with totals.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactReport {
    pub contacts: Vec<Contact>,
    /// Total contact force on the body, N.
    pub force: DVec3,
    /// Total moment about the body's centre of mass, N m.
    pub torque_about_com: DVec3,
    /// The pivot the report was asked about (the atlanto-occipital point for the head).
    pub pivot: DVec3,
    /// Total moment about `pivot`, N m.
    pub moment_about_pivot: DVec3,
    /// Summed normal spring stiffness of the active contacts, N/m: the K of
    /// [`ContactLaw::critical_time_step`].
    pub normal_stiffness_n_per_m: f64,
    /// Samples inside the obstacle deeper than the search band (the
    /// obstacle's search depth, or twice the law's sink if deeper): they carry no
    /// force. Nonzero means the body tunnelled into the bone (a rigid step
    /// too long, or a load far beyond the one the stiffness was sized for):
    /// the loop should stop or shorten its step.
    pub too_deep: usize,
    /// Samples that were in contact at the last query and are now deeper
    /// than the search band: pressed through the contact's reach while it
    /// pushed back, so the body is passing into the obstacle. Unlike
    /// `too_deep`, it ignores samples that appear deep without having been
    /// in contact, which an open sheet's edge gives (a point beside the
    /// edge, behind the sheet's plane, reads as inside it).
    pub pushed_through: usize,
    /// The first of them: (sample, its depth in m, its obstacle region).
    pub first_pushed_through: Option<(u32, f64, Option<u16>)>,
    /// Deepest penetration among the contacts, m. A sample in contact keeps
    /// its side past half a thin wall's thickness (`BodyContactState`); one
    /// that first touches deeper than that is pushed out of the nearer face.
    pub deepest_m: f64,
}

impl ContactReport {
    /// The contact wrench about the centre of mass, for the rigid step.
    pub fn wrench(&self) -> Wrench {
        Wrench { force: self.force, torque: self.torque_about_com }
    }

    /// Total contact force per region label (index = label), N;
    /// `region_count` is the number of region names.
    pub fn force_by_region(&self, region_count: usize) -> Vec<DVec3> {
        let mut totals = vec![DVec3::ZERO; region_count];
        for c in &self.contacts {
            if let Some(r) = c.region.filter(|&r| (r as usize) < region_count) {
                totals[r as usize] += c.force();
            }
        }
        totals
    }

    /// The region carrying the largest normal force: what the body is
    /// pressed against (for an arrest report).
    pub fn main_region(&self, region_count: usize) -> Option<u16> {
        let mut normal = vec![0.0; region_count];
        for c in &self.contacts {
            if let Some(r) = c.region.filter(|&r| (r as usize) < region_count) {
                normal[r as usize] += c.normal_force.length();
            }
        }
        normal
            .iter()
            .enumerate()
            .filter(|(_, &f)| f > 0.0)
            .fold(None, |best: Option<(usize, f64)>, (i, &f)| match best {
                Some((_, g)) if g >= f => best,
                _ => Some((i, f)),
            })
            .map(|(i, _)| i as u16)
    }
}

/// Finds the contacts of a body's samples with the obstacle, applies the law
/// (updating the body's friction anchors) and sums forces and moments.
/// Samples that have not moved out of their clearance since their last
/// query are skipped (see the clearance module: exact). Deterministic: the
/// samples are queried in parallel but gathered and summed in sample order.
pub fn obstacle_contacts(
    obstacle: &RigidObstacle,
    law: &ContactLaw,
    samples: &SurfaceSamples,
    motion: &BodyMotion,
    pivot: DVec3,
    memory: &mut BodyContactState,
) -> Result<ContactReport, ContactError> {
    obstacle_contacts_by_region(obstacle, law, &[], samples, motion, pivot, memory)
}

/// As [`obstacle_contacts`], with a law of its own on some regions of the
/// obstacle (`region_laws`: region label and law; a ligament softer than
/// the bone around it), `law` on the rest.
pub fn obstacle_contacts_by_region(
    obstacle: &RigidObstacle,
    law: &ContactLaw,
    region_laws: &[(u16, ContactLaw)],
    samples: &SurfaceSamples,
    motion: &BodyMotion,
    pivot: DVec3,
    memory: &mut BodyContactState,
) -> Result<ContactReport, ContactError> {
    if memory.sample_count() != Some(samples.len()) {
        return Err(ContactError::LengthMismatch {
            what: "body contact state (anchors, depth flags and clearances, one of each per sample)",
            expected: samples.len(),
            got: [memory.anchors.len(), memory.too_deep.len(), memory.clearance.len()]
                .into_iter()
                .find(|&n| n != samples.len())
                .unwrap_or(samples.len()),
        });
    }
    if memory.sides.is_empty() {
        memory.sides = vec![None; samples.len()];
    }
    let com = motion.pose.position_m;
    let law_of = |region: Option<u16>| match region_laws {
        [] => law,
        _ => region_laws.iter().find(|(label, _)| Some(*label) == region).map_or(law, |(_, own)| own),
    };
    // A soft law (the trunk's cover, a ligament) sinks deeper than the bone
    // law the obstacle's depth is sized for: search down to twice the
    // softest one's sink at the design load, so its samples keep their force.
    let sink = std::iter::once(law)
        .chain(region_laws.iter().map(|(_, own)| own))
        .map(|l| l.design_penetration(DESIGN_HEAD_RADIUS_M, DESIGN_EXPULSION_FORCE_N))
        .fold(0.0, f64::max);
    let band = obstacle.search_depth_m.max(2.0 * sink);
    let searched = band + obstacle.skin_m;

    let memory_in = &*memory;
    // The samples the clearance cannot skip, found serially (a few
    // nanoseconds each); most samples are skipped in most steps.
    let due: Vec<(usize, DVec3)> = (0..samples.len())
        .map(|i| (i, motion.pose.point(samples.points[i])))
        .filter(|&(i, p)| !memory_in.clearance.is_clear(i, p))
        .collect();
    // Per sample queried: its index, where it is, what the query found, and
    // the contact with its new friction anchor.
    type Queried = (usize, DVec3, Option<SurfacePoint>, Option<(Contact, DVec3)>);
    let queried: Vec<Queried> = due
        .into_par_iter()
        // Queries are ~1 us: hand rayon chunks big enough to pay for a split.
        .with_min_len(32)
        .map(|(i, p)| {
            let found = match (obstacle.surface.closest_point(p, searched), memory_in.sides[i]) {
                // A covered sample (the trunk's) past the middle of a thin
                // wall it came in by `side`: back out that way, not on
                // through the far face; unless the faces are under two
                // design sinks apart (it is rounding a sharp edge) or the
                // way back is beyond the band (lost either way). The bone
                // law (the head's) never sinks to a wall's middle: pressed
                // that far, it is rounding an edge (an ischial spine's tip).
                (Some(h), Some(side)) if law.cover.is_some() && h.signed_distance < 0.0 && h.normal.dot(side) < 0.0 => {
                    match obstacle.surface.crossing_along(p, side, band) {
                        Some(back) if -(back.signed_distance + h.signed_distance) > 2.0 * DESIGN_PENETRATION_M => Some(back),
                        _ => Some(h),
                    }
                }
                (found, _) => found,
            };
            let Some(hit) = found.filter(|h| h.signed_distance < 0.0 && -h.signed_distance <= band) else {
                return (i, p, found, None);
            };
            let velocity = motion.linear_velocity + motion.angular_velocity.cross(p - com);
            let stretch = memory_in.anchors[i].map_or(DVec3::ZERO, |a| p - a);
            let region = obstacle.region_of(hit.triangle);
            let f = law_of(region).evaluate(samples.areas[i], -hit.signed_distance, hit.normal, velocity, stretch);
            let contact = Contact {
                sample: i as u32,
                body_point: p,
                obstacle_point: hit.point,
                normal: hit.normal,
                depth: -hit.signed_distance,
                triangle: hit.triangle,
                region,
                normal_force: f.normal,
                friction_force: f.friction,
                sliding: f.sliding,
            };
            (i, p, found, Some((contact, p - f.stretch)))
        })
        .collect();

    let mut report = ContactReport {
        contacts: Vec::new(),
        force: DVec3::ZERO,
        torque_about_com: DVec3::ZERO,
        pivot,
        moment_about_pivot: DVec3::ZERO,
        normal_stiffness_n_per_m: 0.0,
        too_deep: 0,
        pushed_through: 0,
        first_pushed_through: None,
        deepest_m: 0.0,
    };
    // A skipped sample was clear at its last query, so it has no anchor
    // and keeps its depth flag: having moved less than its depth beyond
    // the band, it is still that deep.
    for (i, p, found, contact) in queried {
        memory.clearance.record(i, p, found.as_ref(), band, searched);
        memory.too_deep[i] = found.is_some_and(|h| -h.signed_distance > band);
        if let Some(h) = found.filter(|_| memory.too_deep[i] && memory.anchors[i].is_some()) {
            report.pushed_through += 1;
            report.first_pushed_through
                .get_or_insert((i as u32, -h.signed_distance, obstacle.region_of(h.triangle)));
        }
        memory.anchors[i] = contact.as_ref().map(|(_, anchor)| *anchor);
        memory.sides[i] = contact.as_ref().map(|(c, _)| c.normal);
        if let Some((c, _)) = contact {
            report.force += c.force();
            report.torque_about_com += (c.body_point - com).cross(c.force());
            report.moment_about_pivot += c.moment_about(pivot);
            report.normal_stiffness_n_per_m += law_of(c.region).stiffness_at(c.depth) * samples.areas[i];
            report.deepest_m = report.deepest_m.max(c.depth);
            report.contacts.push(c);
        }
    }
    report.too_deep = memory.too_deep.iter().filter(|&&deep| deep).count();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collider::tests::uv_sphere;
    use crate::rigid::{MassProperties, RigidBodyModel, RigidBodyState};
    use glam::{DMat3, DQuat};

    const G: f64 = 9.81;

    /// A 10 m square plane through the origin, tilted by `tilt` about x,
    /// outward normal up the tilted z, with two region labels.
    fn plane(tilt: DQuat) -> RigidObstacle {
        let v: Vec<DVec3> = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]
            .map(|(x, y)| tilt * DVec3::new(x, y, 0.0))
            .to_vec();
        let regions = RegionTable { names: vec!["sacrum".into(), "symphysis".into()], labels: vec![0, 1] };
        RigidObstacle::new("pelvis", &v, &[[0, 1, 2], [0, 2, 3]], Some(regions)).unwrap()
    }

    struct Slope {
        law: ContactLaw,
        tilt: DQuat,
        pelvis: RigidObstacle,
        samples: SurfaceSamples,
        model: RigidBodyModel,
        state: RigidBodyState,
        anchors: BodyContactState,
        /// Where the body started and how long it has run.
        start: DVec3,
        time: f64,
    }

    /// A 5 cm, 1 kg sphere resting on the plane tilted by `angle_deg`, its
    /// rotation locked (the reference g (sin a - mu cos a) is that of a
    /// sliding block; a free sphere would roll), its bottom pole sunk to the
    /// surface (the load is eased in by `Slope::run`).
    fn slope(angle_deg: f64, mu: f64) -> Slope {
        let law = ContactLaw { friction_coefficient: mu, ..ContactLaw::default() };
        let tilt = DQuat::from_rotation_x(angle_deg.to_radians());
        let (r, m) = (0.05, 1.0);
        let (v, t) = uv_sphere(r, 12, 24);
        let samples = SurfaceSamples::from_vertices("sphere", &v, &t).unwrap();
        let mut model = RigidBodyModel::default();
        model
            .add(MassProperties { mass_kg: m, inertia_kg_m2: DMat3::from_diagonal(DVec3::splat(0.4 * m * r * r)), rotation_locked: true })
            .unwrap();
        let state = RigidBodyState::at_rest(&model, &[RigidPose::new(tilt * DVec3::new(0.0, 0.0, r), tilt)]).unwrap();
        let anchors = BodyContactState::new(&samples);
        let start = state.position[0];
        Slope { law, tilt, pelvis: plane(tilt), samples, model, state, anchors, start, time: 0.0 }
    }

    impl Slope {
        fn downhill(&self) -> DVec3 {
            let n = self.tilt * DVec3::Z;
            let g = DVec3::new(0.0, 0.0, -G);
            (g - n * g.dot(n)).normalize()
        }

        /// Runs on for `duration` s at step `dt`; returns (t, downhill
        /// displacement from the start) per step. Gravity is eased in over
        /// the first 0.1 s (smoothstep), as a body is set down gently, then held.
        fn run(&mut self, duration: f64, dt: f64) -> Vec<(f64, f64)> {
            let down = self.downhill();
            let steps = (duration / dt).round() as usize;
            let mut track = Vec::with_capacity(steps);
            for k in 0..steps {
                let motion = BodyMotion {
                    pose: self.state.pose(0),
                    linear_velocity: self.state.linear_velocity[0],
                    angular_velocity: self.state.angular_velocity(&self.model, 0),
                };
                let report = obstacle_contacts(&self.pelvis, &self.law, &self.samples, &motion, motion.pose.position_m, &mut self.anchors).unwrap();
                let ease = ((self.time + k as f64 * dt) / 0.1).min(1.0);
                let weight = G * self.model.mass_kg[0] * ease * ease * (3.0 - 2.0 * ease);
                let gravity = Wrench { force: DVec3::new(0.0, 0.0, -weight), torque: DVec3::ZERO };
                self.state.step(&self.model, &[gravity + report.wrench()], dt).unwrap();
                track.push((self.time + (k + 1) as f64 * dt, (self.state.position[0] - self.start).dot(down)));
            }
            self.time += steps as f64 * dt;
            track
        }
    }

    /// Least-squares fit of x = x0 + v0 t + a t^2 / 2 over the samples with
    /// t >= `from`; returns a.
    fn fitted_acceleration(track: &[(f64, f64)], from: f64) -> f64 {
        let pts: Vec<(f64, f64)> = track.iter().copied().filter(|(t, _)| *t >= from).collect();
        // Normal equations for the basis (1, t, t^2).
        let mut m = [[0.0f64; 3]; 3];
        let mut rhs = [0.0f64; 3];
        for (t, x) in &pts {
            let b = [1.0, *t, t * t];
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += b[i] * b[j];
                }
                rhs[i] += b[i] * x;
            }
        }
        let mat = DMat3::from_cols_array_2d(&m).transpose();
        let c = mat.inverse() * DVec3::from_array(rhs);
        2.0 * c.z
    }

    const DT: f64 = 5e-4;

    #[test]
    fn c1_slides_above_the_friction_angle_with_the_coulomb_acceleration() {
        let mu: f64 = 0.35;
        let threshold = mu.atan().to_degrees(); // 19.29 deg
        for angle in [threshold + 2.0, 30.0, 45.0] {
            let mut s = slope(angle, mu);
            let track = s.run(1.0, DT);
            let a = fitted_acceleration(&track, 0.2);
            let rad = angle.to_radians();
            let expected = G * (rad.sin() - mu * rad.cos());
            let error = (a - expected).abs() / expected;
            eprintln!("C1 slide mu {mu} angle {angle:.2} deg: a {a:.5} m/s^2, expected {expected:.5} (relative error {:+.1e})", (a - expected) / expected);
            assert!(error < 0.02, "angle {angle:.2}: a = {a:.4}, expected {expected:.4} ({:.2} %)", 100.0 * error);
        }
    }

    #[test]
    fn c1_frictionless_slides_at_g_sin_a() {
        for angle in [5.0f64, 30.0] {
            let mut s = slope(angle, 0.0);
            let a = fitted_acceleration(&s.run(1.0, DT), 0.2);
            let expected = G * angle.to_radians().sin();
            eprintln!("C1 slide mu 0 angle {angle:.2} deg: a {a:.5} m/s^2, expected {expected:.5} (relative error {:+.1e})", (a - expected) / expected);
            assert!((a - expected).abs() / expected < 0.02, "angle {angle}: a = {a}, expected {expected}");
        }
    }

    #[test]
    fn c1_sticks_below_the_friction_angle() {
        let mu: f64 = 0.35;
        let threshold = mu.atan().to_degrees();
        for angle in [10.0, threshold - 2.0] {
            let mut s = slope(angle, mu);
            let track = s.run(1.0, DT);
            // Largest elastic stretch of the stick spring before it slips:
            // mu m g cos a / k_t. Sticking means the body never leaves that
            // elastic range and stops there.
            let k_t = s.law.tangential_stiffness_ratio * s.law.penalty_stiffness_pa_per_m * s.samples.areas[0];
            let stretch_cap = mu * G * angle.to_radians().cos() / k_t;
            let (_, end) = track[track.len() - 1];
            let (_, mid) = track[track.len() / 2];
            eprintln!("C1 stick mu {mu} angle {angle:.2} deg: displacement {end:.3e} m (elastic cap {stretch_cap:.3e} m), creep over the last 0.5 s {:.1e} m", end - mid);
            assert!(end.abs() < stretch_cap, "angle {angle:.2}: moved {end:e} m, cap {stretch_cap:e} m");
            assert!((end - mid).abs() < 1e-9, "angle {angle:.2}: still creeping ({:e} m in 0.5 s)", end - mid);
            assert!(s.anchors.active() == 1);
        }
    }

    /// A free solid sphere (I = 2/5 m r^2) on the slope: below
    /// tan a = 7/2 mu it rolls without slipping, the friction moment
    /// giving a = 5/7 g sin a; above, it slides while spinning up, its
    /// centre at g (sin a - mu cos a) and its spin at 5/2 mu g cos a / r.
    /// This checks friction moments and the rigid rotation together.
    #[test]
    fn free_sphere_rolls_or_slips_as_rigid_body_theory_says() {
        let mu: f64 = 0.35;
        for (angle, rolls) in [(15.0f64, true), (60.0, false)] {
            let (r, m) = (0.05, 1.0);
            let mut s = slope(angle, mu);
            // Fine meridians: the contact runs along the great circle through the poles.
            let (v, t) = uv_sphere(r, 48, 48);
            // The contact dashpot resists rolling (the compressing front of the
            // patch pushes harder than the releasing back): with the default
            // 1 ms the sphere, rolling at up to 1.8 m/s, lags theory by 6 %.
            // A tenth of it isolates the friction moment being checked.
            s.law.damping_time_s = 1e-4;
            s.samples = SurfaceSamples::from_vertices("sphere", &v, &t).unwrap();
            s.anchors = BodyContactState::new(&s.samples);
            s.model = RigidBodyModel::default();
            s.model
                .add(MassProperties { mass_kg: m, inertia_kg_m2: DMat3::from_diagonal(DVec3::splat(0.4 * m * r * r)), rotation_locked: false })
                .unwrap();
            let mut spin = Vec::new();
            let mut track = Vec::new();
            for _ in 0..10 {
                track.extend(s.run(0.1, DT));
                spin.push((s.time, s.state.angular_velocity(&s.model, 0).length()));
            }
            let a = fitted_acceleration(&track, 0.2);
            let rad = angle.to_radians();
            let (expected, expected_spin_rate) = if rolls {
                (5.0 / 7.0 * G * rad.sin(), 5.0 / 7.0 * G * rad.sin() / r)
            } else {
                (G * (rad.sin() - mu * rad.cos()), 2.5 * mu * G * rad.cos() / r)
            };
            let spin_rate = (spin[9].1 - spin[1].1) / (spin[9].0 - spin[1].0);
            eprintln!(
                "free sphere mu {mu} angle {angle} deg: a {a:.4} m/s^2 (theory {expected:.4}), spin-up {spin_rate:.2} rad/s^2 (theory {expected_spin_rate:.2})"
            );
            assert!((a / expected - 1.0).abs() < 0.02, "angle {angle}: a {a} vs {expected}");
            assert!((spin_rate / expected_spin_rate - 1.0).abs() < 0.02, "angle {angle}: spin-up {spin_rate} vs {expected_spin_rate}");
        }
    }

    /// A closed slab `thickness` thick under the plane z = 0 (2 m square),
    /// outward normals: a thin bone.
    fn slab(thickness: f64) -> RigidObstacle {
        let mut v = Vec::new();
        for z in [0.0, -thickness] {
            v.extend([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| DVec3::new(x, y, z)));
        }
        let t = [
            [0, 1, 2], [0, 2, 3], // top, facing +z
            [4, 6, 5], [4, 7, 6], // bottom, facing -z
            [0, 4, 5], [0, 5, 1], [1, 5, 6], [1, 6, 2], [2, 6, 7], [2, 7, 3], [3, 7, 4], [3, 4, 0],
        ];
        RigidObstacle::new("slab", &v, &t, None).unwrap()
    }

    /// A soft sample (the trunk's cover) pressed into a 4 mm wall from
    /// above is still pushed back up once past the wall's middle, where
    /// the nearest face is the underside; a sample first found there, with
    /// no side remembered, is pushed out of the nearer face.
    #[test]
    fn a_sample_past_the_middle_of_a_thin_wall_is_pushed_back_the_way_it_came() {
        let wall = slab(4e-3);
        let bone = ContactLaw::default();
        let law = ContactLaw {
            penalty_stiffness_pa_per_m: 1e7,
            cover: Some(crate::law::SoftCover { depth_m: 6e-3, core_stiffness_pa_per_m: bone.penalty_stiffness_pa_per_m }),
            ..bone
        };
        let samples = SurfaceSamples { points: vec![DVec3::ZERO], areas: vec![1e-4] };
        let at = |z: f64| BodyMotion::at_rest(RigidPose::new(DVec3::new(0.0, 0.0, z), DQuat::IDENTITY));
        let mut memory = BodyContactState::new(&samples);
        for (z, depth) in [(-1e-3, 1e-3), (-2.5e-3, 2.5e-3), (-3.5e-3, 3.5e-3), (-2e-3, 2e-3)] {
            let report = obstacle_contacts(&wall, &law, &samples, &at(z), DVec3::ZERO, &mut memory).unwrap();
            let c = report.contacts[0];
            assert!((c.normal - DVec3::Z).length() < 1e-12 && (c.depth - depth).abs() < 1e-12, "at {z}: {c:?}");
            assert!(report.force.z > 0.0 && (c.obstacle_point.z).abs() < 1e-12, "at {z}: {report:?}");
        }
        let mut fresh = BodyContactState::new(&samples);
        let report = obstacle_contacts(&wall, &law, &samples, &at(-3e-3), DVec3::ZERO, &mut fresh).unwrap();
        assert!(report.force.z < 0.0 && (report.contacts[0].depth - 1e-3).abs() < 1e-12, "{report:?}");
        // Let go, it forgets: found again below the middle, it leaves by the underside.
        let _ = obstacle_contacts(&wall, &law, &samples, &at(0.01), DVec3::ZERO, &mut memory).unwrap();
        let report = obstacle_contacts(&wall, &law, &samples, &at(-3e-3), DVec3::ZERO, &mut memory).unwrap();
        assert!(report.force.z < 0.0, "{report:?}");
        // The bone law (no cover) takes the nearer face, as it always did.
        let mut head = BodyContactState::new(&samples);
        for z in [-1e-3, -3e-3] {
            let report = obstacle_contacts(&wall, &bone, &samples, &at(z), DVec3::ZERO, &mut head).unwrap();
            assert_eq!(report.contacts[0].depth, 1e-3, "at {z}");
        }
    }

    #[test]
    fn moment_about_a_pivot_is_r_cross_f() {
        let pelvis = plane(DQuat::IDENTITY);
        let law = ContactLaw::default();
        // A square plate of four samples, 1 cm^2 each, sunk 0.5 mm.
        let samples = SurfaceSamples {
            points: vec![DVec3::new(-0.01, -0.01, 0.0), DVec3::new(0.01, -0.01, 0.0), DVec3::new(0.01, 0.01, 0.0), DVec3::new(-0.01, 0.01, 0.0)],
            areas: vec![1e-4; 4],
        };
        let motion = BodyMotion::at_rest(RigidPose::new(DVec3::new(0.0, 0.0, -5e-4), DQuat::IDENTITY));
        let e = 0.03;
        let pivot = DVec3::new(e, 0.0, 0.05);
        let mut anchors = BodyContactState::new(&samples);
        let report = obstacle_contacts(&pelvis, &law, &samples, &motion, pivot, &mut anchors).unwrap();
        assert_eq!(report.contacts.len(), 4);
        assert!((report.deepest_m - 5e-4).abs() < 1e-15);
        let f = 4.0 * law.penalty_stiffness_pa_per_m * 1e-4 * 5e-4;
        assert!((report.force - DVec3::new(0.0, 0.0, f)).length() < 1e-9 * f);
        // Centre of pressure under the centre of mass, pivot e to the side:
        // moment (centroid - pivot) x F = (0, e F, 0); none about the centre.
        assert!((report.moment_about_pivot - DVec3::new(0.0, e * f, 0.0)).length() < 1e-9 * f);
        assert!(report.torque_about_com.length() < 1e-9 * f);
        let summed: DVec3 = report.contacts.iter().map(|c| c.moment_about(pivot)).sum();
        assert!((summed - report.moment_about_pivot).length() < 1e-12);
        assert!((report.normal_stiffness_n_per_m - 4.0 * law.penalty_stiffness_pa_per_m * 1e-4).abs() < 1e-6);
        // The plate sits across both triangles of the plane: the diagonal
        // y = x splits it, samples 1 (x > y) on "sacrum", 3 on "symphysis".
        assert_eq!(report.contacts[1].region, Some(0));
        assert_eq!(report.contacts[3].region, Some(1));
        assert_eq!(pelvis.region_name(1), Some("symphysis"));
    }

    #[test]
    fn samples_deeper_than_the_search_depth_are_reported() {
        let pelvis = plane(DQuat::IDENTITY).with_search_depth(2e-3).unwrap();
        let law = ContactLaw::default();
        let samples = SurfaceSamples { points: vec![DVec3::new(0.1, 0.0, -1e-3), DVec3::new(-0.1, 0.0, -3e-3)], areas: vec![1e-4; 2] };
        let still = |z: f64| BodyMotion::at_rest(RigidPose::new(DVec3::new(0.0, 0.0, z), DQuat::IDENTITY));
        let mut memory = BodyContactState::new(&samples);
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(0.0), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((report.contacts.len(), report.too_deep), (1, 1));
        // Still flagged while skipped; cleared once it is back within the band.
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(1e-4), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!(report.too_deep, 1);
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(1.5e-3), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((report.contacts.len(), report.too_deep), (1, 0));
        // Found deep without having been in contact: not pushed through.
        assert_eq!(report.pushed_through, 0);
    }

    /// A sample in contact that is then carried past the search band has
    /// been pushed through the obstacle, and is reported as such, once.
    #[test]
    fn a_sample_carried_from_contact_past_the_band_is_pushed_through() {
        let pelvis = plane(DQuat::IDENTITY).with_search_depth(2e-3).unwrap();
        let law = ContactLaw::default();
        let samples = SurfaceSamples { points: vec![DVec3::new(0.1, 0.0, -1e-3)], areas: vec![1e-4] };
        let still = |z: f64| BodyMotion::at_rest(RigidPose::new(DVec3::new(0.0, 0.0, z), DQuat::IDENTITY));
        let mut memory = BodyContactState::new(&samples);
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(0.0), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((report.contacts.len(), report.pushed_through), (1, 0));
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(-1.5e-3), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((report.contacts.len(), report.too_deep, report.pushed_through), (0, 1, 1));
        let (sample, depth, region) = report.first_pushed_through.unwrap();
        assert_eq!((sample, region), (0, Some(0)));
        assert!((depth - 2.5e-3).abs() < 1e-12);
        // Deep and no longer in contact: not counted again.
        let report = obstacle_contacts(&pelvis, &law, &samples, &still(-1.6e-3), DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((report.too_deep, report.pushed_through), (1, 0));
    }

    #[test]
    fn main_region_is_the_one_pressed_hardest() {
        let pelvis = plane(DQuat::IDENTITY);
        let law = ContactLaw::default();
        // Deeper on the symphysis side (x < y), shallower on the sacrum side.
        let samples = SurfaceSamples {
            points: vec![DVec3::new(0.02, -0.02, 0.0), DVec3::new(-0.02, 0.02, -5e-4)],
            areas: vec![1e-4; 2],
        };
        let motion = BodyMotion::at_rest(RigidPose::new(DVec3::new(0.0, 0.0, -1e-4), DQuat::IDENTITY));
        let mut anchors = BodyContactState::new(&samples);
        let report = obstacle_contacts(&pelvis, &law, &samples, &motion, DVec3::ZERO, &mut anchors).unwrap();
        assert_eq!(report.main_region(2), Some(1));
        let by_region = report.force_by_region(2);
        assert!(by_region[1].z > by_region[0].z && by_region[0].z > 0.0);
    }

    /// A region with a law of its own (a ligament softer than the bone): at
    /// one depth its sample carries that law's force and stiffness, the
    /// rest the body's law; a depth the soft law sinks to at the design
    /// load is searched, where the bone's band would call it too deep.
    #[test]
    fn a_region_with_its_own_law_pushes_with_it() {
        let pelvis = plane(DQuat::IDENTITY);
        let law = ContactLaw::default();
        let soft = ContactLaw { penalty_stiffness_pa_per_m: 0.01 * law.penalty_stiffness_pa_per_m, ..law };
        // 1 mm deep over the sacrum (x > y) and over the symphysis (x < y).
        let samples = SurfaceSamples { points: vec![DVec3::new(0.02, -0.02, -1e-3), DVec3::new(-0.02, 0.02, -1e-3)], areas: vec![1e-4; 2] };
        let still = BodyMotion::at_rest(RigidPose::new(DVec3::ZERO, DQuat::IDENTITY));
        let press = |region_laws: &[(u16, ContactLaw)]| {
            let mut memory = BodyContactState::new(&samples);
            obstacle_contacts_by_region(&pelvis, &law, region_laws, &samples, &still, DVec3::ZERO, &mut memory).unwrap()
        };
        let (bone, softer) = (press(&[]), press(&[(1, soft)]));
        let (one, two) = (bone.force_by_region(2), softer.force_by_region(2));
        assert_eq!(one[0], two[0]);
        assert!((two[1].z / one[1].z - 0.01).abs() < 1e-12, "{} against {}", two[1].z, one[1].z);
        let k = |l: &ContactLaw| l.stiffness_at(1e-3) * 1e-4;
        assert!((softer.normal_stiffness_n_per_m - k(&law) - k(&soft)).abs() < 1e-9 * k(&law));
        // 8 mm deep over the symphysis: past the bone's band (5 mm), within the soft law's.
        let deep = SurfaceSamples { points: vec![DVec3::new(-0.02, 0.02, -8e-3)], areas: vec![1e-4] };
        let mut memory = BodyContactState::new(&deep);
        let bone = obstacle_contacts(&pelvis, &law, &deep, &still, DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((bone.contacts.len(), bone.too_deep), (0, 1));
        let mut memory = BodyContactState::new(&deep);
        let softer = obstacle_contacts_by_region(&pelvis, &law, &[(1, soft)], &deep, &still, DVec3::ZERO, &mut memory).unwrap();
        assert_eq!((softer.contacts.len(), softer.too_deep), (1, 0));
    }

    #[test]
    fn bad_region_tables_are_refused() {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let short = RegionTable { names: vec!["sacrum".into()], labels: vec![] };
        assert!(matches!(RigidObstacle::new("pelvis", &v, &[[0, 1, 2]], Some(short)), Err(ContactError::RegionTableLength { .. })));
        let unnamed = RegionTable { names: vec!["sacrum".into()], labels: vec![3] };
        assert!(matches!(
            RigidObstacle::new("pelvis", &v, &[[0, 1, 2]], Some(unnamed)),
            Err(ContactError::RegionLabelOutOfRange { triangle: 0, label: 3, names: 1 })
        ));
    }

    /// A spinning sphere (rotation free) dropped onto the slope: contacts
    /// come and go over many samples, friction turns the spin.
    fn tumble(skin: f64) -> (RigidBodyState, BodyContactState) {
        let mut s = slope(25.0, 0.35);
        s.pelvis = plane(s.tilt).with_skin(skin).unwrap();
        s.model = RigidBodyModel::default();
        s.model
            .add(MassProperties { mass_kg: 1.0, inertia_kg_m2: DMat3::from_diagonal(DVec3::new(1e-3, 1.2e-3, 0.9e-3)), rotation_locked: false })
            .unwrap();
        s.state.position[0] += s.tilt * DVec3::new(0.0, 0.0, 0.01);
        s.state.set_angular_velocity(&s.model, 0, DVec3::new(5.0, -3.0, 8.0));
        s.run(0.3, DT);
        (s.state, s.anchors)
    }

    fn bits(s: &RigidBodyState) -> Vec<u64> {
        s.position
            .iter()
            .chain(&s.linear_velocity)
            .chain(&s.angular_momentum)
            .flat_map(|v| v.to_array())
            .chain(s.orientation.iter().flat_map(|q| q.to_array()))
            .map(f64::to_bits)
            .collect()
    }

    #[test]
    fn runs_are_bit_identical() {
        let (a, b) = (tumble(DEFAULT_SKIN_M), tumble(DEFAULT_SKIN_M));
        assert_eq!(bits(&a.0), bits(&b.0));
        assert_eq!(a.1, b.1);
        // It did come down onto the plane and move.
        assert!(a.0.linear_velocity[0].length() > 0.1);
    }

    /// The clearance skin saves queries without changing any result.
    #[test]
    fn results_do_not_depend_on_the_skin() {
        let reference = tumble(0.0);
        for skin in [1e-3, 0.05] {
            let other = tumble(skin);
            assert_eq!(bits(&reference.0), bits(&other.0), "skin {skin}");
            assert_eq!(reference.1.anchors, other.1.anchors, "skin {skin}");
        }
    }
}
