//! Rigid-soft coupling: a rigid fetal surface as a moving boundary of the
//! soft pelvic floor, by the partial Dirichlet-Neumann method of Lapeer et
//! al. 2019. Tissue nodes that penetrate the body are moved out onto its
//! surface (imposed displacements: the Dirichlet part); the tissue's
//! reactions on those nodes act back on the body (the Neumann part).
//!
//! Works on plain node arrays so it serves any solver: the labour loop
//! calls [`TissueContact::update`] with the node positions, imposes the
//! targets through the solver (carus-fem's `impose_displacements`, target
//! minus reference position), steps the tissue, reads the nodes' forces
//! back and hands them to [`TissueContact::reaction`].
//!
//! No adhesion: a held node whose reaction would pull the body (tissue
//! tension across the interface, the body moving away) is released on the
//! next update; it is caught again only if it penetrates again.

use glam::DVec3;

use crate::collider::TriangleCollider;
use crate::error::{check_non_negative, ContactError};
use crate::rigid::{RigidPose, Wrench};

/// A tissue node held on the body surface this step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldNode {
    pub node: u32,
    /// Where the node is put: its closest point on the body surface, world, m.
    pub target: DVec3,
    /// Body outward normal there, world.
    pub normal: DVec3,
}

/// The tissue's push on a rigid body, from the held nodes' reactions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TissueReaction {
    /// Total force on the body, N.
    pub force: DVec3,
    /// Moment about the body's centre of mass, N m.
    pub torque_about_com: DVec3,
    /// Moment about the given pivot (the atlanto-occipital point), N m.
    pub moment_about_pivot: DVec3,
    /// Held nodes whose reaction pulled the body: released at the next update.
    pub released: usize,
}

impl TissueReaction {
    pub fn wrench(&self) -> Wrench {
        Wrench { force: self.force, torque: self.torque_about_com }
    }
}

/// Contact state between one rigid body and one tissue mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct TissueContact {
    held: Vec<HeldNode>,
    /// Per held node: its reaction pulled the body at the last reading.
    pulling: Vec<bool>,
    /// How far outside the body a held node may be and still be kept on it
    /// (the body moved away within one step), m.
    follow_distance_m: f64,
    /// Scratch: which nodes are kept from the last step (indexed by node).
    kept: Vec<bool>,
}

impl TissueContact {
    /// `follow_distance_m`: the largest gap a held, pushing node may open to
    /// the body in one coupling step and still be kept on it. Take about the
    /// largest body displacement per coupling step (speed times step).
    pub fn new(follow_distance_m: f64) -> Result<Self, ContactError> {
        Ok(TissueContact {
            held: Vec::new(),
            pulling: Vec::new(),
            follow_distance_m: check_non_negative("follow_distance_m", follow_distance_m, false)?,
            kept: Vec::new(),
        })
    }

    /// The nodes held at the last update, in ascending node order.
    pub fn held(&self) -> &[HeldNode] {
        &self.held
    }

    /// Decides which nodes the body holds this step and where: every node
    /// inside the body (closest surface point in the body frame, with the
    /// pseudo-normal inside test), and every node held last step whose
    /// reaction still pushed, kept on the surface if within the follow
    /// distance. `body` is the body's surface in its own frame, `pose` its
    /// current pose, `nodes` the tissue's current node positions (world).
    pub fn update(&mut self, body: &TriangleCollider, pose: &RigidPose, nodes: &[DVec3]) -> &[HeldNode] {
        self.kept.clear();
        self.kept.resize(nodes.len(), false);
        for (h, &pull) in self.held.iter().zip(&self.pulling) {
            if !pull && (h.node as usize) < nodes.len() {
                self.kept[h.node as usize] = true;
            }
        }
        let (lo, hi) = body.bounds();
        let margin = DVec3::splat(self.follow_distance_m);
        let (lo, hi) = (lo - margin, hi + margin);
        let rotation = pose.orientation;

        self.held.clear();
        for (i, &x) in nodes.iter().enumerate() {
            let local = pose.inverse_transform_point(x);
            // Broad phase: the node against the body's own bounds.
            if local.cmplt(lo).any() || local.cmpgt(hi).any() {
                continue;
            }
            let kept = self.kept[i];
            // Inside points can lie anywhere up to the body's half-size deep.
            let reach = if kept { f64::MAX } else { (hi - lo).max_element() };
            let Some(hit) = body.closest_point(local, reach) else { continue };
            let penetrates = hit.signed_distance < 0.0;
            if penetrates || (kept && hit.signed_distance <= self.follow_distance_m) {
                self.held.push(HeldNode {
                    node: i as u32,
                    target: pose.transform_point(hit.point),
                    normal: rotation * hit.normal,
                });
            }
        }
        self.pulling.clear();
        self.pulling.resize(self.held.len(), false);
        &self.held
    }

    /// The tissue's force and moments on the body, from `forces_on_body[k]`,
    /// the force held node `k` exerts on the body (same order as
    /// [`TissueContact::held`]). With carus-fem's TLED convention
    /// M a = R - F(u), the body supplies R = F(u) to hold a node, so the
    /// node pushes the body with -F(u): pass the negated internal forces.
    /// Nodes whose force pulls the body out along its normal are marked for
    /// release and left out of the sums.
    pub fn reaction(
        &mut self,
        forces_on_body: &[DVec3],
        com: DVec3,
        pivot: DVec3,
    ) -> Result<TissueReaction, ContactError> {
        if forces_on_body.len() != self.held.len() {
            return Err(ContactError::LengthMismatch {
                what: "tissue forces (one per held node)",
                expected: self.held.len(),
                got: forces_on_body.len(),
            });
        }
        let mut out = TissueReaction {
            force: DVec3::ZERO,
            torque_about_com: DVec3::ZERO,
            moment_about_pivot: DVec3::ZERO,
            released: 0,
        };
        for ((h, &f), pull) in self.held.iter().zip(forces_on_body).zip(self.pulling.iter_mut()) {
            *pull = f.dot(h.normal) > 0.0;
            if *pull {
                out.released += 1;
                continue;
            }
            out.force += f;
            out.torque_about_com += (h.target - com).cross(f);
            out.moment_about_pivot += (h.target - pivot).cross(f);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collider::tests::uv_sphere;
    use glam::DQuat;

    fn ball() -> TriangleCollider {
        let (v, t) = uv_sphere(0.05, 12, 24);
        TriangleCollider::new("head", &v, &t).unwrap()
    }

    /// A flat grid of tissue nodes in the plane z = `z`, 1 cm apart.
    fn sheet(z: f64) -> Vec<DVec3> {
        let mut nodes = Vec::new();
        for i in -10..=10 {
            for j in -10..=10 {
                nodes.push(DVec3::new(i as f64 * 0.01, j as f64 * 0.01, z));
            }
        }
        nodes
    }

    #[test]
    fn penetrating_nodes_are_projected_onto_the_body() {
        let body = ball();
        let pose = RigidPose::new(DVec3::new(0.0, 0.0, 0.03), DQuat::from_rotation_y(0.4));
        let nodes = sheet(0.0);
        let mut contact = TissueContact::new(1e-3).unwrap();
        let held = contact.update(&body, &pose, &nodes).to_vec();
        // The sheet cuts the ball 3 cm below its centre: a disc of radius
        // sqrt(5^2 - 3^2) = 4 cm holds the nodes strictly inside.
        let inside: Vec<u32> = (0..nodes.len() as u32)
            .filter(|&i| (nodes[i as usize] - pose.position).length() < 0.0495)
            .collect();
        let got: Vec<u32> = held.iter().map(|h| h.node).collect();
        for i in &inside {
            assert!(got.contains(i), "node {i} inside but not held");
        }
        for h in &held {
            // On the (faceted) sphere and along its outward normal.
            let r = (h.target - pose.position).length();
            assert!((0.0485..=0.0501).contains(&r), "target radius {r}");
            assert!(h.normal.dot(h.target - pose.position) > 0.0);
            assert!((nodes[h.node as usize] - pose.position).length() < 0.0501);
        }
    }

    #[test]
    fn reaction_sums_force_and_moment_and_releases_pulling_nodes() {
        let body = ball();
        let pose = RigidPose::new(DVec3::new(0.0, 0.0, 0.03), DQuat::IDENTITY);
        let nodes = sheet(0.0);
        let mut contact = TissueContact::new(1e-3).unwrap();
        let held = contact.update(&body, &pose, &nodes).to_vec();
        let n = held.len();
        assert!(n > 10);
        // The tissue pushes each node's body point inwards with 0.1 N, except
        // one node that pulls.
        let mut forces: Vec<DVec3> = held.iter().map(|h| -0.1 * h.normal).collect();
        forces[0] = 0.1 * held[0].normal;
        let pivot = DVec3::new(0.0, 0.02, 0.08);
        let r = contact.reaction(&forces, pose.position, pivot).unwrap();
        assert_eq!(r.released, 1);
        let expected: DVec3 = forces[1..].iter().sum();
        assert!((r.force - expected).length() < 1e-12);
        let moment: DVec3 = held[1..].iter().zip(&forces[1..]).map(|(h, f)| (h.target - pivot).cross(*f)).sum();
        assert!((r.moment_about_pivot - moment).length() < 1e-12);
        // The two moments differ by the transfer term (com - pivot) x F.
        let transferred = r.torque_about_com + (pose.position - pivot).cross(r.force);
        assert!((r.moment_about_pivot - transferred).length() < 1e-12);

        // The body rises 2 mm: the nodes (left where they were put) now lie
        // just outside; the pushing ones are kept, the pulling one released.
        let moved = RigidPose::new(pose.position + DVec3::new(0.0, 0.0, 0.002), DQuat::IDENTITY);
        let positions: Vec<DVec3> = {
            let mut p = nodes.clone();
            for h in &held {
                p[h.node as usize] = h.target;
            }
            p
        };
        let mut follow = TissueContact::new(3e-3).unwrap();
        follow.held = contact.held.clone();
        follow.pulling = contact.pulling.clone();
        let again: Vec<u32> = follow.update(&body, &moved, &positions).iter().map(|h| h.node).collect();
        assert!(!again.contains(&held[0].node), "pulling node kept");
        assert_eq!(again.len(), n - 1);
    }

    #[test]
    fn mismatched_force_count_is_an_error() {
        let mut contact = TissueContact::new(1e-3).unwrap();
        contact.update(&ball(), &RigidPose::IDENTITY, &sheet(0.0));
        let held = contact.held().len();
        assert!(held > 0);
        assert!(matches!(
            contact.reaction(&[], DVec3::ZERO, DVec3::ZERO),
            Err(ContactError::LengthMismatch { .. })
        ));
        assert!(contact.reaction(&vec![DVec3::ZERO; held + 1], DVec3::ZERO, DVec3::ZERO).is_err());
    }
}
