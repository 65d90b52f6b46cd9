//! What the mother's tissues do to the fetus at a recorded instant: the
//! force each part of the canal (and the pelvic floor) puts on the head and
//! on the trunk, the moment it causes about the atlanto-occipital pivot, and
//! the moments that spin the head about the pelvic axis, which is what
//! turns theta (internal rotation, restitution).

use carus_analysis::ContactSite;
use carus_anatomy::axis::PelvicAxis;
use carus_contact::{ContactReport, NeckAngles, Wrench};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Which fetal body a load acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Body {
    Head,
    /// The whole trunk, or the thorax when the spine bends.
    Trunk,
    LowerTrunk,
}

impl Body {
    /// The body at rigid-body index `b` (crate::scene's HEAD, TRUNK, LOWER_TRUNK).
    pub fn of(b: usize) -> Body {
        match b {
            crate::scene::HEAD => Body::Head,
            crate::scene::TRUNK => Body::Trunk,
            _ => Body::LowerTrunk,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Body::Head => "head",
            Body::Trunk => "trunk",
            Body::LowerTrunk => "lower_trunk",
        }
    }
}

/// The sum of the contacts of one part of the mother on one fetal body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SiteLoad {
    pub body: Body,
    pub site: ContactSite,
    /// Contact points that carried load: bone samples in contact, or floor
    /// nodes held on the fetal surface.
    pub points: usize,
    /// Total force on the body, N.
    pub force_n: DVec3,
    /// The part of it that is Coulomb friction, N. Zero for the floor:
    /// with the default `coupling = "sliding"` its nodes slide on the
    /// fetal surface without friction, and with `"held"` they do not slip,
    /// so the floor's tangential force is not split out (docs/CONTACT.md).
    pub friction_force_n: DVec3,
    /// Moment of the force about the atlanto-occipital pivot, N m.
    pub moment_about_pivot_nm: DVec3,
    /// How hard the site presses, N: the sum of the sizes of its points'
    /// forces, where `force_n` lets pushes from opposite sides (the two
    /// spines, the two side walls) cancel. The floor's nodes are summed
    /// into one reaction, so for the floor it is that reaction's size.
    /// None in runs recorded before it was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressing_n: Option<f64>,
}

/// Moments on the head about the pelvic axis: the component along the
/// axis's tangent at the head (pointing down the canal) of each source's
/// moment about the head's centre of mass, N m. Positive turns theta up
/// (CARDINAL_MOVEMENTS.md: from LOT at -90 towards OA at 0).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AxialMoments {
    pub bone_nm: f64,
    pub floor_nm: f64,
    pub neck_nm: f64,
    /// The part of `neck_nm` that the force carried through the pivot
    /// gives (the push from the trunk, off the head's centre); the rest
    /// is the neck's bending and twisting springs and their damping.
    #[serde(default)]
    pub neck_push_nm: f64,
    /// The trunk's contact on the head (chin on chest, shoulders on the skull).
    #[serde(default)]
    pub trunk_nm: f64,
}

/// The loads at one recorded instant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoadSample {
    pub time_s: f64,
    /// One entry per body and site that carried load, head first.
    pub sites: Vec<SiteLoad>,
    pub head_axial: AxialMoments,
    /// The trunk's contact force on the head, N (zero without that contact).
    #[serde(default)]
    pub head_trunk_force_n: DVec3,
    /// The moment of that force about the atlanto-occipital pivot, N m,
    /// which places its line of action (none in runs recorded before it was).
    #[serde(default)]
    pub head_trunk_moment_about_pivot_nm: Option<DVec3>,
    /// The neck's force on the head, N, acting at the atlanto-occipital
    /// pivot: the trunk's push (or pull) passed on through the neck's
    /// springs and dampers (none without a trunk, and in runs recorded
    /// before it was).
    #[serde(default)]
    pub neck_force_n: Option<DVec3>,
    /// The neck's joint angles from its rest pose (none without a trunk).
    #[serde(default)]
    pub neck: Option<NeckAngles>,
    /// The thoracolumbar joint's angles from its rest pose, when the spine
    /// bends (flexion bends the thorax forwards).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spine: Option<NeckAngles>,
    /// What moved the head besides the physics: the hybrid's guide, or in
    /// imposed mode the force and moment it took to keep the head on its
    /// way-points (none in forward mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guide: Option<GuideLoad>,
}

/// A wrench on the head from outside the physics (crate::trajectory),
/// about the head's centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GuideLoad {
    pub force_n: DVec3,
    pub moment_nm: DVec3,
}

/// How hard the guide worked over a run (imposed and hybrid modes): the
/// magnitudes of its force and moment on the head, over the recorded
/// instants.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GuideSummary {
    pub peak_force_n: f64,
    pub mean_force_n: f64,
    pub peak_moment_nm: f64,
    pub mean_moment_nm: f64,
}

impl GuideSummary {
    /// None when no instant was guided (forward mode).
    pub fn of(loads: &[LoadSample]) -> Option<GuideSummary> {
        let guided: Vec<&GuideLoad> = loads.iter().filter_map(|l| l.guide.as_ref()).collect();
        if guided.is_empty() {
            return None;
        }
        let n = guided.len() as f64;
        let (forces, moments): (Vec<f64>, Vec<f64>) =
            guided.iter().map(|g| (g.force_n.length(), g.moment_nm.length())).unzip();
        Some(GuideSummary {
            peak_force_n: forces.iter().copied().fold(0.0, f64::max),
            mean_force_n: forces.iter().sum::<f64>() / n,
            peak_moment_nm: moments.iter().copied().fold(0.0, f64::max),
            mean_moment_nm: moments.iter().sum::<f64>() / n,
        })
    }
}

/// One body's bone contacts summed by site; `sites[label]` is the site of
/// the pelvis region `label`.
pub fn bone_loads(
    body: Body,
    report: &ContactReport,
    sites: &[ContactSite],
    pivot: DVec3,
) -> Vec<SiteLoad> {
    let mut out: Vec<SiteLoad> = Vec::new();
    for c in &report.contacts {
        let Some(site) = c.region.and_then(|r| sites.get(r as usize)).copied() else {
            continue;
        };
        let k = match out.iter().position(|l| l.site == site) {
            Some(k) => k,
            None => {
                out.push(SiteLoad {
                    body,
                    site,
                    points: 0,
                    force_n: DVec3::ZERO,
                    friction_force_n: DVec3::ZERO,
                    moment_about_pivot_nm: DVec3::ZERO,
                    pressing_n: Some(0.0),
                });
                out.len() - 1
            }
        };
        let l = &mut out[k];
        let force = c.force();
        l.points += 1;
        l.force_n += force;
        l.friction_force_n += c.friction_force;
        l.moment_about_pivot_nm += c.moment_about(pivot);
        l.pressing_n = l.pressing_n.map(|p| p + force.length());
    }
    out
}

/// The floor's reaction on one body (a wrench about its centre of mass
/// `com`) as a site load; `None` when the floor holds no node of it.
pub fn floor_load(
    body: Body,
    wrench: &Wrench,
    held_nodes: usize,
    com: DVec3,
    pivot: DVec3,
) -> Option<SiteLoad> {
    (held_nodes > 0).then(|| SiteLoad {
        body,
        site: ContactSite::PelvicFloor,
        points: held_nodes,
        force_n: wrench.force,
        friction_force_n: DVec3::ZERO,
        moment_about_pivot_nm: moment_about(wrench, com, pivot),
        pressing_n: Some(wrench.force.length()),
    })
}

/// The direction down the canal at the point of the pelvic axis nearest
/// `at`: the axis about which [`AxialMoments`] are taken.
pub fn down_the_canal(axis: &PelvicAxis, at: DVec3) -> DVec3 {
    axis.tangent(axis.project(at))
}

/// The moment about `point` of a wrench given about `com`.
pub fn moment_about(wrench: &Wrench, com: DVec3, point: DVec3) -> DVec3 {
    wrench.torque + (com - point).cross(wrench.force)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn vec3() -> impl Strategy<Value = DVec3> {
        prop::array::uniform3(-1.0f64..1.0).prop_map(DVec3::from_array)
    }

    proptest! {
        /// Moving the reference point of a wrench agrees with taking the
        /// moment of its force applied at a point directly.
        #[test]
        fn the_moment_about_a_point_follows_the_force(
            f in vec3(), at in vec3(), com in vec3(), pivot in vec3()
        ) {
            let w = Wrench::at_point(f, at, com);
            let direct = (at - pivot).cross(f);
            prop_assert!((moment_about(&w, com, pivot) - direct).length() < 1e-12);
        }
    }

    /// Two spines pushing the head from opposite sides: their site's net
    /// force cancels, its pressing does not.
    #[test]
    fn a_site_s_pressing_adds_what_its_net_force_cancels() {
        let push = |x: f64| carus_contact::Contact {
            sample: 0,
            body_point: DVec3::new(x, 0.0, 0.0),
            obstacle_point: DVec3::new(x, 0.0, 0.0),
            normal: DVec3::new(-x.signum(), 0.0, 0.0),
            depth: 1e-4,
            triangle: 0,
            region: Some(0),
            normal_force: DVec3::new(-x.signum() * 40.0, 0.0, 0.0),
            friction_force: DVec3::new(0.0, 0.0, 3.0),
            sliding: false,
        };
        let report = ContactReport {
            contacts: vec![push(0.05), push(-0.05)],
            force: DVec3::ZERO,
            torque_about_com: DVec3::ZERO,
            pivot: DVec3::ZERO,
            moment_about_pivot: DVec3::ZERO,
            normal_stiffness_n_per_m: 0.0,
            too_deep: 0,
            pushed_through: 0,
            first_pushed_through: None,
            deepest_m: 1e-4,
        };
        let loads = bone_loads(Body::Head, &report, &[ContactSite::IschialSpines], DVec3::ZERO);
        assert_eq!((loads.len(), loads[0].points), (1, 2));
        assert!((loads[0].force_n - DVec3::new(0.0, 0.0, 6.0)).length() < 1e-12);
        let each = (40.0f64 * 40.0 + 3.0 * 3.0).sqrt();
        assert!((loads[0].pressing_n.unwrap() - 2.0 * each).abs() < 1e-12);
    }

    #[test]
    fn no_held_node_is_no_floor_load() {
        let w = Wrench {
            force: DVec3::X,
            torque: DVec3::ZERO,
        };
        assert!(floor_load(Body::Head, &w, 0, DVec3::ZERO, DVec3::ZERO).is_none());
        let l = floor_load(Body::Head, &w, 3, DVec3::ZERO, DVec3::Y).expect("held");
        assert_eq!(l.site, ContactSite::PelvicFloor);
        assert_eq!(l.points, 3);
        // A force along x applied 1 m below the pivot (in -y): moment along +z.
        assert!((l.moment_about_pivot_nm - DVec3::Z).length() < 1e-12);
    }
}
