//! The clinical sanity cases judged on hand-built histories: each case is
//! met by the history that shows its expected outcome and not by the others.

use carus_analysis::sanity::{SanityCase, NEAR_OUTLET_MM};
use carus_analysis::synthetic::{self, reference_canal};
use carus_analysis::{detect, ContactSite, DetectorReport, PoseHistory};

fn outlet_station_mm() -> f64 {
    let canal = reference_canal();
    (canal.outlet_sigma() - canal.spines_sigma()) * 1000.0
}

fn report(history: &PoseHistory) -> DetectorReport {
    detect(history).unwrap()
}

/// The textbook labour held with its head centre `short_mm` before the
/// outlet (more than the plan's 8 mm rocking, so never out), pressed on
/// `site`.
fn held_short(short_mm: f64, site: ContactSite) -> DetectorReport {
    let canal = reference_canal();
    let mut plan = synthetic::textbook_plan(&canal);
    plan.hold_sigma_mm = canal.outlet_sigma() * 1000.0 - short_mm;
    plan.contact = Some(site);
    plan.duration_s = (plan.hold_sigma_mm - plan.start_sigma_mm) / plan.advance_mm_per_s + 5.0 * plan.period_s;
    report(&plan.history(&canal))
}

fn met(case: SanityCase, report: &DetectorReport) -> bool {
    case.judge(report, outlet_station_mm()).met
}

#[test]
fn each_case_is_met_by_its_own_outcome_only() {
    let canal = reference_canal();
    let textbook = report(&synthetic::textbook(&canal));
    let straight = report(&synthetic::straight_push(&canal));
    let inlet = report(&synthetic::inlet_arrest(&canal));
    let shoulders = report(&synthetic::shoulder_arrest(&canal));
    let outlet = held_short(15.0, ContactSite::PelvicSidewall);

    assert!(met(SanityCase::Normal, &textbook));
    for other in [&straight, &inlet, &shoulders, &outlet] {
        assert!(!met(SanityCase::Normal, other));
    }
    let v = SanityCase::Normal.judge(&straight, outlet_station_mm());
    assert_eq!(v.why, "not delivered");

    assert!(met(SanityCase::ContractedInlet, &inlet));
    // The straight push is still descending when it ends: no arrest.
    assert!(straight.outcome.arrest.is_none());
    for other in [&textbook, &straight, &shoulders, &outlet] {
        assert!(!met(SanityCase::ContractedInlet, other));
    }

    assert!(met(SanityCase::LargeShoulders, &shoulders), "{:?}", SanityCase::LargeShoulders.judge(&shoulders, 0.0));
    // What holds them is told with how they lie.
    let v = SanityCase::LargeShoulders.judge(&shoulders, 0.0);
    let lie = shoulders.outcome.arrest.as_ref().unwrap().shoulders_from_ap_deg.unwrap();
    assert!(v.why.ends_with(&format!("the trunk against the symphysis, the bisacromial diameter {lie:.0} deg from the antero-posterior")), "{}", v.why);
    for other in [&textbook, &inlet, &outlet] {
        assert!(!met(SanityCase::LargeShoulders, other));
    }
    let v = SanityCase::LargeShoulders.judge(&outlet, outlet_station_mm());
    assert!(v.why.contains("head not delivered") && v.why.contains("outlet stage, the head against the pelvic sidewall"), "{}", v.why);
    // The head born but itself still pressed on the symphysis: not the
    // shoulders held there.
    let mut head_held = shoulders.clone();
    head_held.outcome.arrest.as_mut().unwrap().part = "head".into();
    let v = SanityCase::LargeShoulders.judge(&head_held, 0.0);
    assert!(!v.met && v.why.contains("shoulders stage, the head against the symphysis"), "{}", v.why);

    assert!(!met(SanityCase::Face, &textbook), "a delivery is not an arrest");
    assert!(!met(SanityCase::Face, &inlet), "an inlet arrest is not near the outlet");
    assert!(!met(SanityCase::Face, &straight), "no arrest");
    assert!(!met(SanityCase::Face, &shoulders), "the head was born");
    assert!(met(SanityCase::Face, &outlet), "{:?}", SanityCase::Face.judge(&outlet, outlet_station_mm()));
}

/// "Near the outlet" is the leading point within NEAR_OUTLET_MM of the
/// outlet plane's crossing of the axis, or past it.
#[test]
fn near_the_outlet_is_within_a_centimetre_of_its_plane() {
    let outlet = held_short(15.0, ContactSite::Sacrum);
    let station = outlet.outcome.arrest.as_ref().unwrap().station_mm;
    assert!(SanityCase::Face.judge(&outlet, station + NEAR_OUTLET_MM - 0.1).met);
    let v = SanityCase::Face.judge(&outlet, station + NEAR_OUTLET_MM + 0.1);
    assert!(!v.met && v.why.contains("mm short of"), "{}", v.why);
    assert!(SanityCase::Face.judge(&outlet, station - 3.0).why.contains("3.0 mm past"));
}
