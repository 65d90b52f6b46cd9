//! The detector on hand-built pose histories (issue 4, "The bar it must
//! clear": a textbook trajectory shows all seven movements, a straight push
//! only engagement and descent), plus the arrest and posterior cases.

use carus_analysis::synthetic::{self, reference_canal};
use carus_analysis::{detect, ArrestStage, DetectorReport, FetalPart, HeadBorn, Movement, PoseHistory, Unit};
use std::sync::OnceLock;

fn textbook() -> &'static (PoseHistory, DetectorReport) {
    static CELL: OnceLock<(PoseHistory, DetectorReport)> = OnceLock::new();
    CELL.get_or_init(|| {
        let history = synthetic::textbook(&reference_canal());
        let report = detect(&history).unwrap();
        (history, report)
    })
}

fn observed(m: &Movement) -> (f64, f64, f64) {
    assert!(m.observed, "{m:?}");
    let (start, end, size) = (m.start_s.unwrap(), m.end_s.unwrap(), m.size.unwrap());
    assert!(start <= end, "{m:?}");
    (start, end, size)
}

fn absent(m: &Movement) {
    assert!(
        !m.observed && m.start_s.is_none() && m.end_s.is_none() && m.size.is_none(),
        "{m:?}"
    );
}

#[test]
fn the_textbook_labour_shows_all_seven_in_order() {
    let (_, r) = textbook();
    let m = &r.movements;
    for (key, movement) in m.by_key() {
        assert!(movement.observed, "{key} not observed");
    }
    let engagement = observed(&m.engagement);
    let descent = observed(&m.descent);
    let flexion = observed(&m.flexion);
    let internal = observed(&m.internal_rotation);
    let extension = observed(&m.extension);
    let external = observed(&m.external_rotation);
    let expulsion = observed(&m.expulsion);

    // Sizes: the plan flexes 25 degrees, rotates 90 (LOT to OA), extends 70,
    // restitutes and turns externally 90; the leading point enters the inlet
    // about 50-60 mm before the biparietal plane does.
    assert!((flexion.2 - 25.0).abs() < 2.0, "flexion {flexion:?}");
    assert!(
        (internal.2 - 90.0).abs() < 3.0,
        "internal rotation {internal:?}"
    );
    assert!((extension.2 - 70.0).abs() < 3.0, "extension {extension:?}");
    assert!(
        (external.2 - 90.0).abs() < 3.0,
        "external rotation {external:?}"
    );
    assert!(
        (45.0..70.0).contains(&engagement.2),
        "engagement {engagement:?}"
    );
    assert!(descent.2 > 100.0, "descent {descent:?}");
    assert!(expulsion.2 > 0.0);
    assert_eq!(m.engagement.unit, Unit::Mm);
    assert_eq!(m.internal_rotation.unit, Unit::Deg);

    // Textbook order: flexion before internal rotation, internal rotation
    // before extension, extension before restitution, which comes before
    // the trunk is out; engagement ends before internal rotation starts.
    assert!(flexion.1 <= internal.0);
    assert!(engagement.1 <= internal.0);
    assert!(internal.1 <= extension.0);
    assert!(extension.1 <= external.0);
    assert!(expulsion.1 > external.0);
    // Descent runs until the head is delivered.
    let delivered_at = r.series.time_s[r.series.head_delivered.iter().position(|&d| d).unwrap()];
    assert!(descent.1 <= delivered_at);
    assert!(r.outcome.delivered && r.outcome.arrest.is_none());
    absent(&r.posterior_rotation);
    assert!((r.contraction_period_s.unwrap() - 10.0).abs() < 0.11);
}

#[test]
fn the_internal_rotation_happens_between_the_stations_of_the_rule() {
    let (_, r) = textbook();
    let s = &r.series;
    let (start, end, _) = observed(&r.movements.internal_rotation);
    for (i, &t) in s.time_s.iter().enumerate() {
        if t == start || t == end {
            assert!(
                (-20.0..=50.0).contains(&s.station_mm[i]),
                "station {} at {t}",
                s.station_mm[i]
            );
        }
    }
}

#[test]
fn a_straight_push_shows_only_engagement_and_descent() {
    let r = detect(&synthetic::straight_push(&reference_canal())).unwrap();
    let m = &r.movements;
    observed(&m.engagement);
    let descent = observed(&m.descent);
    assert!(descent.2 >= 30.0);
    for movement in [
        &m.flexion,
        &m.internal_rotation,
        &m.extension,
        &m.external_rotation,
        &m.expulsion,
    ] {
        absent(movement);
    }
    absent(&r.posterior_rotation);
    // Phi never moves; theta only by the 5 degrees of flexion seen in the
    // cross-section as the canal tilts forward (5 sin(tilt) < 2 degrees).
    for (&theta, &phi) in r.series.theta_deg.iter().zip(&r.series.phi_deg) {
        assert!(
            (theta + 90.0).abs() < 2.0 && (phi - 5.0).abs() < 1e-6,
            "theta {theta} phi {phi}"
        );
    }
    // Still descending when the run stops: neither delivered nor arrested.
    assert!(!r.outcome.delivered && r.outcome.arrest.is_none());
}

#[test]
fn a_head_held_above_the_inlet_is_an_inlet_arrest() {
    let r = detect(&synthetic::inlet_arrest(&reference_canal())).unwrap();
    absent(&r.movements.engagement);
    absent(&r.movements.descent);
    assert!(!r.outcome.delivered);
    let arrest = r.outcome.arrest.as_ref().expect("arrest");
    assert_eq!(arrest.stage, ArrestStage::Inlet);
    assert_eq!((arrest.against.as_str(), arrest.part.as_str()), ("symphysis", "head"));
    // The deepest station of the final window, not the last sample's.
    let max = r
        .series
        .station_mm
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(arrest.station_mm <= max && arrest.station_mm > max - 1.0);
}

#[test]
fn a_rotation_to_direct_op_is_posterior_not_internal() {
    let r = detect(&synthetic::direct_occiput_posterior(&reference_canal())).unwrap();
    absent(&r.movements.internal_rotation);
    let posterior = observed(&r.posterior_rotation);
    assert!((posterior.2 - 90.0).abs() < 3.0, "{posterior:?}");
    assert_eq!(r.posterior_rotation.unit, Unit::Deg);
}

/// Restitution is a turn back to the side the occiput had at engagement,
/// from wherever the head was born: from OP as from OA.
#[test]
fn a_head_born_op_restitutes_towards_its_engagement_side() {
    let canal = reference_canal();
    let outlet = canal.outlet_sigma() * 1e3;
    let at = |station| synthetic::centre_sigma_at_station(&canal, station);
    let mut plan = synthetic::textbook_plan(&canal);
    // Engaged LOT (-90), turned back to OP (-180), born there, then back
    // to LOT once out.
    plan.theta_ramps[0] = synthetic::Ramp { from_mm: at(0.0), to_mm: at(40.0), by: -90.0 };
    plan.theta_ramps[1] = synthetic::Ramp { from_mm: outlet + 10.0, to_mm: outlet + 30.0, by: 90.0 };
    plan.theta_ramps.truncate(2);
    let r = detect(&plan.history(&canal)).unwrap();
    let born = r.head_born.expect("delivered");
    assert!((wrap(born.theta_deg).abs() - 180.0).abs() < 3.0, "{born}");
    observed(&r.posterior_rotation);
    let restitution = observed(&r.movements.external_rotation);
    assert!((restitution.2 - 90.0).abs() < 3.0, "{restitution:?}");
    // Past the side (from LOT on towards OP) is no turn back to it.
    let mut past = synthetic::textbook_plan(&canal);
    past.theta_ramps[0] = synthetic::Ramp { from_mm: at(0.0), to_mm: at(40.0), by: 0.0 };
    past.theta_ramps[1] = synthetic::Ramp { from_mm: outlet + 10.0, to_mm: outlet + 30.0, by: -60.0 };
    past.theta_ramps.truncate(2);
    absent(&detect(&past.history(&canal)).unwrap().movements.external_rotation);
}

fn wrap(deg: f64) -> f64 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

#[test]
fn the_json_shape_is_the_canonical_one() {
    let (_, r) = textbook();
    let json = serde_json::to_value(r).unwrap();
    for key in [
        "engagement",
        "descent",
        "flexion",
        "internal_rotation",
        "extension",
        "external_rotation",
        "expulsion",
    ] {
        let m = &json["movements"][key];
        for field in ["observed", "start_s", "end_s", "size", "unit"] {
            assert!(m.get(field).is_some(), "{key}.{field} missing");
        }
    }
    assert_eq!(json["movements"]["descent"]["unit"], "mm");
    assert_eq!(json["movements"]["flexion"]["unit"], "deg");
    assert_eq!(
        json["posterior_rotation"]["start_s"],
        serde_json::Value::Null
    );
    assert_eq!(json["outcome"]["delivered"], true);
    assert_eq!(json["outcome"]["arrest"], serde_json::Value::Null);
    assert!(json["series"]["station_mm"].as_array().unwrap().len() > 100);

    let arrest = detect(&synthetic::inlet_arrest(&reference_canal())).unwrap();
    let json = serde_json::to_value(&arrest.outcome).unwrap();
    assert_eq!(json["arrest"]["stage"], "inlet");
    assert_eq!(json["arrest"]["against"], "symphysis");
    assert!(json["arrest"]["station_mm"].is_number());
}

#[test]
fn history_and_report_survive_a_json_round_trip() {
    let (history, report) = textbook();
    let text = history.to_json_string().unwrap();
    let back = PoseHistory::from_json_str(&text).unwrap();
    assert!(
        back == *history,
        "the history changed in the JSON round trip"
    );
    let report_back: DetectorReport =
        serde_json::from_str(&serde_json::to_string(report).unwrap()).unwrap();
    assert!(
        report_back == *report,
        "the report changed in the JSON round trip"
    );
}

/// The per-sample measures run in parallel: one thread or several give
/// the same report, bit for bit.
#[test]
fn the_report_does_not_depend_on_the_thread_count() {
    let (history, _) = textbook();
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        serde_json::to_string(&pool.install(|| detect(history)).unwrap()).unwrap()
    };
    assert_eq!(on(1), on(3));
}

#[test]
fn moving_the_time_origin_moves_every_movement_with_it() {
    let history = synthetic::direct_occiput_posterior(&reference_canal());
    let base = detect(&history).unwrap();
    let mut shifted = history.clone();
    let offset = 1234.5;
    for s in &mut shifted.samples {
        s.time_s += offset;
    }
    let moved = detect(&shifted).unwrap();
    let pairs = base
        .movements
        .by_key()
        .into_iter()
        .zip(moved.movements.by_key())
        .map(|((_, a), (_, b))| (*a, *b));
    for (a, b) in pairs.chain([(base.posterior_rotation, moved.posterior_rotation)]) {
        assert_eq!(a.observed, b.observed);
        assert_eq!(a.size, b.size);
        if let (Some(x), Some(y)) = (a.start_s, b.start_s) {
            assert!((y - x - offset).abs() < 1e-9);
        }
        if let (Some(x), Some(y)) = (a.end_s, b.end_s) {
            assert!((y - x - offset).abs() < 1e-9);
        }
    }
    assert_eq!(base.outcome, moved.outcome);
}

#[test]
fn the_series_table_has_one_row_per_sample() {
    let (history, report) = textbook();
    let (columns, rows) = report.series.table();
    assert_eq!(rows.len(), history.samples.len());
    assert!(rows.iter().all(|r| r.len() == columns.len()));
    assert_eq!(
        &columns[..4],
        &["time_s", "station_mm", "theta_deg", "phi_deg"]
    );
    // The straight push has no trunk: its shoulder columns are empty.
    let push = detect(&synthetic::straight_push(&reference_canal())).unwrap();
    let (columns, rows) = push.series.table();
    let shoulders = columns
        .iter()
        .position(|&c| c == "shoulders_sigma_mm")
        .unwrap();
    assert!(rows.iter().all(|r| r[shoulders].is_none()));
}

#[test]
fn bad_histories_are_refused_with_the_sample_named() {
    let (history, _) = textbook();
    let mut h = history.clone();
    h.samples[7].time_s = h.samples[6].time_s;
    let err = detect(&h).unwrap_err().to_string();
    assert!(err.contains("sample 7"), "{err}");
    let mut h = history.clone();
    h.samples[3].head.orientation *= 2.0;
    assert!(detect(&h).unwrap_err().to_string().contains("sample 3"));
    let mut h = history.clone();
    h.samples[5].trunk = None;
    assert!(detect(&h).unwrap_err().to_string().contains("sample 5"));
    let mut h = history.clone();
    h.samples.truncate(1);
    assert!(detect(&h).is_err());
    let mut h = history.clone();
    h.samples[2].expulsion_force_n.x = f64::NAN;
    assert!(detect(&h)
        .unwrap_err()
        .to_string()
        .contains("expulsion_force_n"));
    assert!(PoseHistory::from_json_str("{\"head\": 1}").is_err());
}

/// A history written in millimetres is refused with the fix, not read as
/// a fetus metres away from the pelvis.
#[test]
fn lengths_in_millimetres_are_refused_with_the_fix() {
    let (history, _) = textbook();
    let mut h = history.clone();
    h.samples[4].head.position_m *= 1000.0;
    let err = detect(&h).unwrap_err().to_string();
    assert!(err.contains("sample 4") && err.contains("head.position_m") && err.contains("millimetres"), "{err}");
    let mut h = history.clone();
    for s in &mut h.samples {
        let trunk = s.trunk.as_mut().unwrap();
        trunk.position_m *= 1000.0;
    }
    let err = detect(&h).unwrap_err().to_string();
    assert!(err.contains("sample 0") && err.contains("trunk.position_m"), "{err}");
    let mut h = history.clone();
    for p in &mut h.head.skull_points_m {
        *p *= 1000.0;
    }
    let err = detect(&h).unwrap_err().to_string();
    assert!(err.contains("skull point") && err.contains("millimetres"), "{err}");
    let mut h = history.clone();
    h.head.biparietal_mm = 0.095;
    let err = detect(&h).unwrap_err().to_string();
    assert!(err.contains("biparietal_mm = 0.095"), "{err}");
    // Every run's own history lies well inside the bound.
    assert!(detect(history).is_ok());
}

/// The textbook labour held with the head centre at `hold_mm` sigma for
/// four contractions, pressing on `site`.
fn held(hold_mm: f64, site: carus_analysis::ContactSite) -> DetectorReport {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.hold_sigma_mm = hold_mm;
    plan.duration_s = (hold_mm - plan.start_sigma_mm) / plan.advance_mm_per_s + 4.0 * plan.period_s;
    plan.contact = Some(site);
    detect(&plan.history(&canal)).unwrap()
}

#[test]
fn arrests_are_placed_by_where_the_head_stopped() {
    use carus_analysis::ContactSite;
    let canal = reference_canal();
    let spines = canal.spines_sigma() * 1000.0;
    let cases = [
        (
            spines - 20.0,
            ContactSite::IschialSpines,
            ArrestStage::MidPelvis,
            "ischial_spines",
        ),
        (
            spines + 15.0,
            ContactSite::Coccyx,
            ArrestStage::Outlet,
            "coccyx",
        ),
    ];
    for (hold, site, stage, against) in cases {
        let r = held(hold, site);
        assert!(!r.outcome.delivered);
        let arrest = r
            .outcome
            .arrest
            .as_ref()
            .unwrap_or_else(|| panic!("no arrest held at {hold}"));
        assert_eq!(arrest.stage, stage);
        assert_eq!(arrest.against, against);
        observed(&r.movements.engagement);
        absent(&r.movements.extension);
    }
}

#[test]
fn large_shoulders_deliver_the_head_then_arrest() {
    let r = detect(&synthetic::shoulder_arrest(&reference_canal())).unwrap();
    assert!(r.series.head_delivered.last().copied().unwrap());
    assert!(!r.outcome.delivered);
    let arrest = r.outcome.arrest.as_ref().expect("shoulder arrest");
    assert_eq!(arrest.stage, ArrestStage::Shoulders);
    assert_eq!(arrest.against, "symphysis");
    // The shoulders' station: above the outlet, below the spines.
    let outlet = reference_canal().outlet_sigma() - reference_canal().spines_sigma();
    assert!(
        arrest.station_mm > 0.0 && arrest.station_mm < outlet * 1000.0,
        "{arrest:?}"
    );
    observed(&r.movements.extension);
    absent(&r.movements.expulsion);
    // A shoulder arrest's station is already the shoulders'.
    assert_eq!(arrest.shoulders_station_mm, Some(arrest.station_mm));
    assert_eq!(arrest.shoulders_holding_head(), None);
}

/// A head held short of the outlet by its trunk: the arrest says where the
/// shoulders stood at the moment it reads the station, behind the head by
/// its own length and the neck's; without a trunk it cannot say.
#[test]
fn a_trunk_that_holds_the_head_back_says_where_its_shoulders_stood() {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.hold_sigma_mm = canal.outlet_sigma() * 1000.0 - 10.0;
    plan.contact = Some(carus_analysis::ContactSite::PelvicSidewall);
    let reach_s = (plan.hold_sigma_mm - plan.start_sigma_mm) / plan.advance_mm_per_s;
    plan.duration_s = reach_s + 5.0 * plan.period_s;
    let mut history = plan.history(&canal);
    for s in &mut history.samples {
        s.dominant_part = Some(FetalPart::Trunk);
    }
    let r = detect(&history).unwrap();
    let arrest = r.outcome.arrest.as_ref().expect("arrest");
    assert_eq!((arrest.stage, arrest.part.as_str()), (ArrestStage::Outlet, "trunk"));
    let shoulders = arrest.shoulders_station_mm.expect("a trunk is modelled");
    assert_eq!(arrest.shoulders_holding_head(), Some(shoulders));
    // Read at the same sample as the head's station, behind the leading
    // point by the head's length and the neck's.
    let spines = canal.spines_sigma() * 1000.0;
    let same_sample = r
        .series
        .station_mm
        .iter()
        .zip(r.series.shoulders_sigma_mm.as_ref().unwrap())
        .any(|(&station, &s)| station == arrest.station_mm && s - spines == shoulders);
    assert!(same_sample, "{arrest:?}");
    assert!(arrest.station_mm - shoulders > 60.0, "{arrest:?}");

    // The inlet arrest's history has no trunk.
    let headless = synthetic::inlet_arrest(&canal);
    assert_eq!(detect(&headless).unwrap().outcome.arrest.unwrap().shoulders_station_mm, None);
}

/// A head that turns to occiput anterior only below station +50 mm: the
/// rule does not count it, and the report says where it happened; the
/// textbook's turn, inside the window, needs no such note.
#[test]
fn a_rotation_past_the_window_is_not_counted_but_said() {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    // No extension, which would move the leading point off the vertex and
    // the stations with it.
    plan.phi_ramps.truncate(1);
    plan.theta_ramps[0] = synthetic::Ramp {
        from_mm: synthetic::centre_sigma_at_station(&canal, 52.0),
        to_mm: synthetic::centre_sigma_at_station(&canal, 64.0),
        by: 90.0,
    };
    let r = detect(&plan.history(&canal)).unwrap();
    absent(&r.movements.internal_rotation);
    let late = r.internal_rotation_outside_window.expect("the late turn is reported");
    assert!(late.station_mm > 52.0 && late.station_mm < 64.0, "{late:?}");
    // The first sample at 20 degrees or less of OA, before the head is born.
    let first = r.series.time_s.iter().position(|&t| t == late.time_s).unwrap();
    assert!(r.series.theta_deg[first].abs() <= 20.0 && r.series.theta_deg[first - 1].abs() > 20.0);
    assert!(!r.series.head_delivered[first]);
    assert_eq!(textbook().1.internal_rotation_outside_window, None);

    // A turn begun above the window and ended inside it is not counted
    // either, but it did not happen outside the window: no note.
    plan.theta_ramps[0] = synthetic::Ramp {
        from_mm: synthetic::centre_sigma_at_station(&canal, -50.0),
        to_mm: synthetic::centre_sigma_at_station(&canal, 0.0),
        by: 90.0,
    };
    let r = detect(&plan.history(&canal)).unwrap();
    absent(&r.movements.internal_rotation);
    assert_eq!(r.internal_rotation_outside_window, None);
}

/// A run stopped within its first contractions (too few to time) is
/// neither delivered nor arrested, even in a pause between two pushes:
/// too soon to tell. The same head held for ten contractions is an arrest.
#[test]
fn a_run_stopped_in_its_first_contractions_is_not_an_arrest() {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.hold_sigma_mm = -35.0;
    plan.drift_mm = 5.0;
    plan.contact = Some(carus_analysis::ContactSite::Symphysis);
    for periods in [0.1, 0.6, 1.5] {
        plan.duration_s = periods * plan.period_s;
        let r = detect(&plan.history(&canal)).unwrap();
        assert!(!r.outcome.delivered && r.outcome.arrest.is_none(), "{periods} periods: {:?}", r.outcome);
    }
    plan.duration_s = 10.0 * plan.period_s;
    assert_eq!(detect(&plan.history(&canal)).unwrap().outcome.arrest.unwrap().stage, ArrestStage::Inlet);
    // Nothing has pushed the fetus yet (a run of a step or two, its force
    // still at zero): too soon to tell, however long the history.
    let unpushed = synthetic::Plan { force_mean_n: 0.0, force_swing_n: 0.0, ..plan };
    assert_eq!(detect(&unpushed.history(&canal)).unwrap().outcome.arrest, None);
}

/// A short history under a steady push (no contractions) that is still
/// moving at its end is not an arrest, though its final quarter gains
/// under 3 mm; the same head stopped for most of a longer history is.
#[test]
fn a_head_still_moving_under_a_steady_push_is_not_arrested() {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.start_sigma_mm = -80.0;
    plan.advance_mm_per_s = 5.0;
    plan.drift_mm = 0.0;
    plan.force_mean_n = 50.0;
    plan.force_swing_n = 0.0;
    plan.sample_interval_s = 0.1;
    plan.duration_s = 1.9;
    plan.contact = None;
    let r = detect(&plan.history(&canal)).unwrap();
    assert!(!r.outcome.delivered && r.outcome.arrest.is_none(), "{:?}", r.outcome);
    // Stopped at -75 mm after one second of a ten-second push: held.
    plan.hold_sigma_mm = -75.0;
    plan.duration_s = 10.0;
    assert_eq!(detect(&plan.history(&canal)).unwrap().outcome.arrest.unwrap().stage, ArrestStage::Inlet);
}

/// The turtle sign: a head born at the height of each contraction that
/// slips back inside between them is out, whatever phase of the contraction
/// the run ends in; the stage and the station describe the same moment.
#[test]
fn a_head_that_slips_back_between_contractions_is_a_shoulder_arrest() {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.hold_sigma_mm = canal.outlet_sigma() * 1000.0 + 3.0;
    plan.contact = Some(carus_analysis::ContactSite::Symphysis);
    let reach_s = (plan.hold_sigma_mm - plan.start_sigma_mm) / plan.advance_mm_per_s;
    let mut ends_out_and_in = (false, false);
    for quarter in 0..4 {
        plan.duration_s = (reach_s / plan.period_s).ceil() * plan.period_s
            + 4.0 * plan.period_s
            + 0.25 * f64::from(quarter) * plan.period_s;
        let r = detect(&plan.history(&canal)).unwrap();
        let out_at_end = r.series.head_delivered.last().copied().unwrap();
        ends_out_and_in.0 |= out_at_end;
        ends_out_and_in.1 |= !out_at_end;
        assert!(!r.outcome.delivered);
        let arrest = r.outcome.arrest.as_ref().expect("arrest");
        assert_eq!(arrest.stage, ArrestStage::Shoulders, "ending at quarter {quarter}");
        assert_eq!(arrest.against, "symphysis");
    }
    // The runs end both with the head out and with it slipped back.
    assert_eq!(ends_out_and_in, (true, true));
}

#[test]
fn an_undelivered_head_without_a_contact_record_is_against_unknown() {
    let mut history = synthetic::inlet_arrest(&reference_canal());
    for s in &mut history.samples {
        s.dominant_contact = None;
    }
    let r = detect(&history).unwrap();
    assert_eq!(r.outcome.arrest.unwrap().against, "unknown");
}

/// The arrest names the fetal body that bore the hardest contact: the
/// trunk when the shoulders are what holds the fetus back.
#[test]
fn an_arrest_names_the_fetal_part_held() {
    let mut history = synthetic::inlet_arrest(&reference_canal());
    for s in &mut history.samples {
        s.dominant_part = Some(FetalPart::Trunk);
    }
    let arrest = detect(&history).unwrap().outcome.arrest.unwrap();
    assert_eq!((arrest.against.as_str(), arrest.part.as_str()), ("symphysis", "trunk"));
    for s in &mut history.samples {
        s.dominant_part = None;
    }
    assert_eq!(detect(&history).unwrap().outcome.arrest.unwrap().part, "unknown");
}

/// The textbook plan run through the generated gynecoid pelvis with the
/// average term fetus of carus-anatomy (its real head surface and trunk):
/// the detector sees all seven there too.
#[test]
fn the_textbook_plan_in_the_generated_pelvis_with_the_term_fetus() {
    use carus_analysis::{BirthCanal, HeadGeometry, TrunkGeometry};
    use carus_anatomy::fetus::Fetus;
    use carus_anatomy::pelvis::PelvisDiameters;
    use carus_anatomy::Pelvis;
    let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
    let canal = BirthCanal::from_pelvis(&pelvis).unwrap();
    let fetus = Fetus::term().unwrap();
    let head = HeadGeometry::from_fetal_head(&fetus.head);
    let trunk = TrunkGeometry::from_trunk(&fetus.trunk);
    let history = synthetic::textbook_plan(&canal).history_with(&canal, &head, &trunk);
    let r = detect(&history).unwrap();
    for (key, movement) in r.movements.by_key() {
        assert!(movement.observed, "{key} not observed: {movement:?}");
    }
    assert!(r.outcome.delivered);
    // The head's own biparietal diameter is what engagement uses.
    assert_eq!(
        history.head.biparietal_mm,
        fetus.head.diameters.biparietal_mm
    );
}

/// How the head was born is read at its first delivered sample: the
/// textbook head leaves occiput anterior, extending; a head that never
/// passes the outlet has no such sample.
#[test]
fn the_head_born_is_read_at_its_first_delivered_sample() {
    let (_, report) = textbook();
    let born = report.head_born.expect("the textbook head is delivered");
    let first = report.series.head_delivered.iter().position(|&d| d).unwrap();
    assert_eq!(born.time_s, report.series.time_s[first]);
    assert_eq!(born.phi_deg, report.series.phi_deg[first]);
    assert_eq!(born.occiput_position(), "OA");
    // Born as it extends: phi is already 30 deg past the flexion peak.
    let peak = report.movements.flexion.end_s.unwrap();
    let at_peak = report.series.time_s.iter().position(|&t| t == peak).unwrap();
    assert!(born.phi_deg < report.series.phi_deg[at_peak] - 30.0, "{born}");
    assert!(born.to_string().starts_with("the head was born at 54.8 s, station +90 mm, occiput OA"), "{born}");
    // Clinical names by the nearest eighth of a turn, either way round.
    for (theta_deg, name) in [(0.0, "OA"), (-31.0, "LOA"), (22.4, "OA"), (22.6, "ROA"), (90.0, "ROT"), (-90.0, "LOT"), (135.0, "ROP"), (-135.0, "LOP"), (180.0, "OP"), (-170.0, "OP")] {
        assert_eq!(HeadBorn { theta_deg, ..born }.occiput_position(), name, "{theta_deg}");
    }
    let held = detect(&synthetic::inlet_arrest(&reference_canal())).unwrap();
    assert_eq!(held.head_born, None);
    // A history that begins with the head already out saw no birth.
    let (history, _) = textbook();
    let out_from_the_start = PoseHistory { samples: history.samples[first..].to_vec(), ..history.clone() };
    let r = detect(&out_from_the_start).unwrap();
    assert!(r.outcome.delivered && r.head_born.is_none(), "{:?}", r.head_born);
}

/// The rules count a rotation or an extension where it happens; one the
/// head has lost by its birth (turned back from OA, flexed again) is
/// reported as not held, with the head's figures. The textbook head keeps
/// both.
#[test]
fn movements_lost_before_the_birth_are_reported_as_not_held() {
    let (_, report) = textbook();
    assert!(report.not_held_at_birth.is_empty(), "{:?}", report.not_held_at_birth);
    let canal = reference_canal();
    let outlet = canal.outlet_sigma() * 1e3;
    let at = |station| synthetic::centre_sigma_at_station(&canal, station);
    let mut plan = synthetic::textbook_plan(&canal);
    // Extended by 70 deg between stations +35 and +55, flexed again by the
    // outlet; turned to OA by station +40, then back by 40 deg.
    plan.phi_ramps[1] = synthetic::Ramp { from_mm: at(35.0), to_mm: at(55.0), by: -70.0 };
    plan.phi_ramps.push(synthetic::Ramp { from_mm: at(60.0), to_mm: outlet - 2.0, by: 70.0 });
    plan.theta_ramps.push(synthetic::Ramp { from_mm: at(45.0), to_mm: outlet - 5.0, by: -40.0 });
    let lost = detect(&plan.history(&canal)).unwrap();
    assert!(lost.movements.internal_rotation.observed && lost.movements.extension.observed);
    let born = lost.head_born.expect("delivered");
    let keys: Vec<&str> = lost.not_held_at_birth.iter().map(|n| n.movement.as_str()).collect();
    assert_eq!(keys, ["internal_rotation", "extension"], "{born}");
    let [rotation, extension] = [0, 1].map(|k| lost.not_held_at_birth[k].to_string());
    assert!(rotation.starts_with("internal_rotation not held at birth: the occiput had turned back to LOA (theta -40 deg)"), "{rotation}");
    assert!(extension.contains(&format!("born at phi {:+.1} deg", born.phi_deg)) && extension.ends_with("it was born flexed"), "{extension}");
    // Flexed past where it began: said as more flexed, never as a negative fall.
    assert!(extension.contains("deg of extension were undone before the birth") && extension.contains("more flexed than the"), "{extension}");
    // Flexed again only in part: said as part of the extension undone.
    let mut partly = plan.clone();
    partly.phi_ramps.last_mut().unwrap().by = 55.0;
    let partly = detect(&partly.history(&canal)).unwrap();
    let lost = partly.not_held_at_birth.iter().find(|n| n.movement == "extension").expect("15 deg kept is under the rule's 30");
    let extension = partly.movements.extension;
    let began = partly.series.time_s.iter().position(|&t| Some(t) == extension.start_s).unwrap();
    let kept = partly.series.phi_deg[began] - partly.head_born.unwrap().phi_deg;
    let size = extension.size.unwrap();
    assert!((10.0..20.0).contains(&kept), "{kept}");
    assert!(
        lost.reason.starts_with(&format!("{:.0} of the {size:.0} deg of extension were undone", size - kept))
            && lost.reason.contains(&format!("only {kept:.0} deg less flexed than")),
        "{lost}"
    );

    // Still extending when born, short of the rule's 30 deg: nothing was
    // undone; the rest of the extension came after the birth.
    let mut going_on = synthetic::textbook_plan(&canal);
    going_on.phi_ramps[1] = synthetic::Ramp { from_mm: outlet - 10.0, to_mm: outlet + 30.0, by: -70.0 };
    let going_on = detect(&going_on.history(&canal)).unwrap();
    let born = going_on.head_born.expect("delivered");
    let extension = going_on.movements.extension;
    assert!(extension.observed && extension.end_s.unwrap() > born.time_s, "{extension:?}");
    let lost = going_on.not_held_at_birth.iter().find(|n| n.movement == "extension").expect("under 30 deg by the birth");
    assert!(
        lost.reason.starts_with("only ") && lost.reason.contains("deg of extension had happened by the birth, the rest after it")
            && !lost.reason.contains("undone"),
        "{lost}"
    );

    // An extension that begins only once the head is out was not lost by
    // the birth: it had not happened.
    let mut late = synthetic::textbook_plan(&canal);
    late.phi_ramps[1] = synthetic::Ramp { from_mm: outlet + 5.0, to_mm: outlet + 25.0, by: -70.0 };
    let late = detect(&late.history(&canal)).unwrap();
    let born = late.head_born.expect("delivered");
    let extension = late.movements.extension;
    assert!(extension.observed && extension.start_s.unwrap() > born.time_s, "{extension:?} against {born}");
    assert!(late.not_held_at_birth.iter().all(|n| n.movement != "extension"), "{:?}", late.not_held_at_birth);
}

/// The shoulders' passage: the textbook's come into the inlet oblique (they
/// followed the head's turn half-way, to -45) and its body is born as
/// expulsion ends; the shoulder arrest's body is never born, and its
/// arrest says how the held shoulders lie; without a trunk there is none.
#[test]
fn the_shoulders_passage_reads_their_lie_at_the_inlet_and_the_head_to_body_interval() {
    let (_, r) = textbook();
    let p = r.shoulders.expect("the textbook has a trunk");
    let sigma = r.series.shoulders_sigma_mm.as_ref().unwrap();
    let came = r.series.time_s.iter().position(|&t| Some(t) == p.inlet_s).unwrap();
    assert!(sigma[came] >= 0.0 && sigma[came - 1] < 0.0, "{p:?}");
    // Set along the head's stretch of the canal, read on the shoulders'
    // (the canal curves between them): oblique, within a few degrees.
    let lie = p.inlet_from_ap_deg.unwrap();
    assert!((lie - 45.0).abs() < 5.0, "{p:?}");
    let head = r.head_born.unwrap().time_s;
    let body = r.movements.expulsion.end_s.unwrap();
    assert_eq!((p.body_born_s, p.head_to_body_s), (Some(body), Some(body - head)));
    assert!(body > head);
    assert!((p.head_to_body_periods.unwrap() * r.contraction_period_s.unwrap() - (body - head)).abs() < 1e-9);
    assert_eq!(p.body_not_born_after_s, None);
    assert!(p.to_string().contains(&format!("the bisacromial diameter oblique ({lie:.0} deg from the antero-posterior); the body was born")), "{p}");

    let held = detect(&synthetic::shoulder_arrest(&reference_canal())).unwrap();
    let p = held.shoulders.unwrap();
    assert_eq!((p.body_born_s, p.head_to_body_s, p.head_to_body_periods), (None, None, None));
    let end = *held.series.time_s.last().unwrap();
    assert_eq!(p.body_not_born_after_s, Some(end - held.head_born.unwrap().time_s));
    assert!(p.to_string().ends_with(&format!("the body was not born in the {:.1} s after the head", end - held.head_born.unwrap().time_s)), "{p}");
    // Read at the arrest's own sample, the deepest: the shoulders there
    // partway through their external rotation from oblique towards the
    // antero-posterior (the plan's -45 to -90).
    let arrest = held.outcome.arrest.unwrap();
    let spines = reference_canal().spines_sigma() * 1000.0;
    let sigma = held.series.shoulders_sigma_mm.as_ref().unwrap();
    let stuck = sigma.iter().rposition(|&s| s - spines == arrest.station_mm).unwrap();
    let back = held.series.shoulders_theta_deg.as_ref().unwrap()[stuck];
    assert_eq!(arrest.shoulders_from_ap_deg, Some(carus_analysis::shoulders::from_antero_posterior_deg(back)));
    assert!((10.0..40.0).contains(&arrest.shoulders_from_ap_deg.unwrap()), "{arrest:?}");

    let no_trunk = detect(&synthetic::inlet_arrest(&reference_canal())).unwrap();
    assert_eq!(no_trunk.shoulders, None);
    assert_eq!(no_trunk.outcome.arrest.unwrap().shoulders_from_ap_deg, None);
}
