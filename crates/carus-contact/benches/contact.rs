//! Cost of one contact pass at labour-loop sizes: a fetal head of ~3k
//! samples against a ~50k-triangle bony surface, the trunk's samples
//! against the moving head, and the tissue coupling query for a 10k-node
//! pelvic floor.

use carus_contact::{
    obstacle_contacts, pair_contacts, BodyMotion, ContactLaw, BodyContactState, RigidObstacle, RigidPose, SurfaceSamples, TissueContact,
    TriangleCollider,
};
use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DQuat, DVec3};
use parry3d_f64::shape::Ball;

/// A ball as a triangle surface (parry's tessellation), outward normals.
fn ball(radius: f64, theta: u32, phi: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    Ball::new(radius).to_trimesh(theta, phi)
}

fn contact_pass(c: &mut Criterion) {
    // The canal: the inside of a 6 cm hollow ball (winding reversed, so the
    // bone lies outside it), about 50k triangles.
    let (v, mut t) = ball(0.06, 250, 100);
    for tri in &mut t {
        tri.swap(1, 2);
    }
    let pelvis = RigidObstacle::new("pelvis", &v, &t, None).unwrap();
    // The head: radius 4.75 cm, pressed 0.5 mm into the wall on one side.
    let (hv, ht) = ball(0.0475, 80, 40);
    let samples = SurfaceSamples::from_vertices("head", &hv, &ht).unwrap();
    let motion = BodyMotion {
        pose: RigidPose::new(DVec3::new(0.0130, 0.0, 0.0), DQuat::IDENTITY),
        linear_velocity: DVec3::new(0.01, 0.0, -0.02),
        angular_velocity: DVec3::new(0.0, 0.5, 0.0),
    };
    let law = ContactLaw::default();
    let mut anchors = BodyContactState::new(&samples);
    let report = obstacle_contacts(&pelvis, &law, &samples, &motion, DVec3::ZERO, &mut anchors).unwrap();
    eprintln!(
        "pelvis {} triangles, head {} samples, {} contacts, force {:.1} N",
        pelvis.surface().triangle_count(),
        samples.len(),
        report.contacts.len(),
        report.force.length()
    );
    // Cold: a fresh state queries every sample (the first step of a run).
    c.bench_function("obstacle_contacts cold: head 3k samples vs 50k triangles", |b| {
        b.iter(|| {
            let mut fresh = BodyContactState::new(&samples);
            obstacle_contacts(&pelvis, &law, &samples, &motion, DVec3::ZERO, &mut fresh).unwrap()
        })
    });
    // Moving: the head advances 5 um per step (0.05 m/s at a 1e-4 s step),
    // so the clearance skin skips the samples clear of the wall.
    let mut step = 0u64;
    c.bench_function("obstacle_contacts moving 5 um/step: head 3k samples vs 50k triangles", |b| {
        b.iter(|| {
            step += 1;
            let phase = step as f64 * 5e-6 / 1e-3;
            let moved = BodyMotion {
                pose: RigidPose::new(motion.pose.position_m + DVec3::new(0.0, 1e-3 * phase.sin(), 1e-3 * phase.cos()), DQuat::IDENTITY),
                ..motion
            };
            obstacle_contacts(&pelvis, &law, &samples, &moved, DVec3::ZERO, &mut anchors).unwrap()
        })
    });

    // Head on trunk: a 6 cm chest ball's 1k samples pressed 5 mm into the
    // head ball, both moving, under the trunk's soft law (1e7 Pa/m).
    let head_obstacle = RigidObstacle::new("head", &hv, &ht, None).unwrap();
    let (cv, ct) = ball(0.06, 40, 20);
    let chest = SurfaceSamples::from_vertices("chest", &cv, &ct).unwrap();
    let soft = ContactLaw { penalty_stiffness_pa_per_m: 1.0e7, ..ContactLaw::default() };
    let head_motion = BodyMotion {
        pose: RigidPose::new(DVec3::new(0.1, 0.0, 0.0), DQuat::from_rotation_z(0.3)),
        linear_velocity: DVec3::new(0.0, 0.0, -0.02),
        angular_velocity: DVec3::new(0.0, 0.2, 0.0),
    };
    let chest_motion = BodyMotion {
        pose: RigidPose::new(DVec3::new(0.1, 0.0, -0.1025), DQuat::IDENTITY),
        linear_velocity: DVec3::new(0.0, 0.0, -0.018),
        angular_velocity: DVec3::ZERO,
    };
    let mut chest_memory = BodyContactState::new(&chest);
    let pair = pair_contacts(&head_obstacle, &soft, &chest, &chest_motion, &head_motion, &mut chest_memory).unwrap();
    eprintln!("chest {} samples, {} on the head, force {:.1} N", chest.len(), pair.active, pair.on_obstacle.force.length());
    c.bench_function("pair_contacts: chest 762 samples 5 mm into the head, repeated pass", |b| {
        b.iter(|| pair_contacts(&head_obstacle, &soft, &chest, &chest_motion, &head_motion, &mut chest_memory).unwrap())
    });

    // Tissue: a 100 x 100 sheet of nodes, 1.5 mm apart, cut by the head.
    let head = TriangleCollider::new("head", &hv, &ht).unwrap();
    let nodes: Vec<DVec3> = (0..100 * 100)
        .map(|k| DVec3::new((k % 100) as f64 * 1.5e-3 - 0.075, (k / 100) as f64 * 1.5e-3 - 0.075, -0.045))
        .collect();
    let mut tissue = TissueContact::new(2e-3).unwrap();
    let pose = RigidPose::IDENTITY;
    eprintln!("tissue {} nodes, {} held", nodes.len(), tissue.update(&head, &pose, &nodes).len());
    c.bench_function("tissue update cold: 10k nodes vs head", |b| {
        b.iter(|| TissueContact::new(2e-3).unwrap().update(&head, &pose, &nodes).len())
    });
    let mut step = 0u64;
    c.bench_function("tissue update moving 5 um/step: 10k nodes vs head", |b| {
        b.iter(|| {
            step += 1;
            let phase = step as f64 * 5e-6 / 1e-3;
            let moved = RigidPose::new(DVec3::new(1e-3 * phase.sin(), 0.0, 1e-3 * phase.cos()), DQuat::IDENTITY);
            tissue.update(&head, &moved, &nodes).len()
        })
    });
}

criterion_group!(benches, contact_pass);
criterion_main!(benches);
