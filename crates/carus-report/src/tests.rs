//! Reports built from the synthetic histories, checked as a reader would:
//! one page, the outcome, every movement with its flag, the plots, the
//! pictures inline, nothing fetched from elsewhere.

use crate::demo::Demo;
use crate::{write_report, write_report_with, AxialMomentSample, CanalForceSample, FloorFrame, ReportError, ReportInput, SampleForces};

/// The timeline row of a movement, to its closing tag.
fn movement_row(html: &str, key: &str) -> String {
    let start = html
        .find(&format!("data-movement=\"{key}\""))
        .unwrap_or_else(|| panic!("no row for {key}"));
    let end = start + html[start..].find("</div>").unwrap();
    html[start..end].to_string()
}

fn assert_self_contained(html: &str) {
    assert_eq!(html.matches("<html").count(), 1, "one page");
    for external in [
        "http://", "https://", "src=\"/", "<script", "<link", "@import",
    ] {
        assert!(
            !html.contains(external),
            "the page refers outside itself: {external}"
        );
    }
}

#[test]
fn the_textbook_report_shows_everything_on_one_page() {
    let demo = Demo::textbook().unwrap();
    let report = write_report(&demo.input("textbook (synthetic)")).unwrap();
    let html = &report.html;
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_self_contained(html);
    assert!(html.contains("id=\"outcome\" data-delivered=\"true\">Delivered<"));
    assert!(html.contains("7 of 7 cardinal movements observed"));
    for (key, label) in [
        ("engagement", "Engagement"),
        ("descent", "Descent"),
        ("flexion", "Flexion"),
        ("internal_rotation", "Internal rotation"),
        ("extension", "Extension"),
        ("external_rotation", "External rotation (restitution)"),
        ("expulsion", "Expulsion"),
    ] {
        let row = movement_row(html, key);
        assert!(row.contains("data-observed=\"true\""), "{key}");
        assert!(row.contains(&format!("</i>{label}</span>")), "{row}");
        // The detector's own start, end and size, as the page writes them.
        let m = demo.detector.movements.by_key().into_iter().find(|(k, _)| *k == key).unwrap().1;
        let (Some(start), Some(end), Some(size)) = (m.start_s, m.end_s, m.size) else { panic!("{key}: {m:?}") };
        let size = match m.unit {
            carus_analysis::Unit::Mm => format!("{size:.1} mm"),
            carus_analysis::Unit::Deg => format!("{size:.0}\u{b0}"),
        };
        let expected = format!("<span class=\"when\">{start:.1} &ndash; {end:.1} s</span><span class=\"size\">{size}</span>");
        assert!(row.ends_with(&expected), "{row}\n  expected: {expected}");
    }
    for plot in ["station", "theta", "phi", "force"] {
        let at = html.find(&format!("id=\"plot-{plot}\"")).unwrap();
        let figure = &html[at..at + html[at..].find("</figure>").unwrap()];
        assert!(figure.contains("<svg"), "plot {plot} has its SVG");
    }
    // Four key moments, two views each, as PNG data: URIs.
    assert_eq!(html.matches("class=\"moment\"").count(), 4);
    assert_eq!(html.matches("src=\"data:image/png;base64,").count(), 8);
    assert!(html.contains("imposed trajectory (carus-analysis synthetic::textbook), not the physics"));
    assert!(html.contains("No pelvic floor was simulated in this run."));
    // Theta is plotted with the head's twist, and the textbook's rotations
    // need no caveat: its occiput never tilts steeply.
    let theta_plot = &html[html.find("id=\"plot-theta\"").unwrap()..];
    let theta_plot = &theta_plot[..theta_plot.find("</figure>").unwrap()];
    assert!(theta_plot.contains("twist about"));
    assert!(!html.contains("data-caveat"));
    // The shoulders' station beside the head's, with the inlet marked.
    let station_plot = &html[html.find("id=\"plot-station\"").unwrap()..];
    let station_plot = &station_plot[..station_plot.find("</figure>").unwrap()];
    assert!(station_plot.contains("bisacromial midpoint") && station_plot.contains("the inlet plane at -"));
}

/// A rotation the rule did not count for its station is said under the
/// timeline, with where and when it happened.
#[test]
fn a_rotation_outside_the_window_is_noted() {
    let mut demo = Demo::textbook().unwrap();
    assert!(!write_report_with(&demo.input("in the window"), None).unwrap().html.contains("rotation-outside-window"));
    demo.detector.internal_rotation_outside_window =
        Some(carus_analysis::RotationOutsideWindow { time_s: 6.14, station_mm: 63.8 });
    let html = write_report_with(&demo.input("late"), None).unwrap().html;
    let at = html.find("data-note=\"rotation-outside-window\"").expect("the note");
    assert!(at < html.find("id=\"plots\"").unwrap(), "under the timeline");
    let note = &html[at..at + html[at..].find("</p>").unwrap()];
    assert!(note.contains("at 6.1 s, station +64 mm") && note.contains("-20 to +50 mm"), "{note}");
}

#[test]
fn a_straight_push_reports_the_movements_it_lacks() {
    let demo = Demo::straight_push().unwrap();
    let report = write_report_with(&demo.input("straight push"), None).unwrap();
    let html = &report.html;
    assert_self_contained(html);
    for key in ["engagement", "descent"] {
        assert!(
            movement_row(html, key).contains("data-observed=\"true\""),
            "{key}"
        );
    }
    for key in [
        "flexion",
        "internal_rotation",
        "extension",
        "external_rotation",
        "expulsion",
    ] {
        assert!(
            movement_row(html, key).contains("data-observed=\"false\""),
            "{key}"
        );
    }
    assert!(html.contains("2 of 7 cardinal movements observed"));
    assert!(!html.contains("data-delivered=\"true\""));
    // No trunk in this history: the head's station alone.
    assert!(!html.contains("bisacromial midpoint"));
    assert!(
        html.contains("Not reached: full internal rotation (internal rotation was not observed)")
    );
}

#[test]
fn without_a_renderer_the_report_is_written_with_a_note() {
    let demo = Demo::textbook().unwrap();
    let report = write_report_with(&demo.input("no pictures"), None).unwrap();
    assert!(report.html.contains("id=\"no-pictures\""));
    assert!(!report.html.contains("data:image/png"));
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    // The rest of the page is all there.
    assert_eq!(report.html.matches("<svg").count(), 4);
    assert!(report.html.contains("Delivered"));
}

#[test]
fn a_detector_report_of_another_history_is_refused() {
    let textbook = Demo::textbook().unwrap();
    let push = Demo::straight_push().unwrap();
    let mut input = textbook.input("mismatch");
    input.detector = &push.detector;
    let error = write_report_with(&input, None).unwrap_err();
    assert!(
        matches!(error, ReportError::SeriesMismatch { .. }),
        "{error}"
    );
}

#[test]
fn floor_stretch_and_the_scenario_appear_when_given() {
    let demo = Demo::straight_push().unwrap();
    let mut input = demo.input("with floor");
    input.floor_peak_stretch = vec![(0.0, 1.0), (10.0, 1.4), (20.0, 1.2)];
    input.scenario_toml = Some("[forces]\nmax_n = 120 # <max>\n".into());
    let html = write_report_with(&input, None).unwrap().html;
    assert_eq!(
        html.matches("<svg").count(),
        5,
        "four plots and the floor's"
    );
    assert!(html.contains("Greatest: 1.400 at 10.0 s."));
    assert!(!html.contains("Lien et al."), "a floor near rest passes no cited level");
    assert!(!html.contains("plot-axial-moments"), "no moments given, no plot");
    assert!(html.contains("max_n = 120 # &lt;max&gt;"));
    // A floor the fetus never touched is said to be at rest, not dated to a tie.
    let untouched = vec![(0.0, 1.0), (10.0, 1.0), (20.0, 1.0)];
    let mut at_rest = demo.input("untouched floor");
    at_rest.floor_peak_stretch = untouched;
    let html = write_report_with(&at_rest, None).unwrap().html;
    assert!(html.contains("The floor was not stretched") && !html.contains("Greatest:"), "{html}");
    // Once a floor element has a corner turned inside out, what the floor
    // reads is not to be trusted: the greatest is taken before, and the rest is said.
    let mut inverted = demo.input("inverted corners");
    inverted.floor_peak_stretch = vec![(0.0, 1.0), (10.0, 1.4), (20.0, 3.0)];
    inverted.floor_untrusted_from_s = Some(15.0);
    let html = write_report_with(&inverted, None).unwrap().html;
    assert!(html.contains("Greatest while its elements were whole: 1.400 at 10.0 s."), "{html}");
    assert!(html.contains("From 15.0 s floor elements had a corner turned inside out") && html.contains("(up to 3.000)"));
    assert!(!html.contains("Lien et al."), "3.0 came after: no cited level is passed");
    input.floor_peak_stretch[1].1 = f64::NAN;
    assert!(matches!(
        write_report_with(&input, None),
        Err(ReportError::NotFinite { .. })
    ));
}

#[test]
fn a_floor_stretched_past_the_cited_crowning_levels_is_marked() {
    let demo = Demo::straight_push().unwrap();
    let mut input = demo.input("overstretched floor");
    let count_lines = |html: &str| {
        let floor = &html[html.find("id=\"plot-floor\"").unwrap()..];
        floor[..floor.find("</figure>").unwrap()].matches("opacity=\"0.45\"").count()
    };
    input.floor_peak_stretch = vec![(0.0, 1.0), (10.0, 2.0), (20.0, 1.5)];
    let rest_only = count_lines(&write_report_with(&input, None).unwrap().html);
    input.floor_peak_stretch = vec![(0.0, 1.0), (10.0, 4.0), (20.0, 1.5)];
    let html = write_report_with(&input, None).unwrap().html;
    assert!(html.contains("which this floor passes: 3.26 (Lien et al. 2004)."));
    assert_eq!(count_lines(&html), rest_only + 1, "one more reference line");
    input.floor_peak_stretch[1].1 = 7.9;
    let html = write_report_with(&input, None).unwrap().html;
    assert!(html.contains("3.26 (Lien et al. 2004) and 4.64 (Jing et al. 2012)"));
    assert_eq!(count_lines(&html), rest_only + 2);
}

#[test]
fn what_pushes_the_head_is_plotted_when_known() {
    let demo = Demo::straight_push().unwrap();
    let mut input = demo.input("with canal forces");
    let plots = |input: &ReportInput| write_report_with(input, None).unwrap().html.matches("<svg").count();
    let without = plots(&input);
    input.head_canal_forces = (0..3)
        .map(|k| CanalForceSample {
            time_s: 10.0 * k as f64,
            push_n: 30.0,
            trunk_n: 1.0,
            bone_n: -5.0 * k as f64,
            floor_n: -10.0,
            guide_n: 0.0,
        })
        .collect();
    let html = write_report_with(&input, None).unwrap().html;
    assert_eq!(plots(&input), without + 1);
    assert!(html.contains("id=\"plot-canal-forces\"") && html.contains("the push that reaches it at the pivot"));
    assert!(!html.contains("the guide (not the physics)"));
    input.head_canal_forces[1].guide_n = 4.0;
    assert!(write_report_with(&input, None).unwrap().html.contains("the guide (not the physics)"));
    input.head_canal_forces[2].floor_n = f64::NAN;
    assert!(matches!(
        write_report_with(&input, None),
        Err(ReportError::NotFinite { what: "head_canal_forces", .. })
    ));
}

#[test]
fn the_moments_that_turn_the_head_are_plotted_when_known() {
    let demo = Demo::straight_push().unwrap();
    let mut input = demo.input("with moments");
    input.head_axial_moments = (0..3)
        .map(|k| AxialMomentSample {
            time_s: 10.0 * k as f64,
            bone_nm: 0.1 * k as f64,
            floor_nm: -0.2,
            neck_nm: 0.05,
            neck_push_nm: -0.1,
            trunk_nm: 0.02,
            guide_nm: 0.0,
        })
        .collect();
    let html = write_report_with(&input, None).unwrap().html;
    assert_eq!(html.matches("<svg").count(), 5, "four plots and the moments' (no floor)");
    assert!(html.contains("id=\"plot-axial-moments\"") && html.contains("the push through the pivot") && html.contains("the trunk on the head"));
    assert!(!html.contains("the guide (not the physics)"), "a forward run has no guide");
    // An imposed or hybrid run's guide turns the head too, and is drawn.
    input.head_axial_moments[1].guide_nm = 0.3;
    let html = write_report_with(&input, None).unwrap().html;
    assert!(html.contains("the push through the pivot</span> <span style=\"color:#d91ad9\">&#9632; the guide (not the physics)</span>"), "{html}");
    input.head_axial_moments[2].neck_nm = f64::INFINITY;
    assert!(matches!(
        write_report_with(&input, None),
        Err(ReportError::NotFinite { what: "head_axial_moments", .. })
    ));
}

#[test]
fn a_recorded_floor_is_coloured_by_stretch_and_a_bad_frame_costs_only_its_pictures() {
    let demo = Demo::textbook().unwrap();
    let mut input = demo.input("floor frames");
    let scene = input.scene.as_mut().unwrap();
    let floor = scene.floor.as_mut().unwrap();
    let rest = floor.rest_positions_m.clone();
    // Stretch growing towards the back of the floor, recorded at two instants.
    let stretch: Vec<f64> = rest.iter().map(|p| 1.0 + (0.05 - p.y).max(0.0)).collect();
    let top = stretch.iter().copied().fold(1.0, f64::max);
    floor.frames = vec![
        FloorFrame {
            time_s: 0.0,
            positions_m: rest.clone(),
            stretch: vec![1.0; rest.len()],
        },
        FloorFrame {
            time_s: 60.0,
            positions_m: rest.clone(),
            stretch,
        },
    ];
    let report = write_report(&input).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert!(report.html.contains(&format!(
        "<span class=\"ramp\"></span> 1.00 &ndash; {top:.2}"
    )));
    // The scale spans the stretch recorded; only a floor near rest gets the least span, and says so.
    assert!(top > 1.05 && !report.html.contains("least span"));
    assert!(report.html.contains("floor as recorded at 60.00 s"));
    assert_eq!(
        report.html.matches("src=\"data:image/png;base64,").count(),
        8
    );
    // The scale reaches the floor's peak stretch before its first inverted
    // element, between the pictured states; not the untrusted ones after.
    let mut peaked = input.clone();
    peaked.floor_peak_stretch = vec![(0.0, 1.0), (30.0, top + 1.0), (50.0, 9.0)];
    peaked.floor_untrusted_from_s = Some(40.0);
    let html = write_report(&peaked).unwrap().html;
    assert!(html.contains(&format!("<span class=\"ramp\"></span> 1.00 &ndash; {:.2}", top + 1.0)), "{html}");

    // A frame with too few stretch values: those pictures fail, the page does not.
    let floor = input.scene.as_mut().unwrap().floor.as_mut().unwrap();
    floor.frames[1].stretch.truncate(3);
    let report = write_report(&input).unwrap();
    assert!(!report.warnings.is_empty());
    assert!(
        report.warnings.iter().all(|w| w.contains("not drawn")),
        "{:?}",
        report.warnings
    );
    assert!(report.html.contains("Not drawn: "));
    assert!(report.html.contains("Delivered"));
}

/// How the head was born is said under the timeline, so that a movement
/// undone before the birth is seen; no note for a head not born.
#[test]
fn how_the_head_was_born_is_noted() {
    let mut demo = Demo::textbook().unwrap();
    let html = write_report_with(&demo.input("born"), None).unwrap().html;
    let at = html.find("data-note=\"head-born\"").expect("the note");
    assert!(at < html.find("id=\"plots\"").unwrap(), "under the timeline");
    let note = &html[at..at + html[at..].find("</p>").unwrap()];
    assert!(note.contains("The head was born at") && note.contains("occiput OA") && note.contains("flexion positive"), "{note}");
    demo.detector.head_born = None;
    assert!(!write_report_with(&demo.input("held"), None).unwrap().html.contains("head-born"));
}

/// How the shoulders came into the inlet and how long the body took after
/// the head are said beside the birth; a fetus without a trunk has no note.
#[test]
fn the_shoulders_passage_is_noted() {
    let mut demo = Demo::textbook().unwrap();
    let html = write_report_with(&demo.input("born"), None).unwrap().html;
    let at = html.find("data-note=\"shoulders\"").expect("the note");
    assert!(at < html.find("id=\"plots\"").unwrap(), "under the timeline");
    let note = &html[at..at + html[at..].find("</p>").unwrap()];
    let passage = demo.detector.shoulders.expect("the textbook has a trunk");
    assert!(note.contains("The shoulders came into the inlet at") && note.contains("oblique"), "{note}");
    assert!(note.contains(&format!("the body was born {:.1} s after the head", passage.head_to_body_s.unwrap())), "{note}");
    demo.detector.shoulders = None;
    assert!(!write_report_with(&demo.input("no trunk"), None).unwrap().html.contains("data-note=\"shoulders\""));
}

/// The forces plot says that its contact curve is a vector total, and
/// the contact load (the sum of the sizes) has a plot of its own when it
/// was recorded at every sample.
#[test]
fn the_contact_load_is_plotted_beside_the_net_contact_force() {
    let demo = Demo::textbook().unwrap();
    let mut input = demo.input("load");
    let html = write_report_with(&input, None).unwrap().html;
    assert!(html.contains("pushes from opposite sides cancel") && !html.contains("plot-contact-load") && !html.contains("contact load below"));
    input.contact_load_n = vec![120.0; input.history.samples.len()];
    let html = write_report_with(&input, None).unwrap().html;
    assert!(html.contains("id=\"plot-contact-load\"") && html.contains("the sum of the sizes of the bone") && html.contains("contact load below"));
    input.contact_load_n.pop();
    assert!(!write_report_with(&input, None).unwrap().html.contains("plot-contact-load"));
    input.contact_load_n.push(f64::NAN);
    assert!(write_report_with(&input, None).is_err());
}

/// A counted movement the head had lost by its birth is flagged in its
/// row and explained under the timeline; the textbook's are not.
#[test]
fn a_movement_lost_by_the_birth_is_flagged() {
    let mut demo = Demo::textbook().unwrap();
    let html = write_report_with(&demo.input("held"), None).unwrap().html;
    assert!(!html.contains("not-held") && !html.contains("observed, not held"));
    demo.detector.not_held_at_birth = vec![carus_analysis::NotHeldAtBirth {
        movement: "extension".into(),
        reason: "the head was born at phi +19.8 deg".into(),
    }];
    let html = write_report_with(&demo.input("lost"), None).unwrap().html;
    let whole_row = |key: &str| {
        let start = html.find(&format!("<div class=\"row\" data-movement=\"{key}\"")).unwrap();
        html[start..start + html[start..].find("</div>").unwrap()].to_string()
    };
    assert!(whole_row("extension").contains("observed, not held"));
    assert!(!whole_row("internal_rotation").contains("not held"));
    let at = html.find("data-note=\"not-held\"").expect("the note");
    assert!(at < html.find("id=\"plots\"").unwrap(), "under the timeline");
    let note = &html[at..at + html[at..].find("</p>").unwrap()];
    assert!(note.contains("<b>Extension not held at birth:</b> the head was born at phi +19.8 deg."), "{note}");
    // The headline's count says so too, with the position born in.
    let born = demo.detector.head_born.expect("the textbook is born");
    let sub = format!(
        "7 of 7 cardinal movements observed, extension not held at birth (the head was born {}, phi {:+.0}&deg;)",
        born.occiput_position(),
        born.phi_deg
    );
    assert!(html.contains(&sub), "{sub}");
}

/// Forces given for a key moment's sample are drawn as arrows in its
/// pictures and listed under it in their colours, with the scale said once;
/// a page without them says nothing of arrows.
#[test]
fn the_forces_at_a_key_moment_are_drawn_and_listed() {
    let demo = Demo::textbook().unwrap();
    let plain = write_report(&demo.input("no forces")).unwrap().html;
    assert!(!plain.contains("Arrows:") && !plain.contains("class=\"forces\""));

    let mut input = demo.input("forces");
    let (moments, _) = carus_analysis::moments::key_moments(&demo.detector);
    let sample = moments[1].sample;
    let head = demo.history.samples[sample].head.position_m.as_vec3().to_array();
    let arrow = carus_render::RenderMesh::arrow("force: sacrum", [head[0], head[1] - 0.1, head[2]], [head[0], head[1] - 0.05, head[2]], 0.0015, [0.15, 0.35, 0.9]);
    input.scene.as_mut().unwrap().forces = vec![SampleForces {
        sample,
        arrows: vec![arrow],
        listed: vec![("sacrum".into(), 100.0, [0.15, 0.35, 0.9])],
    }];
    let report = write_report(&input).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let html = &report.html;
    assert!(html.contains("Arrows: the forces on the fetus") && html.contains("10 mm per 20 N"), "legend");
    assert_eq!(html.matches("class=\"forces\"").count(), 1);
    assert!(html.contains("<span style=\"color:#2659e6\">&#9632;</span> sacrum 100 N"));
    // The arrow is in that moment's pictures, and only there.
    let pictures = |html: &str| -> Vec<String> {
        html.split("src=\"data:image/png;base64,").skip(1).map(|rest| rest[..rest.find('"').unwrap()].to_string()).collect()
    };
    let (with, without) = (pictures(html), pictures(&plain));
    let changed: Vec<usize> = (0..with.len()).filter(|&i| with[i] != without[i]).collect();
    assert!(!changed.is_empty() && changed.iter().all(|&i| i / 2 == 1), "{changed:?}");
}

/// The fontanelles ride on the head in every moment's pictures, so the
/// occiput's position reads off them, and the legend names their colours.
#[test]
fn the_fontanelles_mark_the_head_in_the_pictures() {
    let demo = Demo::textbook().unwrap();
    let input = demo.input("fontanelles");
    let scene = input.scene.as_ref().unwrap();
    let (moments, _) = carus_analysis::moments::key_moments(&demo.detector);
    let sample = moments[1].sample;
    let (meshes, _) = crate::pictures::meshes_at_sample(scene, &demo.history, sample, None);
    let centre = |name: &str| {
        let mesh = meshes.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no {name}"));
        mesh.positions.iter().map(|p| glam::Vec3::from(*p)).sum::<glam::Vec3>() / mesh.positions.len() as f32
    };
    let pose = &demo.history.samples[sample].head;
    for (name, landmark) in [("posterior fontanelle", demo.fetus.head.landmarks.lambda), ("anterior fontanelle", demo.fetus.head.landmarks.bregma)] {
        let at = pose.point(landmark).as_vec3();
        // The mean of the ball's vertices: its seam repeats some, a tenth of a millimetre off.
        assert!(centre(name).distance(at) < 3e-4, "{name}: {} against {at}", centre(name));
    }
    let html = write_report(&input).unwrap().html;
    assert!(html.contains("the posterior fontanelle <span style=\"color:#1a246b\">&#9679;</span> (the occiput lies behind it)"));

    let mut unmarked = demo.input("unmarked");
    unmarked.scene.as_mut().unwrap().fontanelles = None;
    let plain = write_report(&unmarked).unwrap().html;
    assert!(!plain.contains("fontanelle"));
    let pictures = |html: &str| -> Vec<String> {
        html.split("src=\"data:image/png;base64,").skip(1).map(|rest| rest[..rest.find('"').unwrap()].to_string()).collect()
    };
    let (with, without) = (pictures(&html), pictures(&plain));
    for moment in 0..moments.len() {
        assert!((0..2).any(|view| with[2 * moment + view] != without[2 * moment + view]), "moment {moment} drawn without its fontanelles");
    }
}
