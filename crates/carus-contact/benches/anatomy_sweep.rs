//! The contact pass on the project's own anatomy: the default term head
//! (carus-anatomy) swept down the pelvic axis of the default gynecoid pelvis,
//! occiput transverse (LOT), 0.1 mm per pass, from 30 mm above the inlet to
//! the outlet. Prints where the head meets bone, then times a pass.

use carus_anatomy::fetus::{FetalHead, HeadDiameters};
use carus_anatomy::pelvis::PelvisDiameters;
use carus_anatomy::Pelvis;
use carus_contact::{obstacle_contacts, BodyContactState, BodyMotion, ContactLaw, RigidObstacle, RigidPose, SurfaceSamples};
use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DMat3, DQuat};

fn sweep(c: &mut Criterion) {
    let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
    let head = FetalHead::new(&HeadDiameters::default()).unwrap();
    let collider = RigidObstacle::new("pelvis", &pelvis.surface.vertices, &pelvis.surface.triangles, None).unwrap();
    let samples = SurfaceSamples::from_vertices("fetal head", &head.surface.vertices, &head.surface.triangles).unwrap();
    let law = ContactLaw::default();
    let mut memory = BodyContactState::new(&samples);
    eprintln!(
        "pelvis {} triangles, head {} samples; axis length {:.1} mm",
        collider.surface().triangle_count(),
        samples.len(),
        pelvis.axis.length() * 1e3
    );
    // Head frame: x = o, y = b, z = v. Occiput transverse to the mother's
    // left: o along the canal's transverse axis x, v along the descent t.
    let pose_at = |sigma: f64| {
        let f = pelvis.axis.frame(sigma);
        let rotation = DMat3::from_cols(f.transverse, f.tangent.cross(f.transverse), f.tangent);
        RigidPose::new(f.point, DQuat::from_mat3(&rotation))
    };
    let outlet = pelvis.plane_sigmas()[3];
    let mut sigma = -0.03;
    let mut first_contact = None;
    let mut passes = 0u32;
    let mut next_print = 100u32;
    let start = std::time::Instant::now();
    while sigma <= outlet {
        let motion = BodyMotion::at_rest(pose_at(sigma));
        let report = obstacle_contacts(&collider, &law, &samples, &motion, motion.pose.position_m, &mut memory).unwrap();
        passes += 1;
        if first_contact.is_none() && !report.contacts.is_empty() {
            first_contact = Some(sigma);
            eprintln!("first bone contact at sigma {:.1} mm", sigma * 1e3);
        }
        if passes == next_print && !report.contacts.is_empty() {
            eprintln!(
                "sigma {:6.1} mm: {:4} contacts, deepest {:.2} mm, force {:8.1} N, {} samples tunnelled",
                sigma * 1e3,
                report.contacts.len(),
                report.deepest_m * 1e3,
                report.force.length(),
                report.too_deep
            );
        }
        if passes == next_print {
            next_print += 100;
        }
        sigma += 1e-4;
    }
    eprintln!(
        "{passes} passes in {:.3} s: {:.1} us per pass (head moving 0.1 mm per pass)",
        start.elapsed().as_secs_f64(),
        start.elapsed().as_secs_f64() / passes as f64 * 1e6
    );

    let mid = pose_at(pelvis.plane_sigmas()[2]);
    c.bench_function("obstacle_contacts cold: default head at the mid-pelvis", |b| {
        b.iter(|| {
            let mut fresh = BodyContactState::new(&samples);
            let motion = BodyMotion::at_rest(mid);
            obstacle_contacts(&collider, &law, &samples, &motion, mid.position_m, &mut fresh).unwrap()
        })
    });
}

criterion_group!(benches, sweep);
criterion_main!(benches);
