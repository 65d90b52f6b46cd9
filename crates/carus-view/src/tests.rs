use carus_render::{Camera, Projection, View};
use carus_report::demo::Demo;
use glam::Vec3;

use super::*;

/// The synthetic textbook labour of carus-report's demonstration, as a replay.
fn textbook() -> (Replay, Demo) {
    let demo = Demo::textbook().unwrap();
    let scene = demo.input("textbook").scene.expect("the demonstration has its anatomy");
    let replay = Replay::new("textbook", scene, demo.history.clone(), Some(&demo.detector)).unwrap();
    (replay, demo)
}

#[test]
fn the_sample_shown_is_the_last_one_at_or_before_the_time() {
    let (replay, demo) = textbook();
    let times: Vec<f64> = demo.history.samples.iter().map(|s| s.time_s).collect();
    assert_eq!(replay.sample_at(-1.0), 0);
    assert_eq!(replay.sample_at(times[0]), 0);
    assert_eq!(replay.sample_at(times[3]), 3);
    assert_eq!(replay.sample_at(0.5 * (times[3] + times[4])), 3);
    assert_eq!(replay.sample_at(1e9), times.len() - 1);
    assert_eq!(replay.duration_s(), *times.last().unwrap());
}

#[test]
fn a_frame_has_the_fetus_where_the_history_puts_it() {
    let (replay, demo) = textbook();
    let k = demo.history.samples.len() / 2;
    let meshes = replay.meshes(k);
    let names: Vec<&str> = meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["fetal head", "fetal trunk", "pelvic floor", "pelvis"]);
    // The head's vertices are its surface moved by the sample's pose.
    let pose = demo.history.samples[k].head;
    let first = pose.point(demo.fetus.head.surface.vertices[0]);
    let drawn = meshes[0].positions[0];
    assert!((Vec3::from(drawn) - first.as_vec3()).length() < 1e-6, "{drawn:?} against {first}");
    // The same counts at every sample: the window updates in place.
    let last = replay.meshes(demo.history.samples.len() - 1);
    for (a, b) in meshes.iter().zip(&last) {
        assert_eq!((a.positions.len(), a.indices.len()), (b.positions.len(), b.indices.len()), "{}", a.name);
    }
}

#[test]
fn the_readout_names_the_head_s_place_and_the_movements_under_way() {
    let (replay, demo) = textbook();
    let rotation = demo.detector.movements.internal_rotation;
    let during = 0.5 * (rotation.start_s.unwrap() + rotation.end_s.unwrap());
    let lines = replay.readout(replay.sample_at(during));
    assert!(lines[0].starts_with("t = ") && lines[1].starts_with("station ") && lines[2].starts_with("theta "));
    assert!(lines.iter().any(|l| l.contains("internal rotation")), "{lines:?}");
    assert_eq!(replay.readout(0)[4], "head in the canal");
    // The demonstration records no floor state: it is drawn at rest, and said so.
    assert_eq!(replay.readout(0)[5], "floor at rest (no state recorded)");
    assert_eq!(replay.readout(demo.history.samples.len() - 1)[4], "head delivered");
}

#[test]
fn an_empty_history_is_refused() {
    let (_, demo) = textbook();
    let scene = demo.input("x").scene.unwrap();
    let mut empty = demo.history.clone();
    empty.samples.clear();
    assert!(matches!(Replay::new("x", scene, empty, None), Err(ViewError::NoSamples)));
}

#[test]
fn the_orbit_starts_from_the_standard_views_and_keeps_up_up() {
    let (replay, _) = textbook();
    let lateral = Orbit::from_view(View::Lateral);
    assert!((lateral.eye_direction() - Vec3::X).length() < 1e-6);
    // From below, the pubis (anterior, +y) is at the top of the picture,
    // as in the standard inferior view; from the side, cranial is up.
    let below = replay.camera(&Orbit::from_view(View::Inferior));
    let centre = below.target;
    assert!(below.project(centre + 0.05 * Vec3::Y, 100, 100)[1] < 50.0);
    assert!(below.eye_direction.z < -0.99);
    let above = replay.camera(&Orbit::from_view(View::Superior));
    assert!(above.project(above.target + 0.05 * Vec3::Y, 100, 100)[1] < 50.0);
    let side = replay.camera(&lateral);
    assert!(side.project(side.target + 0.05 * Vec3::Z, 100, 100)[1] < 50.0);

    // The scale holds while the camera circles.
    let mut turned = lateral;
    turned.drag(0.7, -0.4);
    assert_eq!(replay.camera(&turned).half_extent, replay.camera(&lateral).half_extent);

    let mut orbit = lateral;
    orbit.drag(0.3, 10.0);
    assert!((orbit.azimuth - (std::f32::consts::TAU - 0.3)).abs() < 1e-5);
    assert!(orbit.elevation <= MAX_ELEVATION && orbit.eye_direction().z > 0.99);
    orbit.zoom_by(100.0);
    assert_eq!(orbit.zoom, ZOOM.1);
    orbit.zoom_by(f32::NAN);
    assert_eq!(orbit.zoom, ZOOM.1);
    // Zooming in halves the field kept in view.
    let mut near = lateral;
    near.zoom_by(2.0);
    let (whole, half) = (replay.camera(&lateral), replay.camera(&near));
    assert!((whole.half_extent[0] - 2.0 * half.half_extent[0]).abs() < 1e-6);
    // In perspective, zoom narrows the field of view from the same eye.
    let perspective = Orbit { projection: Projection::Perspective { fov_y: 0.6 }, ..lateral };
    let closer = Orbit { zoom: 2.0, ..perspective };
    let (wide, narrow) = (replay.camera(&perspective), replay.camera(&closer));
    assert!(!wide.is_orthographic() && (wide.eye() - narrow.eye()).length() < 1e-6);
    let point = wide.target + 0.02 * Vec3::Y;
    let off = |c: &Camera| c.project(point, 100, 100)[0] - 50.0;
    assert!((off(&narrow) - 2.0 * off(&wide)).abs() < 0.05 * off(&wide).abs(), "{} {}", off(&narrow), off(&wide));
}

/// A frame drawn offscreen shows the scene: the picture is not all
/// background, and the fetus moves between two times. Needs a GPU or
/// Mesa's lavapipe (`.ci/run` installs it).
#[test]
fn a_frame_is_drawn_offscreen() {
    let (replay, demo) = textbook();
    let camera = replay.standard_camera(View::Lateral);
    let early = replay.picture(0.0, &camera, 160, 120).unwrap();
    let late = replay.picture(replay.duration_s(), &camera, 160, 120).unwrap();
    let background = early.pixels()[..4].to_vec();
    let drawn = early.pixels().chunks(4).filter(|p| *p != &background[..]).count();
    assert!(drawn > 160 * 120 / 20, "only {drawn} pixels drawn");
    assert_ne!(early.pixels(), late.pixels(), "the fetus did not move between the first and last samples");
    assert!(demo.history.samples.len() > 2);
}
