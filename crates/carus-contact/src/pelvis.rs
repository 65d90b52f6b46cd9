//! Contact of a rigid fetal body with the rigid bony pelvis: the pelvis is a
//! static collider in the pelvis frame (BVH built once); the body is a set
//! of surface samples in its frame. Each step every sample is projected on
//! the pelvis with a bounded search (broad phase: the BVH, pruned by the
//! search depth; narrow phase: the exact closest point, signed by the
//! pseudo-normal), and penetrating samples get the contact law's forces.

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::collider::TriangleCollider;
use crate::error::{check_non_negative, ContactError};
use crate::law::{ContactLaw, DESIGN_PENETRATION_M};
use crate::rigid::{RigidPose, Wrench};
use crate::sampling::SurfaceSamples;

/// Names of pelvic regions (symphysis, sacrum, ischial spine, ...) and one
/// label per pelvis triangle, so a report can say what the fetus met.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionTable {
    pub names: Vec<String>,
    pub labels: Vec<u16>,
}

/// The bony pelvis as a contact obstacle, in the pelvis frame.
#[derive(Debug)]
pub struct PelvisCollider {
    surface: TriangleCollider,
    regions: Option<RegionTable>,
    search_depth_m: f64,
}

/// Default depth down to which penetration is searched, m: five times the
/// design penetration of the penalty law, so a sample is never lost at the
/// loads the law is sized for, while the bounded search stays cheap.
pub const DEFAULT_SEARCH_DEPTH_M: f64 = 5.0 * DESIGN_PENETRATION_M;

impl PelvisCollider {
    /// Builds the collider from the bony surface (metres, pelvis frame,
    /// outward normals) and optionally a region label per triangle.
    pub fn new(
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
        regions: Option<RegionTable>,
    ) -> Result<Self, ContactError> {
        let surface = TriangleCollider::new("pelvis", vertices, triangles)?;
        if let Some(table) = &regions {
            if table.labels.len() != triangles.len() {
                return Err(ContactError::RegionTableLength {
                    what: "pelvis",
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
        Ok(PelvisCollider { surface, regions, search_depth_m: DEFAULT_SEARCH_DEPTH_M })
    }

    /// Sets how deep below the bone surface a sample is still found, m.
    pub fn with_search_depth(mut self, depth_m: f64) -> Result<Self, ContactError> {
        self.search_depth_m = check_non_negative("search_depth_m", depth_m, false)?;
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

/// Friction memory of one body: per sample, the anchor of its stick spring
/// on the pelvis (pelvis frame), or none when the sample is not in contact.
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionAnchors {
    anchors: Vec<Option<DVec3>>,
}

impl FrictionAnchors {
    pub fn new(samples: &SurfaceSamples) -> Self {
        FrictionAnchors { anchors: vec![None; samples.len()] }
    }

    /// Number of samples currently in contact.
    pub fn active(&self) -> usize {
        self.anchors.iter().filter(|a| a.is_some()).count()
    }
}

/// One penetrating sample and the forces on the body there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub sample: u32,
    /// The sample's world position (on the body), m.
    pub body_point: DVec3,
    /// Closest point on the pelvis, m.
    pub pelvis_point: DVec3,
    /// Pelvis outward normal (from the bone towards the fetus).
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

/// Finds the contacts of a body's samples with the pelvis, applies the law
/// (updating the body's friction anchors) and sums forces and moments.
/// Deterministic: the samples are queried in parallel but gathered and
/// summed in sample order.
pub fn pelvis_contacts(
    pelvis: &PelvisCollider,
    law: &ContactLaw,
    samples: &SurfaceSamples,
    motion: &BodyMotion,
    pivot: DVec3,
    anchors: &mut FrictionAnchors,
) -> Result<ContactReport, ContactError> {
    if anchors.anchors.len() != samples.len() {
        return Err(ContactError::LengthMismatch {
            what: "friction anchors (one per sample)",
            expected: samples.len(),
            got: anchors.anchors.len(),
        });
    }
    let com = motion.pose.position;
    let band = pelvis.search_depth_m;

    // Broad phase for the whole body: its world bounds against the pelvis'.
    let world: Vec<DVec3> = samples.points.iter().map(|&p| motion.pose.transform_point(p)).collect();
    let (body_min, body_max) = world
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let (pelvis_min, pelvis_max) = pelvis.surface.bounds();
    let apart = (body_min - pelvis_max).max_element() > band || (pelvis_min - body_max).max_element() > band;

    let results: Vec<(Option<Contact>, Option<DVec3>)> = if apart {
        vec![(None, None); samples.len()]
    } else {
        (0..samples.len())
            .into_par_iter()
            .map(|i| {
                let p = world[i];
                let Some(hit) = pelvis.surface.closest_point(p, band).filter(|h| h.signed_distance < 0.0) else {
                    return (None, None);
                };
                let velocity = motion.linear_velocity + motion.angular_velocity.cross(p - com);
                let stretch = anchors.anchors[i].map_or(DVec3::ZERO, |a| p - a);
                let f = law.evaluate(samples.areas[i], -hit.signed_distance, hit.normal, velocity, stretch);
                let contact = Contact {
                    sample: i as u32,
                    body_point: p,
                    pelvis_point: hit.point,
                    normal: hit.normal,
                    depth: -hit.signed_distance,
                    triangle: hit.triangle,
                    region: pelvis.region_of(hit.triangle),
                    normal_force: f.normal,
                    friction_force: f.friction,
                    sliding: f.sliding,
                };
                (Some(contact), Some(p - f.stretch))
            })
            .collect()
    };

    let mut report = ContactReport {
        contacts: Vec::new(),
        force: DVec3::ZERO,
        torque_about_com: DVec3::ZERO,
        pivot,
        moment_about_pivot: DVec3::ZERO,
        normal_stiffness_n_per_m: 0.0,
    };
    for (i, (contact, anchor)) in results.into_iter().enumerate() {
        anchors.anchors[i] = anchor;
        if let Some(c) = contact {
            report.force += c.force();
            report.torque_about_com += (c.body_point - com).cross(c.force());
            report.moment_about_pivot += c.moment_about(pivot);
            report.normal_stiffness_n_per_m += law.penalty_stiffness_pa_per_m * samples.areas[i];
            report.contacts.push(c);
        }
    }
    Ok(report)
}
