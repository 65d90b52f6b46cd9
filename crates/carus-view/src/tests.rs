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
    let meshes = replay.meshes(k, Layers::default());
    let names: Vec<&str> = meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["fetal head", "posterior fontanelle", "anterior fontanelle", "fetal trunk", "pelvic floor", "pelvis"]);
    // The head's vertices are its surface moved by the sample's pose.
    let pose = demo.history.samples[k].head;
    let first = pose.point(demo.fetus.head.surface.vertices[0]);
    let drawn = meshes[0].positions[0];
    assert!((Vec3::from(drawn) - first.as_vec3()).length() < 1e-6, "{drawn:?} against {first}");
    // The same counts at every sample: the window updates in place.
    let last = replay.meshes(demo.history.samples.len() - 1, Layers::default());
    for (a, b) in meshes.iter().zip(&last) {
        assert_eq!((a.positions.len(), a.indices.len()), (b.positions.len(), b.indices.len()), "{}", a.name);
    }
}

/// Whether every vertex of the head at samples `ks` is inside an 800 x
/// 600 picture from each standard view.
fn head_in_view(replay: &Replay, ks: &[usize]) {
    let (width, height) = (800, 600);
    for view in [View::Lateral, View::Anterior, View::Inferior] {
        let camera = replay.standard_camera(view);
        for &k in ks {
            let head = &replay.meshes(k, Layers::default())[0];
            for &p in &head.positions {
                let [x, y] = camera.project(Vec3::from(p), width, height);
                let inside = (0.0..=width as f32).contains(&x) && (0.0..=height as f32).contains(&y);
                assert!(inside, "{view:?}: head vertex at sample {k} drawn at ({x}, {y})");
            }
        }
    }
}

/// The standard views keep the head in the picture from above the inlet
/// until it is born, not only while it is in the canal; in a run whose
/// head is never born, down to its deepest.
#[test]
fn the_standard_views_hold_the_head_s_path_to_its_birth() {
    let (replay, demo) = textbook();
    let born = replay.series.head_delivered.iter().position(|&b| b).expect("the textbook head is born");
    head_in_view(&replay, &[0, born / 2, born]);

    let scene = demo.input("textbook").scene.unwrap();
    let mut short = demo.history.clone();
    short.samples.truncate(born);
    let unborn = Replay::new("textbook", scene, short, None).unwrap();
    assert!(!unborn.series.head_delivered.iter().any(|&b| b));
    head_in_view(&unborn, &[0, born - 1]);
}

#[test]
fn the_readout_names_the_head_s_place_and_the_movements_under_way() {
    let (replay, demo) = textbook();
    let rotation = demo.detector.movements.internal_rotation;
    let during = 0.5 * (rotation.start_s.unwrap() + rotation.end_s.unwrap());
    let lines = replay.readout(replay.sample_at(during));
    assert!(lines[0].starts_with("t = ") && lines[1].starts_with("station ") && lines[2].starts_with("theta "));
    assert!(lines.iter().any(|l| l.contains("internal rotation")), "{lines:?}");
    assert_eq!(replay.readout(0)[4], "head not engaged (its widest part above the inlet)");
    let engagement = demo.detector.movements.engagement.end_s.unwrap();
    assert_eq!(replay.readout(replay.sample_at(engagement + 1.0))[4], "head engaged, in the canal");
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

/// Theta past OP reads as the history keeps it, with where it points.
#[test]
fn theta_beyond_a_half_turn_names_where_the_occiput_points() {
    assert_eq!(theta_words(-31.0), "theta -31.0 deg, occiput LOA");
    assert_eq!(theta_words(-300.0), "theta -300.0 deg (= +60.0), occiput ROA");
    assert_eq!(theta_words(-180.0), "theta -180.0 deg, occiput OP");
}

/// A detector's record cut short (or of another history) is named, not
/// read past its end.
#[test]
fn a_detector_record_of_another_history_is_refused() {
    let (_, demo) = textbook();
    let scene = || demo.input("x").scene.unwrap();
    let mut cut = demo.detector.clone();
    cut.series = carus_analysis::Series::from_history(&carus_analysis::PoseHistory {
        samples: demo.history.samples[..400].to_vec(),
        ..demo.history.clone()
    });
    let e = Replay::new("x", scene(), demo.history.clone(), Some(&cut)).err().unwrap().to_string();
    assert!(e.contains(&format!("400 samples against the history's {}", demo.history.samples.len())), "{e}");
    let mut later = demo.history.clone();
    for s in &mut later.samples {
        s.time_s += 1.0;
    }
    let e = Replay::new("x", scene(), later, Some(&demo.detector)).err().unwrap().to_string();
    assert!(e.contains("its sample 0 is at 0 s, the history's at 1 s"), "{e}");
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
    let early = replay.picture(0.0, &camera, Layers::default(), 160, 120).unwrap();
    let late = replay.picture(replay.duration_s(), &camera, Layers::default(), 160, 120).unwrap();
    let background = early.pixels()[..4].to_vec();
    let drawn = early.pixels().chunks(4).filter(|p| *p != &background[..]).count();
    assert!(drawn > 160 * 120 / 20, "only {drawn} pixels drawn");
    assert_ne!(early.pixels(), late.pixels(), "the fetus did not move between the first and last samples");
    assert!(demo.history.samples.len() > 2);
}

mod forces {
    use carus_analysis::ContactSite;
    use carus_labour::loads::{AxialMoments, Body, GuideLoad, LoadSample, SiteLoad};
    use glam::DVec3;

    use super::*;
    use crate::forces::{ARROW_M_PER_N, EXPULSION_RGB};

    /// Any point of the head frame will do as the pivot: the moments are
    /// taken about it consistently.
    const PIVOT_IN_HEAD: DVec3 = DVec3::new(-0.02, 0.0, -0.03);

    fn site(body: Body, site: ContactSite, at: DVec3, force_n: DVec3, pivot: DVec3) -> SiteLoad {
        SiteLoad {
            body,
            site,
            points: 3,
            force_n,
            friction_force_n: DVec3::ZERO,
            moment_about_pivot_nm: (at - pivot).cross(force_n),
            pressing_n: Some(force_n.length()),
        }
    }

    /// The textbook replay with, at sample `k`, the sacrum pushing on the
    /// head's surface point farthest back (-y), the symphysis pushing the
    /// trunk at its chest's vertex farthest forward (+y), a 1 N touch too small to
    /// draw, a guide through the head's centre, the neck pushing the head
    /// at the pivot along the expulsion (60 N) and the trunk touching the
    /// head's side (+x, 30 N); and a push of 80 N on the trunk at every
    /// sample. Returns the points pushed.
    fn loaded(k: usize) -> (Replay, Demo, DVec3, DVec3) {
        let (_, demo) = textbook();
        let scene = demo.input("textbook").scene.unwrap();
        let mut history = demo.history.clone();
        for s in &mut history.samples {
            let spine = s.trunk.unwrap().orientation * demo.history.trunk.as_ref().unwrap().spine;
            s.expulsion_force_n = -80.0 * spine;
        }
        let sample = history.samples[k];
        let pivot = sample.head.point(PIVOT_IN_HEAD);
        let farthest = |surface: &carus_anatomy::TriSurface, pose: &carus_analysis::RigidPose, along: DVec3| {
            surface.vertices.iter().map(|&v| pose.point(v)).max_by(|a, b| a.dot(along).total_cmp(&b.dot(along))).unwrap()
        };
        let on_head = farthest(&scene.head, &sample.head, -DVec3::Y);
        let trunk = sample.trunk.unwrap();
        // On the chest, level with the trunk's centre, where the line from
        // the point to the centre enters the body at that point (from the
        // vertex farthest forward overall it can enter elsewhere first).
        let chest = carus_anatomy::TriSurface::new(
            scene.trunk.as_ref().unwrap().vertices.iter().copied().filter(|v| v.z.abs() < 0.02).collect(),
            Vec::new(),
        );
        let on_trunk = farthest(&chest, &trunk, DVec3::Y);
        let touched = farthest(&scene.head, &sample.head, DVec3::X);
        let touch = (sample.head.position_m - touched).normalize() * 30.0;
        let neck = sample.expulsion_force_n.normalize() * 60.0;
        let loads = history
            .samples
            .iter()
            .enumerate()
            .map(|(i, s)| LoadSample {
                time_s: s.time_s,
                sites: match i == k {
                    true => vec![
                        site(Body::Head, ContactSite::Sacrum, on_head, (sample.head.position_m - on_head).normalize() * 40.0, pivot),
                        site(Body::Trunk, ContactSite::Symphysis, on_trunk, (trunk.position_m - on_trunk).normalize() * 25.0, pivot),
                        site(Body::Head, ContactSite::PelvicSidewall, on_head, DVec3::X, pivot),
                        // Along the surface, off the head's centre: its moment places it.
                        site(Body::Head, ContactSite::PubicArch, on_head, DVec3::new(12.0, 0.0, 16.0), pivot),
                    ],
                    false => Vec::new(),
                },
                head_axial: AxialMoments::default(),
                head_trunk_force_n: if i == k { touch } else { DVec3::ZERO },
                head_trunk_moment_about_pivot_nm: (i == k).then(|| (touched - pivot).cross(touch)),
                neck: None,
                // The other samples are as a run recorded before the neck's force was.
                neck_force_n: (i == k).then_some(neck),
                spine: None,
                guide: (i == k).then_some(GuideLoad { force_n: DVec3::new(0.0, 0.0, -10.0), moment_nm: DVec3::ZERO }),
            })
            .collect();
        let replay = Replay::new("textbook", scene, history, Some(&demo.detector))
            .unwrap()
            .with_forces(loads, PIVOT_IN_HEAD, false)
            .unwrap();
        (replay, demo, on_head, on_trunk)
    }

    /// Each force's arrow lies on its line of action, points along it and
    /// ends where that line enters the body pushed: the sacrum's and the
    /// symphysis's at the points they push, the expulsion on the trunk's
    /// surface in line with its centre, the guide on the head in line with
    /// its centre. A 1 N touch is not drawn.
    #[test]
    fn an_arrow_ends_where_its_force_meets_the_body() {
        let k = 7;
        let (replay, _, on_head, on_trunk) = loaded(k);
        let arrows = replay.arrows(k);
        let labels: Vec<&str> = arrows.iter().map(|a| a.label.as_str()).collect();
        assert_eq!(labels, ["expulsion", "guide", "neck", "trunk on the head", "sacrum", "symphysis on the trunk", "pubic arch"]);
        assert!(arrows[4].tip_m.distance(on_head) < 1e-6, "{} against {on_head}", arrows[4].tip_m);
        assert!(arrows[5].tip_m.distance(on_trunk) < 1e-6, "{} against {on_trunk}", arrows[5].tip_m);
        let sample = &replay.history.samples[k];
        let in_line = |a: &crate::forces::Arrow, centre: DVec3| (a.tip_m - centre).cross(a.force_n.normalize()).length();
        // An off-centre force's arrow lies on its own line, through the
        // point it pushes, not through the head's centre.
        assert!(in_line(&arrows[6], on_head) < 1e-9, "{}", in_line(&arrows[6], on_head));
        assert!(in_line(&arrows[6], replay.history.samples[k].head.position_m) > 1e-3);
        let (trunk, head) = (sample.trunk.unwrap(), sample.head);
        assert!(in_line(&arrows[0], trunk.position_m) < 1e-9 && in_line(&arrows[1], head.position_m) < 1e-9);
        // The neck pushes at the pivot, inside the head: its arrow is on the
        // line through the pivot and ends where that line enters the head,
        // before the pivot.
        let pivot = head.point(PIVOT_IN_HEAD);
        assert!(in_line(&arrows[2], pivot) < 1e-9);
        assert!((arrows[2].tip_m - pivot).dot(arrows[2].force_n) < -1e-3);
        // The trunk's touch ends where it touches, on its own line.
        let touched = arrows[3].tip_m;
        assert!(in_line(&arrows[3], head.position_m) < 1e-9, "a push aimed at the centre");
        assert!((touched - head.position_m).dot(DVec3::X) > 0.03, "{touched}");
        // The expulsion pushes the breech: its arrow ends behind the trunk's centre.
        assert!((arrows[0].tip_m - trunk.position_m).dot(arrows[0].force_n) < 0.0);
        assert_eq!(arrows[0].rgb, EXPULSION_RGB);
        // Drawn as a mesh from tail to tip, as long as its scale says.
        let mesh = arrows[4].mesh();
        let ends = mesh.positions.iter().map(|p| Vec3::from(*p).as_dvec3());
        let back = -arrows[4].force_n.normalize();
        let reach = ends.map(|p| (p - arrows[4].tip_m).dot(back)).fold(0.0, f64::max);
        assert!((reach - 40.0 * ARROW_M_PER_N).abs() < 1e-5, "{reach}");
        // Another sample has only the expulsion: a run recorded before the
        // neck's force and the touch's moment were has no arrows for them.
        assert_eq!(replay.arrows(k + 1).len(), 1);
    }

    #[test]
    fn the_layers_are_laid_over_the_anatomy_when_asked() {
        let k = 7;
        let (replay, _, _, _) = loaded(k);
        let marker = RenderMesh::sphere("sacral_promontory", [0.0, 0.0, 0.1], 0.003, [1.0, 0.0, 0.0]);
        let lambda = DVec3::new(-0.05, 0.0, 0.03);
        let replay = replay.with_markers(vec![marker]).with_head_markers(vec![("lambda".into(), lambda)], 0.0025, [1.0, 0.0, 0.0]);
        assert_eq!(replay.layers_available(), Layers { markers: true, forces: true });
        let names = |layers| replay.meshes(k, layers).iter().map(|m| m.name.clone()).collect::<Vec<_>>();
        let anatomy = ["fetal head", "posterior fontanelle", "anterior fontanelle", "fetal trunk", "pelvic floor", "pelvis"];
        assert_eq!(names(Layers::default()), anatomy);
        assert_eq!(names(Layers { markers: true, forces: false })[6..], ["sacral_promontory", "lambda"]);
        let both = names(Layers { markers: true, forces: true });
        assert_eq!(both[..8], names(Layers { markers: true, forces: false })[..]);
        assert_eq!(
            both[8..],
            ["force: expulsion", "force: guide", "force: neck", "force: trunk on the head", "force: sacrum", "force: symphysis on the trunk", "force: pubic arch"]
        );
        // The head's landmark moves with the head.
        let sphere = &replay.meshes(k, Layers { markers: true, forces: false })[7];
        let centre = sphere.positions.iter().map(|p| Vec3::from(*p)).sum::<Vec3>() / sphere.positions.len() as f32;
        let at = replay.history.samples[k].head.point(lambda).as_vec3();
        assert!(centre.distance(at) < 1e-4, "{centre} against {at}");
        // The floor and the trunk turn see-through only under the forces.
        for (mesh, name) in [(3, "fetal trunk"), (4, "pelvic floor")] {
            let opacity = |layers| replay.meshes(k, layers)[mesh].colour[3];
            assert_eq!(opacity(Layers::default()), 1.0, "{name}");
            assert!(opacity(Layers { markers: false, forces: true }) < 1.0, "{name}");
        }
        // Said in words, largest first.
        assert_eq!(
            replay.force_readout(k),
            ["expulsion 80 N", "neck 60 N", "sacrum 40 N", "trunk on the head 30 N", "symphysis on the trunk 25 N", "pubic arch 20 N", "guide 10 N"]
        );
        // Without loads there is nothing to lay over.
        let (bare, _) = textbook();
        assert_eq!(bare.layers_available(), Layers::default());
        assert_eq!(bare.meshes(k, Layers { markers: true, forces: true }).len(), 6);
        assert!(bare.force_readout(k).is_empty());
    }
}

/// The floor's colour scale is said in the readout, and a run whose floor
/// had an element turned inside out takes it from the frames before.
#[test]
fn the_floor_colour_scale_is_read_from_the_trusted_frames() {
    let demo = Demo::textbook().unwrap();
    let mut scene = demo.input("textbook").scene.unwrap();
    let floor = scene.floor.as_mut().expect("the demonstration draws a floor");
    let frame = |time_s: f64, stretch: f64| carus_report::FloorFrame {
        time_s,
        positions_m: floor.rest_positions_m.clone(),
        stretch: vec![stretch; floor.rest_positions_m.len()],
    };
    floor.frames = vec![frame(1.0, 2.0), frame(2.0, 9.0)];
    let replay = Replay::new("textbook", scene, demo.history.clone(), Some(&demo.detector)).unwrap();
    let shown = |replay: &Replay| replay.readout(replay.sample_at(1.0))[5].clone();
    assert!(shown(&replay).ends_with("colour: stretch 1.00 (dark) to 9.00 (bright)"), "{}", shown(&replay));
    let trusted = replay.with_stretch_scale_before(2.0);
    assert!(shown(&trusted).ends_with("to 2.00 (bright)"), "{}", shown(&trusted));
    // No frame before the time: all of them set it, as in the report.
    assert!(shown(&trusted.with_stretch_scale_before(1.0)).ends_with("to 9.00 (bright)"));
}
