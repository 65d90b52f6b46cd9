//! Forces on the fetus as arrows: what each part of the canal puts on each
//! fetal body (the sum of its contacts, drawn on its line of action), the
//! expulsion force, what the trunk puts on the head (through the neck, at
//! the atlanto-occipital pivot, and by touching it) and, in imposed and
//! hybrid runs, the guide's.
//!
//! A site's contacts add up to a force and a moment about the
//! atlanto-occipital pivot (`run.json`'s `loads`). Such a pair acts along
//! one line, its central axis (Poinsot), up to a couple about that line;
//! the arrow lies on that line and ends where the line enters the body it
//! pushes, so it points at the surface the force is applied to (or, for a
//! line that passes the body by, at the body's point nearest it).

use carus_analysis::{ContactSite, PoseHistory, RigidPose};
use carus_contact::{TriangleCollider, Wrench};
use carus_labour::loads::{moment_about, Body, LoadSample};
use carus_render::RenderMesh;
use carus_report::ReportScene;
use glam::DVec3;

use crate::ViewError;

pub use carus_report::pictures::ARROW_M_PER_N;
/// Forces smaller than this are not drawn, N: they would be shorter than
/// their own head.
pub const SMALLEST_DRAWN_N: f64 = 2.0;
/// Radius of an arrow's shaft, m.
const SHAFT_RADIUS_M: f32 = 1.5e-3;
/// The expulsion arrow's colour: mid grey, seen on the window's dark
/// background and on the report's white one alike.
pub const EXPULSION_RGB: [f32; 3] = [0.6, 0.6, 0.6];
/// The guide's (the teacher's hand) colour: magenta.
pub const GUIDE_RGB: [f32; 3] = [0.85, 0.1, 0.85];
/// The neck's force on the head (the trunk's push at the pivot): olive.
pub const NECK_RGB: [f32; 3] = [0.45, 0.5, 0.1];
/// The trunk's own surface on the head (chin on chest, shoulders on the
/// skull): dark teal.
pub const TRUNK_ON_HEAD_RGB: [f32; 3] = [0.0, 0.35, 0.35];

/// The colour of a site's arrows, one per part of the canal.
pub fn site_rgb(site: ContactSite) -> [f32; 3] {
    match site {
        ContactSite::Symphysis => [0.85, 0.15, 0.15],
        ContactSite::PubicArch => [0.95, 0.5, 0.05],
        ContactSite::SacralPromontory => [0.55, 0.25, 0.8],
        ContactSite::Sacrum => [0.15, 0.35, 0.9],
        ContactSite::Coccyx => [0.05, 0.7, 0.8],
        ContactSite::IschialSpines => [0.9, 0.8, 0.05],
        ContactSite::PelvicSidewall => [0.6, 0.38, 0.15],
        ContactSite::SacrospinousLigament => [0.95, 0.45, 0.7],
        ContactSite::AbdominalWall => [0.55, 0.75, 0.95],
        ContactSite::ObturatorMembrane => [0.75, 0.55, 0.95],
        ContactSite::PelvicFloor => [0.1, 0.6, 0.3],
    }
}

/// One force as drawn: its tip on the body's surface and its tail
/// `ARROW_M_PER_N` metres per newton behind.
#[derive(Debug, Clone, PartialEq)]
pub struct Arrow {
    /// What pushes, and on which body ("sacrum", "pelvic sidewall on the trunk").
    pub label: String,
    pub force_n: DVec3,
    /// Where the arrow ends, m (pelvis frame).
    pub tip_m: DVec3,
    pub rgb: [f32; 3],
}

impl Arrow {
    pub fn mesh(&self) -> RenderMesh {
        let tail = self.tip_m - ARROW_M_PER_N * self.force_n;
        RenderMesh::arrow(
            format!("force: {}", self.label),
            tail.as_vec3().to_array(),
            self.tip_m.as_vec3().to_array(),
            SHAFT_RADIUS_M,
            self.rgb,
        )
    }
}

/// A run's recorded loads, ready to be drawn at any pose sample.
pub struct Forces {
    loads: Vec<LoadSample>,
    /// The atlanto-occipital pivot in the head's body frame, m: the point
    /// the recorded moments are taken about.
    pivot_in_head_m: DVec3,
    /// Whether the expulsion force acts at the pivot (no trunk, or
    /// `expulsion.acts_on = "pivot"`) rather than on the trunk's centre.
    expulsion_at_pivot: bool,
    /// Head, trunk and lower trunk surfaces in their body frames.
    bodies: [Option<TriangleCollider>; 3],
}

impl Forces {
    /// The loads of a run whose surfaces are `scene`'s.
    pub fn new(
        loads: Vec<LoadSample>,
        pivot_in_head_m: DVec3,
        expulsion_at_pivot: bool,
        scene: &ReportScene,
    ) -> Result<Forces, ViewError> {
        let collider = |what, s: &carus_anatomy::TriSurface| TriangleCollider::new(what, &s.vertices, &s.triangles);
        Ok(Forces {
            loads,
            pivot_in_head_m,
            expulsion_at_pivot,
            bodies: [
                Some(collider("fetal head", &scene.head)?),
                scene.trunk.as_ref().map(|s| collider("fetal trunk", s)).transpose()?,
                scene.lower_trunk.as_ref().map(|s| collider("lower trunk", s)).transpose()?,
            ],
        })
    }

    /// The loads recorded at sample `k`'s time, or the last before it.
    fn load_at(&self, history: &PoseHistory, k: usize) -> Option<&LoadSample> {
        let t = history.samples[k].time_s;
        match self.loads.get(k) {
            Some(load) if load.time_s == t => Some(load),
            _ => self.loads[..self.loads.partition_point(|l| l.time_s <= t)].last(),
        }
    }

    /// The arrows of sample `k`: the expulsion, the guide, the neck and the
    /// trunk on the head, then each site on each body, those under
    /// `SMALLEST_DRAWN_N` left out.
    pub fn arrows(&self, history: &PoseHistory, k: usize) -> Vec<Arrow> {
        let sample = &history.samples[k];
        let pivot = sample.head.point(self.pivot_in_head_m);
        let pose = |body: Body| match body {
            Body::Head => Some(sample.head),
            Body::Trunk => sample.trunk,
            Body::LowerTrunk => sample.lower_trunk,
        };
        let mut arrows = Vec::new();
        let mut draw = |label: String, body: Body, force_n: DVec3, line_point: DVec3, rgb| {
            if force_n.length() < SMALLEST_DRAWN_N {
                return;
            }
            let (Some(pose), Some(surface)) = (pose(body), self.bodies[body as usize].as_ref()) else {
                return;
            };
            let tip_m = entry_point(surface, &pose, line_point, force_n);
            arrows.push(Arrow { label, force_n, tip_m, rgb });
        };
        // The push acts on the breech's body: the lower trunk when the spine bends.
        let breech = sample.lower_trunk.map(|p| (Body::LowerTrunk, p)).or(sample.trunk.map(|p| (Body::Trunk, p)));
        let expulsion_on = match (self.expulsion_at_pivot, breech) {
            (false, Some((body, pose))) => (body, pose.position_m),
            _ => (Body::Head, pivot),
        };
        draw("expulsion".into(), expulsion_on.0, sample.expulsion_force_n, expulsion_on.1, EXPULSION_RGB);
        let Some(load) = self.load_at(history, k) else {
            return arrows;
        };
        let head_centre = sample.head.position_m;
        if let Some(guide) = &load.guide {
            draw("guide".into(), Body::Head, guide.force_n, central_axis_point(guide.force_n, guide.moment_nm, head_centre), GUIDE_RGB);
        }
        // The fetus's own parts on the head: the trunk's push through the
        // neck, at the pivot, and the trunk's surface where it touches.
        if let Some(neck) = load.neck_force_n {
            draw("neck".into(), Body::Head, neck, pivot, NECK_RGB);
        }
        if let Some(about_pivot) = load.head_trunk_moment_about_pivot_nm {
            let force = load.head_trunk_force_n;
            let moment = about_centre(force, about_pivot, pivot, head_centre);
            draw("trunk on the head".into(), Body::Head, force, central_axis_point(force, moment, head_centre), TRUNK_ON_HEAD_RGB);
        }
        for site in &load.sites {
            let Some(centre) = pose(site.body).map(|p| p.position_m) else {
                continue;
            };
            let moment = about_centre(site.force_n, site.moment_about_pivot_nm, pivot, centre);
            let label = match site.body {
                Body::Head => site.site.name().replace('_', " "),
                body => format!("{} on the {}", site.site.name().replace('_', " "), body.name().replace('_', " ")),
            };
            draw(label, site.body, site.force_n, central_axis_point(site.force_n, moment, centre), site_rgb(site.site));
        }
        arrows
    }

    /// The forces drawn at sample `k` in words, largest first:
    /// "expulsion 96 N", "sacrum 31 N", ...
    pub fn readout(&self, history: &PoseHistory, k: usize) -> Vec<String> {
        let arrows = largest_first(self.arrows(history, k));
        if arrows.is_empty() {
            return vec![format!("no force of {SMALLEST_DRAWN_N} N or more")];
        }
        arrows.iter().map(|a| format!("{} {:.0} N", a.label, a.force_n.length())).collect()
    }
}

/// `arrows` ordered by the size of their forces, largest first, as they
/// are listed beside the pictures.
pub fn largest_first(mut arrows: Vec<Arrow>) -> Vec<Arrow> {
    arrows.sort_by(|a, b| b.force_n.length().total_cmp(&a.force_n.length()));
    arrows
}

/// The moment about a body's `centre` of a force whose moment about the
/// `pivot` is `about_pivot`.
fn about_centre(force: DVec3, about_pivot: DVec3, pivot: DVec3, centre: DVec3) -> DVec3 {
    moment_about(&Wrench { force, torque: about_pivot }, pivot, centre)
}

/// The point of a force's line of action nearest `centre`, for a force
/// `force` and moment `moment` about `centre`: centre + F x M / |F|^2.
fn central_axis_point(force: DVec3, moment: DVec3, centre: DVec3) -> DVec3 {
    centre + force.cross(moment) / force.length_squared()
}

/// Where the line through `point` along `force` enters the posed body; a
/// line that passes the body by (a large couple about a small force) ends
/// on the body's surface point nearest `point`.
fn entry_point(surface: &TriangleCollider, pose: &RigidPose, point: DVec3, force: DVec3) -> DVec3 {
    let to_body = pose.orientation.inverse();
    let local = to_body * (point - pose.position_m);
    let entry = surface
        .entry_point(local, to_body * force)
        .or_else(|| surface.closest_point(local, f64::MAX).map(|p| p.point))
        .unwrap_or(local);
    pose.point(entry)
}
