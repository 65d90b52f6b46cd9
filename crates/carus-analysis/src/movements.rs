//! The seven cardinal movements, detected on a [`Series`] by the rules of
//! CARDINAL_MOVEMENTS.md ("When a movement counts as observed").
//!
//! The table says when a movement is observed; where it is silent (when a
//! movement starts and ends, what its size is) the choices are the same for
//! every movement and every run, and docs/DETECTOR.md gives the reasons:
//!
//! - size is the change of the movement's own quantity between the reported
//!   start and end samples (station for engagement and descent, phi for
//!   flexion and extension, theta for the rotations, the trunk centre's
//!   distance past the outlet for expulsion), always given as a magnitude;
//! - start is the last sample at which the quantity was still within a
//!   small onset tolerance of the level it moved away from, end the first
//!   sample at which it came within that tolerance of the level it reached.

use crate::measures::{wrap_deg, Series};
use serde::{Deserialize, Serialize};

/// CARDINAL_MOVEMENTS.md: descent needs a net rise of the station of 30 mm.
pub const DESCENT_MIN_MM: f64 = 30.0;
/// CARDINAL_MOVEMENTS.md: flexion needs phi 10 degrees above its start value...
pub const FLEXION_MIN_DEG: f64 = 10.0;
/// ...before the leading point reaches station +20 mm.
pub const FLEXION_BY_STATION_MM: f64 = 20.0;
/// CARDINAL_MOVEMENTS.md: internal rotation, abs(theta) from at least 45...
pub const ROTATION_FROM_DEG: f64 = 45.0;
/// ...to at most 20 degrees...
pub const ROTATION_TO_DEG: f64 = 20.0;
/// ...while the leading point is between station -20...
pub const ROTATION_STATION_MIN_MM: f64 = -20.0;
/// ...and +50 mm.
pub const ROTATION_STATION_MAX_MM: f64 = 50.0;
/// CARDINAL_MOVEMENTS.md: posterior rotation, abs(theta) from at most 135...
pub const POSTERIOR_FROM_DEG: f64 = 135.0;
/// ...to at least 160 degrees (direct OP).
pub const POSTERIOR_TO_DEG: f64 = 160.0;
/// CARDINAL_MOVEMENTS.md: extension, phi falls by at least 30 degrees...
pub const EXTENSION_MIN_DEG: f64 = 30.0;
/// ...while the station is at least +30 mm.
pub const EXTENSION_FROM_STATION_MM: f64 = 30.0;
/// CARDINAL_MOVEMENTS.md: restitution, theta turns by at least 30 degrees.
pub const RESTITUTION_MIN_DEG: f64 = 30.0;

/// Onset tolerance for stations (detector choice, docs/DETECTOR.md): a
/// movement starts when its quantity leaves its level by more than this;
/// 1 mm is below clinical resolution and above numerical contact jitter.
pub const ONSET_MM: f64 = 1.0;
/// Onset tolerance for angles (detector choice, docs/DETECTOR.md).
pub const ONSET_DEG: f64 = 1.0;
/// Within this many degrees of OA (0) or OP (180) the side of the occiput
/// at engagement is undecided, and restitution may turn either way
/// (detector choice, docs/DETECTOR.md).
pub const SIDE_UNDECIDED_DEG: f64 = 10.0;

/// Unit of a movement's size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    Mm,
    Deg,
}

/// One movement as CONVENTIONS.md spells it: start, end and size are null
/// when the movement was not observed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Movement {
    pub observed: bool,
    pub start_s: Option<f64>,
    pub end_s: Option<f64>,
    pub size: Option<f64>,
    pub unit: Unit,
}

impl Movement {
    /// Not observed: no start, end or size.
    pub fn absent(unit: Unit) -> Self {
        Movement {
            observed: false,
            start_s: None,
            end_s: None,
            size: None,
            unit,
        }
    }

    fn between(series: &Series, span: Span, quantity: &[f64], unit: Unit) -> Self {
        Movement {
            observed: true,
            start_s: Some(series.time_s[span.start]),
            end_s: Some(series.time_s[span.end]),
            size: Some((quantity[span.end] - quantity[span.start]).abs()),
            unit,
        }
    }
}

/// The seven movements under their canonical keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Movements {
    pub engagement: Movement,
    pub descent: Movement,
    pub flexion: Movement,
    pub internal_rotation: Movement,
    pub extension: Movement,
    pub external_rotation: Movement,
    pub expulsion: Movement,
}

impl Movements {
    /// All seven unobserved, each with its unit: what a run that stopped
    /// before there was anything to detect reports.
    pub fn none() -> Self {
        Movements {
            engagement: Movement::absent(Unit::Mm),
            descent: Movement::absent(Unit::Mm),
            flexion: Movement::absent(Unit::Deg),
            internal_rotation: Movement::absent(Unit::Deg),
            extension: Movement::absent(Unit::Deg),
            external_rotation: Movement::absent(Unit::Deg),
            expulsion: Movement::absent(Unit::Mm),
        }
    }

    /// Keys and movements in the textbook order.
    pub fn by_key(&self) -> [(&'static str, &Movement); 7] {
        [
            ("engagement", &self.engagement),
            ("descent", &self.descent),
            ("flexion", &self.flexion),
            ("internal_rotation", &self.internal_rotation),
            ("extension", &self.extension),
            ("external_rotation", &self.external_rotation),
            ("expulsion", &self.expulsion),
        ]
    }
}

/// Sample indices of a movement's start and end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Span {
    start: usize,
    end: usize,
}

/// What the detector found: the seven movements and the posterior rotation
/// reported apart from them.
pub struct Detected {
    pub movements: Movements,
    pub posterior_rotation: Movement,
    pub rotation_outside_window: Option<RotationOutsideWindow>,
    pub head_born: Option<HeadBorn>,
    pub not_held_at_birth: Vec<NotHeldAtBirth>,
}

/// A movement the rules counted whose result the head had lost by the
/// time it was born. CARDINAL_MOVEMENTS.md counts a movement where it
/// happens; the textbooks describe a head born occiput anterior and by
/// extension, so a reader is told when the counted rotation or extension
/// did not last, judged at the birth by the rule's own threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NotHeldAtBirth {
    /// Canonical key: `internal_rotation` or `extension`.
    pub movement: String,
    /// The head at its birth against the rule, in words.
    pub reason: String,
}

/// Which of the counted internal rotation and extension, begun before the
/// head was `born`, it no longer showed then: an occiput further than
/// [`ROTATION_TO_DEG`] from OA, or phi less than [`EXTENSION_MIN_DEG`]
/// below where the extension began.
fn not_held_at_birth(series: &Series, movements: &Movements, born: Option<HeadBorn>) -> Vec<NotHeldAtBirth> {
    let Some(born) = born else {
        return Vec::new();
    };
    let mut lost = Vec::new();
    // Only what had happened by the birth can have been lost by it.
    let before_birth = |m: &Movement| m.observed && m.start_s.is_some_and(|start| start <= born.time_s);
    if before_birth(&movements.internal_rotation) && born.theta_deg.abs() > ROTATION_TO_DEG {
        lost.push(NotHeldAtBirth {
            movement: "internal_rotation".into(),
            reason: format!(
                "the occiput had turned back to {} (theta {:+.0} deg) when the head was born, further than \
                 the {ROTATION_TO_DEG:.0} deg from occiput anterior that ends the rotation",
                born.occiput_position(),
                born.theta_deg
            ),
        });
    }
    let extension = &movements.extension;
    let began = extension
        .start_s
        .filter(|_| before_birth(extension))
        .and_then(|start| series.time_s.iter().position(|&t| t == start));
    if let Some(began) = began.filter(|&i| series.phi_deg[i] - born.phi_deg < EXTENSION_MIN_DEG) {
        let from = series.phi_deg[began];
        let fall = from - born.phi_deg;
        let kept = match fall {
            f if f <= -0.5 => format!("{:.0} deg more flexed than", -f),
            f if f < 0.5 => "back at".to_string(),
            f => format!("only {f:.0} deg less flexed than"),
        };
        // The most it had extended by the birth (the counted size, for an
        // extension over by then): what was undone is the part of that it
        // no longer showed, and an extension still going on at the birth
        // had been undone by nothing.
        let size = extension.size.unwrap_or(0.0);
        let reached = match extension.end_s {
            Some(end) if end <= born.time_s => size.max(fall),
            _ => series.time_s[began..]
                .iter()
                .zip(&series.phi_deg[began..])
                .take_while(|&(&t, _)| t <= born.time_s)
                .map(|(_, &phi)| from - phi)
                .fold(fall, f64::max),
        };
        let undone = reached - fall;
        let what = if undone < 0.5 {
            format!("only {fall:.0} of the {size:.0} deg of extension had happened by the birth, the rest after it")
        } else if fall >= 0.5 {
            // A head still somewhat extended had part of it undone, not all.
            format!("{undone:.0} of the {reached:.0} deg of extension were undone before the birth")
        } else {
            format!("the {reached:.0} deg of extension were undone before the birth")
        };
        lost.push(NotHeldAtBirth {
            movement: "extension".into(),
            reason: format!(
                "{what}: the head was born at phi {:+.1} deg, \
                 {kept} the {from:+.1} deg it began to extend from, where the rule asks {EXTENSION_MIN_DEG:.0} \
                 deg less{}",
                born.phi_deg,
                if born.phi_deg > 0.0 { "; it was born flexed" } else { "" }
            ),
        });
    }
    lost
}

/// "internal_rotation not held at birth: the occiput had turned back...":
/// the words `carus run`, `carus detect` and the report share.
impl std::fmt::Display for NotHeldAtBirth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} not held at birth: {}", self.movement, self.reason)
    }
}

/// A turn to within 20 degrees of occiput anterior (from at least 45, as
/// internal rotation's rule asks) that the rule does not count because the
/// leading point was outside its station window, before the head was born.
/// Reported beside an unobserved internal rotation, so that a reader does
/// not take a rotation completed a few millimetres too deep for none.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RotationOutsideWindow {
    /// When abs(theta) first reached 20 degrees.
    pub time_s: f64,
    /// The leading point's station then, mm.
    pub station_mm: f64,
}

/// "the head turned to within 20 deg of occiput anterior at 6.1 s, station
/// +64 mm, outside the rule's window of stations -20 to +50 mm": the words
/// `carus run`, `carus detect` and the report share.
impl std::fmt::Display for RotationOutsideWindow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the head turned to within {ROTATION_TO_DEG:.0} deg of occiput anterior at {:.1} s, \
             station {:+.0} mm, outside the rule's window of stations {ROTATION_STATION_MIN_MM:+.0} \
             to {ROTATION_STATION_MAX_MM:+.0} mm",
            self.time_s, self.station_mm
        )
    }
}

/// The head at its first delivered sample: the position and attitude it
/// was born in. The rules judge each movement where it happened; this says
/// whether what happened lasted to the birth (an extension undone before
/// it, a rotation turned back), which is what the textbooks describe.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeadBorn {
    pub time_s: f64,
    /// The leading point's station, mm.
    pub station_mm: f64,
    /// Theta wrapped to (-180, 180], degrees.
    pub theta_deg: f64,
    /// Phi, degrees: positive in flexion.
    pub phi_deg: f64,
}

impl HeadBorn {
    fn at(series: &Series, i: usize) -> HeadBorn {
        HeadBorn {
            time_s: series.time_s[i],
            station_mm: series.station_mm[i],
            theta_deg: wrap_deg(series.theta_deg[i]),
            phi_deg: series.phi_deg[i],
        }
    }

    /// The occiput position nearest the head's theta: [`occiput_position`].
    pub fn occiput_position(&self) -> &'static str {
        occiput_position(self.theta_deg)
    }
}

/// The occiput position nearest `theta_deg`, as a clinician names it: OA
/// at 0, ROT at +90, LOT at -90, OP at 180 (CARDINAL_MOVEMENTS.md), in
/// eighths of a turn; any number of whole turns away reads the same.
pub fn occiput_position(theta_deg: f64) -> &'static str {
    const EIGHTHS: [&str; 8] = ["OA", "ROA", "ROT", "ROP", "OP", "LOP", "LOT", "LOA"];
    EIGHTHS[((theta_deg / 45.0).round() as i64).rem_euclid(8) as usize]
}

/// "the head was born at 11.4 s, station +90 mm, occiput LOA (theta -31
/// deg), phi +19.8 deg (flexion positive)": the words `carus run`, `carus detect` and the
/// report share.
impl std::fmt::Display for HeadBorn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the head was born at {:.1} s, station {:+.0} mm, occiput {} (theta {:+.0} deg), phi {:+.1} deg (flexion positive)",
            self.time_s,
            self.station_mm,
            self.occiput_position(),
            self.theta_deg,
            self.phi_deg
        )
    }
}

/// Applies every rule to the series. `spines_sigma_mm` is the arc length of
/// the ischial-spine plane, to turn stations back into sigma.
pub fn detect_movements(series: &Series, spines_sigma_mm: f64) -> Detected {
    let engagement = engagement(series, spines_sigma_mm);
    let flexion_peak = flexion_peak(series);
    let abs_theta: Vec<f64> = series
        .theta_deg
        .iter()
        .map(|&t| wrap_deg(t).abs())
        .collect();
    let rotation_window: Vec<usize> = (0..series.len())
        .filter(|&i| {
            (ROTATION_STATION_MIN_MM..=ROTATION_STATION_MAX_MM).contains(&series.station_mm[i])
        })
        .collect();
    let internal = fall(
        &abs_theta,
        &rotation_window,
        ROTATION_FROM_DEG,
        ROTATION_TO_DEG,
        ONSET_DEG,
    );
    let neg_abs_theta: Vec<f64> = abs_theta.iter().map(|a| -a).collect();
    let posterior = fall(
        &neg_abs_theta,
        &rotation_window,
        -POSTERIOR_FROM_DEG,
        -POSTERIOR_TO_DEG,
        ONSET_DEG,
    );
    // Only where the rule saw none: the first sample before the head was
    // born at which abs(theta) is down to 20 after having been 45, when
    // that sample lies outside the window.
    let rotation_outside_window = internal
        .is_none()
        .then(|| {
            let before_birth: Vec<usize> = (0..delivery(series).unwrap_or(series.len())).collect();
            first_fall_to(&abs_theta, &before_birth, ROTATION_FROM_DEG, ROTATION_TO_DEG)
        })
        .flatten()
        .filter(|&i| !(ROTATION_STATION_MIN_MM..=ROTATION_STATION_MAX_MM).contains(&series.station_mm[i]))
        .map(|i| RotationOutsideWindow {
            time_s: series.time_s[i],
            station_mm: series.station_mm[i],
        });
    let rotation = |span: Option<Span>| {
        span.map_or(Movement::absent(Unit::Deg), |s| {
            Movement::between(series, s, &series.theta_deg, Unit::Deg)
        })
    };
    let movements = Movements {
        engagement: engagement.map_or(Movement::absent(Unit::Mm), |s| {
            Movement::between(series, s, &series.station_mm, Unit::Mm)
        }),
        descent: descent(series),
        flexion: flexion(series, flexion_peak),
        internal_rotation: rotation(internal),
        extension: extension(series, flexion_peak),
        external_rotation: external_rotation(series, engagement.map(|s| s.end)),
        expulsion: expulsion(series),
    };
    let head_born = birth(series).map(|i| HeadBorn::at(series, i));
    Detected {
        not_held_at_birth: not_held_at_birth(series, &movements, head_born),
        movements,
        posterior_rotation: rotation(posterior),
        rotation_outside_window,
        head_born,
    }
}

/// Engagement: the head enters the inlet. End: the first sample with both
/// eminences below the inlet plane (not so at the first sample). Start: the
/// sample from which the leading point stayed below the inlet (sigma > 0)
/// up to the end. Size: the station gained in between.
fn engagement(series: &Series, spines_sigma_mm: f64) -> Option<Span> {
    if series.engaged(0) {
        return None;
    }
    let end = (1..series.len()).find(|&i| series.engaged(i))?;
    let leading_sigma = |i: usize| series.station_mm[i] + spines_sigma_mm;
    let start = (0..end)
        .rev()
        .find(|&i| leading_sigma(i) <= 0.0)
        .map_or(0, |i| (i + 1).min(end));
    Some(Span { start, end })
}

/// Index of the first sample at which the head is delivered, if any.
fn delivery(series: &Series) -> Option<usize> {
    series.head_delivered.iter().position(|&d| d)
}

/// Index of the head's birth: the first sample delivered after one that
/// was not (a head out from the first sample was not born there; if it
/// slips back in, its birth is when it comes out again).
fn birth(series: &Series) -> Option<usize> {
    (1..series.len()).find(|&i| series.head_delivered[i] && !series.head_delivered[i - 1])
}

/// Descent: the station's upper envelope (running maximum) over the samples
/// up to the head's delivery, so backward drift between contractions
/// neither counts against it nor is counted twice when regained. Observed
/// when the envelope ends at least 30 mm above the first station. Start:
/// the last sample before the envelope first rose more than the onset
/// tolerance; end: the first sample within the tolerance of the envelope's
/// final value.
fn descent(series: &Series) -> Movement {
    let last = delivery(series).unwrap_or(series.len() - 1);
    let station = &series.station_mm[..=last];
    let s0 = station[0];
    let top = station.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if top - s0 < DESCENT_MIN_MM {
        return Movement::absent(Unit::Mm);
    }
    let first_rise = station.iter().position(|&s| s > s0 + ONSET_MM).unwrap_or(0);
    let start = first_rise.saturating_sub(1);
    let end = station
        .iter()
        .position(|&s| s >= top - ONSET_MM)
        .unwrap_or(last);
    Movement::between(series, Span { start, end }, &series.station_mm, Unit::Mm)
}

/// The flexion peak: the first sample within the onset tolerance of the
/// greatest phi before the leading point first reaches station +30 mm
/// (where extension may begin), or over the whole run if it never does.
/// (The tolerance keeps rounding noise on a plateau from moving the peak.)
fn flexion_peak(series: &Series) -> usize {
    let limit = series
        .station_mm
        .iter()
        .position(|&s| s >= EXTENSION_FROM_STATION_MM)
        .unwrap_or(series.len());
    let phi = &series.phi_deg[..limit.max(1)];
    let top = phi.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    phi.iter().position(|&p| p >= top - ONSET_DEG).unwrap_or(0)
}

/// Flexion: phi at least 10 degrees above its first value at some sample
/// before the leading point first reaches station +20 mm. Start: the last
/// sample, before that crossing, with phi within the onset tolerance of its
/// first value; end: the flexion peak.
fn flexion(series: &Series, peak: usize) -> Movement {
    let phi = &series.phi_deg;
    let limit = series
        .station_mm
        .iter()
        .position(|&s| s >= FLEXION_BY_STATION_MM)
        .unwrap_or(series.len());
    let Some(crossing) = (0..limit).find(|&i| phi[i] >= phi[0] + FLEXION_MIN_DEG) else {
        return Movement::absent(Unit::Deg);
    };
    let start = (0..=crossing)
        .rev()
        .find(|&i| phi[i] <= phi[0] + ONSET_DEG)
        .unwrap_or(0);
    Movement::between(
        series,
        Span {
            start,
            end: peak.max(crossing),
        },
        phi,
        Unit::Deg,
    )
}

/// Extension: after the flexion peak, among the samples at station +30 mm
/// or deeper, the largest fall of phi from an earlier value; observed when
/// it is at least 30 degrees and the head is delivered during the run.
fn extension(series: &Series, peak: usize) -> Movement {
    if delivery(series).is_none() {
        return Movement::absent(Unit::Deg);
    }
    let window: Vec<usize> = (peak..series.len())
        .filter(|&i| series.station_mm[i] >= EXTENSION_FROM_STATION_MM)
        .collect();
    let neg_phi: Vec<f64> = series.phi_deg.iter().map(|p| -p).collect();
    match largest_rise(&neg_phi, &window, ONSET_DEG) {
        Some((span, fall)) if fall >= EXTENSION_MIN_DEG => {
            Movement::between(series, span, &series.phi_deg, Unit::Deg)
        }
        _ => Movement::absent(Unit::Deg),
    }
}

/// External rotation (restitution): after the head's delivery, the largest
/// turn of theta towards the side the occiput had at engagement (its sign
/// at the engagement sample, or at the first sample if the head did not
/// engage during the run; either side when that was within 10 degrees of
/// OA or OP): the largest fall of theta's angular distance from that side
/// (+-90 deg), so a head born OP turns back to the side as one born OA
/// does. Observed when the turn is at least 30 degrees.
fn external_rotation(series: &Series, engagement_end: Option<usize>) -> Movement {
    let Some(delivered) = delivery(series) else {
        return Movement::absent(Unit::Deg);
    };
    let window: Vec<usize> = (delivered..series.len()).collect();
    let side_theta = wrap_deg(series.theta_deg[engagement_end.unwrap_or(0)]);
    let sides: &[f64] =
        if side_theta.abs() < SIDE_UNDECIDED_DEG || side_theta.abs() > 180.0 - SIDE_UNDECIDED_DEG {
            &[1.0, -1.0]
        } else {
            &[side_theta.signum()]
        };
    let best = sides
        .iter()
        .filter_map(|&side| {
            let toward: Vec<f64> = series.theta_deg.iter().map(|&t| -wrap_deg(t - 90.0 * side).abs()).collect();
            largest_rise(&toward, &window, ONSET_DEG)
        })
        .fold(None::<(Span, f64)>, |best, candidate| match best {
            Some(b) if b.1 >= candidate.1 => Some(b),
            _ => Some(candidate),
        });
    match best {
        Some((span, turn)) if turn >= RESTITUTION_MIN_DEG => {
            Movement::between(series, span, &series.theta_deg, Unit::Deg)
        }
        _ => Movement::absent(Unit::Deg),
    }
}

/// Expulsion: the bisacromial midpoint passes the outlet plane (start: the
/// first sample past it, not the first sample of the run), then the trunk
/// centre does (end). Size: the trunk centre's travel along the outlet
/// normal in between. Needs a modelled trunk.
fn expulsion(series: &Series) -> Movement {
    let (Some(shoulders), Some(trunk)) = (
        &series.shoulders_below_outlet_mm,
        &series.trunk_below_outlet_mm,
    ) else {
        return Movement::absent(Unit::Mm);
    };
    let Some(start) = shoulders.iter().position(|&d| d > 0.0).filter(|&i| i > 0) else {
        return Movement::absent(Unit::Mm);
    };
    let Some(end) = (start..trunk.len()).find(|&i| trunk[i] > 0.0) else {
        return Movement::absent(Unit::Mm);
    };
    Movement::between(series, Span { start, end }, trunk, Unit::Mm)
}

/// The first fall of `q` (over the samples `window`, in time order) to at
/// most `to` from an earlier value of at least `from`. Start: the last
/// window sample before the fall's end within `tolerance` of the highest
/// earlier value; end: the first sample of the stretch at or below `to`
/// within `tolerance` of that stretch's lowest value.
fn fall(q: &[f64], window: &[usize], from: f64, to: f64, tolerance: f64) -> Option<Span> {
    let reach = first_fall_to(q, window, from, to)?;
    let before = &window[..reach];
    let high = before
        .iter()
        .map(|&i| q[i])
        .fold(f64::NEG_INFINITY, f64::max);
    let start = *before.iter().rev().find(|&&i| q[i] >= high - tolerance)?;
    let stretch: Vec<usize> = window[reach..]
        .iter()
        .copied()
        .take_while(|&i| q[i] <= to)
        .collect();
    let low = stretch.iter().map(|&i| q[i]).fold(f64::INFINITY, f64::min);
    let end = *stretch.iter().find(|&&i| q[i] <= low + tolerance)?;
    Some(Span { start, end })
}

/// Where in `window` (time order) `q` is first at most `to` after an earlier
/// sample at least `from`.
fn first_fall_to(q: &[f64], window: &[usize], from: f64, to: f64) -> Option<usize> {
    let mut seen_from = false;
    window.iter().position(|&i| {
        let hit = seen_from && q[i] <= to;
        seen_from |= q[i] >= from;
        hit
    })
}

/// The largest rise of `q` from an earlier to a later sample of `window`
/// (time order), with its size. Start: the last sample before the top that
/// is within `tolerance` of the lowest value preceding it; end: the first
/// sample from the start within `tolerance` of the top.
fn largest_rise(q: &[f64], window: &[usize], tolerance: f64) -> Option<(Span, f64)> {
    let first = *window.first()?;
    let (mut low, mut best) = (q[first], None::<(usize, f64, f64)>);
    for &i in window {
        low = low.min(q[i]);
        let rise = q[i] - low;
        if rise > best.map_or(0.0, |b| b.1) {
            best = Some((i, rise, low));
        }
    }
    let (top, rise, low) = best?;
    let start_pos = window
        .iter()
        .rposition(|&i| i < top && q[i] <= low + tolerance)?;
    let end = *window[start_pos..]
        .iter()
        .find(|&&i| q[i] >= q[top] - tolerance)?;
    Some((
        Span {
            start: window[start_pos],
            end,
        },
        rise,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn none_is_the_seven_unobserved_in_order_with_their_units() {
        let none = Movements::none();
        let keys: Vec<&str> = none.by_key().iter().map(|(k, _)| *k).collect();
        assert_eq!(
            keys,
            ["engagement", "descent", "flexion", "internal_rotation", "extension", "external_rotation", "expulsion"]
        );
        for (key, m) in none.by_key() {
            assert!(!m.observed && m.start_s.is_none() && m.end_s.is_none() && m.size.is_none(), "{key}");
            let linear = matches!(key, "engagement" | "descent" | "expulsion");
            assert_eq!(m.unit, if linear { Unit::Mm } else { Unit::Deg }, "{key}");
        }
    }

    #[test]
    fn a_fall_reports_its_onset_and_its_settling() {
        let q = [90.0, 90.0, 89.8, 70.0, 40.0, 10.0, 2.0, 0.5, 0.2, 0.3];
        let window: Vec<usize> = (0..q.len()).collect();
        let span = fall(&q, &window, 45.0, 20.0, 1.0).unwrap();
        assert_eq!(span, Span { start: 2, end: 7 });
    }

    #[test]
    fn a_fall_needs_its_starting_level_inside_the_window() {
        let q = [90.0, 90.0, 30.0, 10.0];
        assert_eq!(fall(&q, &[2, 3], 45.0, 20.0, 1.0), None);
        assert!(fall(&q, &[1, 2, 3], 45.0, 20.0, 1.0).is_some());
    }

    #[test]
    fn the_largest_rise_ignores_an_earlier_smaller_one() {
        let q = [0.0, 5.0, 1.0, 2.0, 40.0, 39.5, 10.0];
        let window: Vec<usize> = (0..q.len()).collect();
        let (span, rise) = largest_rise(&q, &window, 1.0).unwrap();
        assert_eq!(rise, 40.0);
        // The rise's onset is the last sample near the low before the top.
        assert_eq!(span, Span { start: 2, end: 4 });
    }

    #[test]
    fn a_falling_series_has_no_rise() {
        let q = [3.0, 2.0, 1.0];
        assert_eq!(largest_rise(&q, &[0, 1, 2], 1.0), None);
    }
}
