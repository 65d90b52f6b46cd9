//! The HTML page: headline, timeline, pictures, plots, figures, scenario.
//! One file with everything inline (CSS, SVG, PNG as data: URIs); no
//! script and no URL, so it opens offline and archives as it is.

use std::fmt::Write as _;

use carus_analysis::{ArrestStage, DetectorReport, Outcome, THETA_ILL_CONDITIONED_TILT_DEG};
use plotters::style::RGBColor;

use crate::error::ReportError;
use crate::input::{AxialMomentSample, CanalForceSample, ReportInput};
use carus_analysis::moments::{KeyMoment, MissedMoment};
use crate::movements::{css, ill_conditioned_rotations, label_of, shown, size_text, Shown};
use crate::pictures::{MomentPictures, PICTURE_SIZE};
use crate::plots::{self, Band, Curve, Mark, PlotSpec};

/// Escapes text for HTML element content and quoted attributes.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The headline: CSS class and sentence.
pub fn headline(outcome: &Outcome) -> (&'static str, String) {
    if outcome.delivered {
        return ("delivered", "Delivered".to_string());
    }
    match &outcome.arrest {
        Some(arrest) => {
            let place = match arrest.stage {
                ArrestStage::Inlet => "at the pelvic inlet (not engaged: the parietal eminences stayed above the inlet plane)",
                ArrestStage::MidPelvis => "in the mid-pelvis (engaged, the biparietal plane above the ischial spines)",
                ArrestStage::Outlet => "at the pelvic outlet (the biparietal plane past the spines, the head not born)",
                ArrestStage::Shoulders => "at the shoulders (head born, trunk not)",
            };
            let against = if arrest.against == "unknown" {
                "an unrecorded contact".to_string()
            } else {
                format!("the {}", arrest.against.replace('_', " "))
            };
            let held = match (arrest.stage, arrest.part.as_str()) {
                (_, "unknown") => String::new(),
                // Born by the rule's measure, yet what is held is the head.
                (ArrestStage::Shoulders, "head") => {
                    "the head, counted born (its centre past the outlet plane), still held ".to_string()
                }
                (_, part) => format!("the {part} held "),
            };
            let station = match arrest.stage {
                ArrestStage::Shoulders => "shoulders at",
                _ => "station",
            };
            (
                "arrested",
                format!(
                    "Arrested {place}, {station} {:+.0} mm{}, {held}against {against}{}",
                    arrest.station_mm,
                    arrest
                        .held_shoulders_from_ap_deg()
                        .map_or(String::new(), |deg| format!(" ({deg:.0}° from antero-posterior)")),
                    arrest.shoulders_holding_head().map_or(String::new(), |s| format!(
                        ", its shoulders at station {s:+.0} mm"
                    ))
                ),
            )
        }
        None => (
            "undecided",
            "Not delivered: the run ended while the fetus was still progressing".to_string(),
        ),
    }
}

/// Everything the page needs besides the input.
pub struct Parts<'a> {
    pub moments: &'a [KeyMoment],
    pub missed: &'a [MissedMoment],
    /// `None`: pictures not attempted (no scene); `Some(Err)`: no renderer.
    pub pictures: Option<Result<Vec<MomentPictures>, String>>,
    pub stretch_range: Option<[f64; 2]>,
}

/// Builds the whole page.
pub fn page(input: &ReportInput, parts: &Parts) -> Result<String, ReportError> {
    let d = input.detector;
    let rows = shown(d);
    let series = &d.series;
    let t0 = series.time_s[0];
    let t1 = *series.time_s.last().unwrap_or(&t0);
    let time_range = (t0, if t1 > t0 { t1 } else { t0 + 1.0 });
    let (class, headline) = headline(&d.outcome);
    let observed = d
        .movements
        .by_key()
        .iter()
        .filter(|(_, m)| m.observed)
        .count();
    let title = escape(&input.title);

    let mut html = String::new();
    let w = &mut html;
    // Writing into a String cannot fail.
    let _ = write!(
        w,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{title} (report)</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>\n\
         <header><p class=\"kicker\">Carus labour report</p><h1>{title}</h1>"
    );
    if let Some(notice) = &input.notice {
        let _ = write!(
            w,
            "<p class=\"notice\" id=\"notice\">{}</p>",
            escape(notice)
        );
    }
    // What the birth undid belongs beside the count, not only further down.
    let lost: Vec<&str> = d.not_held_at_birth.iter().map(|n| label_of(&rows, &n.movement)).collect();
    let not_held = match lost.is_empty() {
        true => String::new(),
        false => format!(
            ", {} not held at birth{}",
            lost.join(" and ").to_lowercase(),
            d.head_born.map_or(String::new(), |born| format!(
                " (the head was born {}, phi {:+.0}&deg;)",
                born.occiput_position(),
                born.phi_deg
            ))
        ),
    };
    let _ = write!(
        w,
        "<p class=\"headline {class}\" id=\"outcome\" data-delivered=\"{}\">{}</p>\
         <p class=\"sub\">{observed} of 7 cardinal movements observed{not_held} &middot; {:.1} s simulated",
        d.outcome.delivered,
        escape(&headline),
        input.run.simulated_s
    );
    match d.contraction_period_s {
        Some(period) => {
            let _ = write!(w, " &middot; contraction period {period:.1} s");
        }
        None => {
            let _ = write!(w, " &middot; contraction period not read (a steady push, or fewer than three whole contractions)");
        }
    }
    let _ = writeln!(w, "</p></header>");

    timeline(w, &rows, d, parts, time_range);
    pictures(w, parts, input.scene.as_ref().is_some_and(|s| s.fontanelles.is_some()));
    plots_section(w, input, &rows, parts, time_range)?;
    figures(w, input);
    reading_guide(w);
    let _ = writeln!(w, "</main>\n</body>\n</html>");
    Ok(html)
}

fn percent(t: f64, (t0, t1): (f64, f64)) -> f64 {
    (100.0 * (t - t0) / (t1 - t0)).clamp(0.0, 100.0)
}

fn timeline(
    w: &mut String,
    rows: &[Shown],
    d: &DetectorReport,
    parts: &Parts,
    range: (f64, f64),
) {
    let series = &d.series;
    let at: Vec<f64> = parts.moments.iter().map(|m| percent(m.time_s, range)).collect();
    let ticks: Vec<(f64, usize)> = at.iter().copied().zip(tick_lines(&at)).collect();
    let _ = write!(
        w,
        "<section id=\"movements\"><h2>Cardinal movements</h2>\
         <div class=\"timeline\"><div class=\"row axis\"><span class=\"name\"></span>\
         <span class=\"flag\"></span><span class=\"track{}\">",
        ["", " two-lines"][usize::from(ticks.iter().any(|&(_, line)| line == 1))]
    );
    for (m, (at, line)) in parts.moments.iter().zip(ticks) {
        let _ = write!(
            w,
            "<span class=\"tick{}\" style=\"left:{at:.2}%\" title=\"{} at {:.2} s\">{}</span>",
            ["", " second"][line],
            m.kind.label(),
            m.time_s,
            m.kind.mark()
        );
    }
    let _ = write!(
        w,
        "</span><span class=\"when\">start &ndash; end</span><span class=\"size\">size</span></div>"
    );
    for row in rows {
        let m = row.movement;
        // The posterior rotation is listed only when it happened.
        if row.key == "posterior_rotation" && !m.observed {
            continue;
        }
        let colour = css(row.colour);
        let _ = write!(
            w,
            "<div class=\"row\" data-movement=\"{}\" data-observed=\"{}\">\
             <span class=\"name\"><i class=\"swatch\" style=\"background:{colour}\"></i>{}</span>",
            row.key, m.observed, row.label
        );
        match (m.observed, m.start_s, m.end_s, m.size) {
            (true, Some(start), Some(end), Some(size)) => {
                let left = percent(start, range);
                let width = (percent(end, range) - left).max(0.6);
                let size = size_text(size, m.unit);
                let flag = match d.not_held_at_birth.iter().any(|n| n.movement == row.key) {
                    true => "<span class=\"flag lost\" title=\"counted where it happened, but not shown by the head at its birth: see below\">observed, not held</span>",
                    false => "<span class=\"flag yes\">observed</span>",
                };
                let _ = write!(
                    w,
                    "{flag}<span class=\"track\">\
                     <span class=\"bar\" style=\"left:{left:.2}%;width:{width:.2}%;background:{colour}\" \
                     title=\"{}: {start:.1} s to {end:.1} s, {size}\"></span></span>\
                     <span class=\"when\">{start:.1} &ndash; {end:.1} s</span><span class=\"size\">{size}</span></div>",
                    row.label
                );
            }
            _ => {
                let _ = write!(
                    w,
                    "<span class=\"flag no\">not observed</span><span class=\"track empty\"></span>\
                     <span class=\"when\">&mdash;</span><span class=\"size\">&mdash;</span></div>"
                );
            }
        }
    }
    let _ = write!(w, "</div>");
    for (label, tilt) in ill_conditioned_rotations(rows, series) {
        let _ = write!(
            w,
            "<p class=\"note\" data-caveat=\"theta\">{label}: read from theta while the occiput \
             pointed up to {tilt:.0}&deg; out of the canal's cross-section (theta, the occiput's \
             direction projected onto it, is ill-conditioned past {THETA_ILL_CONDITIONED_TILT_DEG:.0}&deg;): \
             a turn of the head about another axis can read as this rotation.</p>"
        );
    }
    if let Some(r) = d.internal_rotation_outside_window {
        let _ = write!(
            w,
            "<p class=\"note\" data-note=\"rotation-outside-window\">Internal rotation not counted: \
             {} (Carus's docs/spec/CARDINAL_MOVEMENTS.md).</p>",
            escape(&r.to_string())
        );
    }
    // Whether what the rules counted lasted to the birth (an extension
    // undone before it, a rotation turned back) is read here.
    if let Some(born) = d.head_born {
        let text = born.to_string();
        let _ = write!(
            w,
            "<p class=\"note\" data-note=\"head-born\">{}{}.</p>",
            text[..1].to_uppercase(),
            escape(&text[1..])
        );
    }
    // The head-to-body interval and the shoulders' lie: what a shoulder
    // dystocia is judged by, and what held them in this model.
    if let Some(passage) = d.shoulders.filter(|p| p.inlet_s.is_some() || d.head_born.is_some()) {
        let text = passage.to_string();
        let _ = write!(
            w,
            "<p class=\"note\" data-note=\"shoulders\">{}{}.</p>",
            text[..1].to_uppercase(),
            escape(&text[1..])
        );
    }
    for lost in &d.not_held_at_birth {
        let label = label_of(rows, &lost.movement);
        let _ = write!(
            w,
            "<p class=\"note\" data-note=\"not-held\" data-movement=\"{}\"><b>{label} not held at birth:</b> {}. \
             The rule counts it where it happened (CARDINAL_MOVEMENTS.md); the textbook birth keeps it.</p>",
            lost.movement,
            escape(&lost.reason)
        );
    }
    let _ = writeln!(w, "</section>");
}

fn pictures(w: &mut String, parts: &Parts, fontanelles: bool) {
    let _ = write!(w, "<section id=\"pictures\"><h2>Key moments</h2>");
    match &parts.pictures {
        None => {
            let _ = write!(
                w,
                "<p class=\"note\">No pictures: the run supplied no meshes to draw.</p>"
            );
        }
        Some(Err(reason)) => {
            let _ = write!(
                w,
                "<p class=\"note\" id=\"no-pictures\">Pictures could not be drawn: {}. \
                 The rest of the report is complete.</p>",
                escape(reason)
            );
        }
        Some(Ok(moments)) => {
            let _ = write!(
                w,
                "<p class=\"legend\">Lateral view from the mother's right (anterior to the right) \
                 and inferior view of the outlet (pubis at the top); one scale for all pictures. \
                 Bone semi-transparent, fetus opaque"
            );
            if fontanelles {
                let _ = write!(
                    w,
                    ", on the head the posterior fontanelle {} (the occiput lies behind it) \
                     and the anterior {}",
                    swatch(crate::pictures::POSTERIOR_FONTANELLE_RGB, "&#9679;"),
                    swatch(crate::pictures::ANTERIOR_FONTANELLE_RGB, "&#9679;")
                );
            }
            if let Some([low, high]) = parts.stretch_range {
                let _ = write!(
                    w,
                    ", pelvic floor coloured by maximum principal stretch \
                     <span class=\"ramp\"></span> {low:.2} &ndash; {high:.2}{}",
                    match high <= crate::pictures::MIN_STRETCH_TOP {
                        true => " (the scale's least span: the floor stretched less than its top)",
                        false => "",
                    }
                );
            }
            if moments.iter().any(|m| !m.forces.is_empty()) {
                let _ = write!(
                    w,
                    ". Arrows: the forces on the fetus, each on its line of action and ending where \
                     it meets the fetal surface, 10 mm per {:.0} N, listed under each moment in their colours; \
                     the floor and the fetal trunk see-through under them",
                    0.01 / crate::pictures::ARROW_M_PER_N
                );
            }
            let _ = write!(w, ".</p><div class=\"moments\">");
            for m in moments {
                let _ = write!(
                    w,
                    "<figure class=\"moment\" data-moment=\"{}\"><figcaption><b>{}</b> \
                     at {:.2} s<br><small>{}</small>",
                    m.moment.kind.mark(),
                    m.moment.kind.label(),
                    m.moment.time_s,
                    m.moment.kind.rule()
                );
                if let Some(t) = m.floor_time_s {
                    let _ = write!(w, "<br><small>floor as recorded at {t:.2} s</small>");
                }
                if !m.forces.is_empty() {
                    let listed: Vec<String> = m
                        .forces
                        .iter()
                        .map(|(what, newtons, rgb)| format!("{} {} {newtons:.0} N", swatch(*rgb, "&#9632;"), escape(what)))
                        .collect();
                    let _ = write!(w, "<br><small class=\"forces\">{}</small>", listed.join(", "));
                }
                let _ = write!(w, "</figcaption>");
                match &m.pictures {
                    Ok(views) => {
                        for p in views {
                            let _ = write!(
                                w,
                                "<span class=\"view\"><img src=\"{}\" width=\"{}\" height=\"{}\" \
                                 alt=\"{} at {:.2} s, {} view\"><small>{} view</small></span>",
                                p.data_uri,
                                PICTURE_SIZE.0,
                                PICTURE_SIZE.1,
                                m.moment.kind.label(),
                                m.moment.time_s,
                                p.view.name(),
                                p.view.name()
                            );
                        }
                    }
                    Err(reason) => {
                        let _ = write!(w, "<p class=\"note\">Not drawn: {}</p>", escape(reason));
                    }
                }
                let _ = write!(w, "</figure>");
            }
            let _ = write!(w, "</div>");
        }
    }
    if !parts.missed.is_empty() {
        let _ = write!(w, "<p class=\"missed\">Not reached: ");
        let missed: Vec<String> = parts
            .missed
            .iter()
            .map(|m| format!("{} ({})", m.kind.label().to_lowercase(), escape(&m.reason)))
            .collect();
        let _ = write!(w, "{}.</p>", missed.join("; "));
    }
    let _ = writeln!(w, "</section>");
}

/// Least distance between two key-moment marks on one line of the
/// timeline's axis, per cent of its width: two bold letters or so in a
/// window 800 px wide.
const TICK_SPACING_PERCENT: f64 = 12.0;

/// The line (0 or 1) of each key-moment mark at `at` per cent along the
/// axis, in time order: a mark too near the one before it on the first
/// line drops to the second, so that neighbours stay legible in a narrow
/// window; when both are crowded it stays on the first.
fn tick_lines(at: &[f64]) -> Vec<usize> {
    let mut line_ends = [f64::NEG_INFINITY; 2];
    at.iter()
        .map(|&at| {
            let line = usize::from(at - line_ends[0] < TICK_SPACING_PERCENT && at - line_ends[1] >= TICK_SPACING_PERCENT);
            line_ends[line] = at;
            line
        })
        .collect()
}

/// `symbol` (an HTML entity) in the sRGB colour `rgb`.
fn swatch(rgb: [f32; 3], symbol: &str) -> String {
    let [r, g, b] = rgb.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8);
    format!("<span style=\"color:#{r:02x}{g:02x}{b:02x}\">{symbol}</span>")
}

fn plots_section(
    w: &mut String,
    input: &ReportInput,
    rows: &[Shown],
    parts: &Parts,
    time_range: (f64, f64),
) -> Result<(), ReportError> {
    let d: &DetectorReport = input.detector;
    let s = &d.series;
    let bands: Vec<Band> = rows
        .iter()
        .filter_map(|r| {
            let m = r.movement;
            match (m.observed, m.start_s, m.end_s) {
                (true, Some(start_s), Some(end_s)) => Some(Band {
                    start_s,
                    end_s,
                    colour: r.colour,
                }),
                _ => None,
            }
        })
        .collect();
    let marks: Vec<Mark> = parts
        .moments
        .iter()
        .map(|m| Mark {
            time_s: m.time_s,
            label: m.kind.mark(),
        })
        .collect();
    let axis = TimeAxis {
        bands: &bands,
        marks: &marks,
        range: time_range,
    };
    let blue = RGBColor(31, 87, 153);
    let spec =
        |id, y_label, curves, references| axis.spec(id, y_label, &s.time_s, curves, references);
    let orange = RGBColor(200, 82, 0);
    let spines_mm = input.history.canal.spines_sigma() * 1000.0;
    // The shoulders beside the head, where a trunk is modelled: a trunk
    // held on the brim while the head is born shows here.
    let shoulders_station: Option<Vec<f64>> = s
        .shoulders_sigma_mm
        .as_ref()
        .map(|sigma| sigma.iter().map(|s| s - spines_mm).collect());
    let mut station = vec![Curve {
        values: &s.station_mm,
        colour: blue,
    }];
    if let Some(shoulders) = &shoulders_station {
        station.push(Curve {
            values: shoulders,
            colour: orange,
        });
    }
    let inlet_station = format!("{:.0}", -spines_mm);
    let station_caption = if shoulders_station.is_some() {
        format!(
            "<span style=\"color:#1f5799\">&#9632; the head's leading point</span> \
             <span style=\"color:#c85200\">&#9632; the bisacromial midpoint (shoulders)</span>; mm \
             below the ischial spines (line at 0), the inlet plane at {inlet_station}; up = deeper"
        )
    } else {
        format!("mm below the ischial spines (line at 0), the inlet plane at {inlet_station}; up = deeper")
    };
    let mut theta = vec![Curve {
        values: &s.theta_deg,
        colour: blue,
    }];
    // The head's twist beside theta, where the series has it (older runs do not).
    let twist = s.head_twist_deg.len() == s.len();
    if twist {
        theta.push(Curve {
            values: &s.head_twist_deg,
            colour: orange,
        });
    }
    let theta_caption = if twist {
        "<span style=\"color:#1f5799\">&#9632; theta, the occiput's direction projected on the \
         canal's cross-section</span> <span style=\"color:#c85200\">&#9632; the head's twist about \
         the canal axis, well conditioned however steeply the occiput tilts (docs/DETECTOR.md)</span>; \
         0 = OA, +90 = ROT, -90 = LOT, \u{b1}180 = OP, on past it -270 = ROT"
    } else {
        "occiput position: 0 = OA, +90 = ROT, -90 = LOT, \u{b1}180 = OP, on past it -270 = ROT"
    };
    let phi = vec![Curve {
        values: &s.phi_deg,
        colour: blue,
    }];
    let force = vec![
        Curve {
            values: &s.expulsion_force_n,
            colour: blue,
        },
        Curve {
            values: &s.contact_force_n,
            colour: orange,
        },
    ];
    let force_caption = format!(
        "<span style=\"color:#1f5799\">&#9632; expulsion force along the spine</span> \
         <span style=\"color:#c85200\">&#9632; net contact force (bone + floor): the size of their vector \
         total, in which pushes from opposite sides cancel{}</span>",
        if load_plotted(input, &s.time_s) { " (the contact load below adds their sizes)" } else { "" }
    );
    let figures = [
        (
            "station",
            "Station",
            station_caption.as_str(),
            plots::svg(&spec("station", "station (mm)", station, vec![0.0, -spines_mm]))?,
        ),
        (
            "theta",
            "Rotation theta",
            theta_caption,
            plots::svg(&spec("theta", "theta (deg)", theta, vec![0.0]))?,
        ),
        (
            "phi",
            "Attitude phi",
            "positive = flexion, negative = extension",
            plots::svg(&spec("phi", "phi (deg)", phi, vec![0.0]))?,
        ),
        (
            "force",
            "Forces on the fetus",
            force_caption.as_str(),
            plots::svg(&spec("force", "force (N)", force, vec![0.0]))?,
        ),
    ];
    let moments = if parts.moments.is_empty() {
        "No key moment was reached.".to_string()
    } else {
        let marks: Vec<String> = parts
            .moments
            .iter()
            .map(|m| format!("{} = {}", m.kind.mark(), m.kind.label().to_lowercase()))
            .collect();
        format!("Dashed: the key moments ({}).", marks.join(", "))
    };
    let _ = write!(
        w,
        "<section id=\"plots\"><h2>Against time</h2><p class=\"legend\">Shaded: the movements \
         in the timeline's colours. {moments}</p><div class=\"plots\">"
    );
    for (id, heading, caption, svg) in figures {
        let _ = write!(
            w,
            "<figure class=\"plot\" id=\"plot-{id}\"><figcaption><b>{heading}</b> \
             <small>{caption}</small></figcaption>{svg}</figure>"
        );
    }
    contact_load_plot(w, input, &axis, &s.time_s)?;
    floor_plot(w, input, &axis)?;
    axial_moment_plot(w, input, &axis)?;
    canal_force_plot(w, input, &axis)?;
    let _ = writeln!(w, "</div></section>");
    Ok(())
}

/// The time axis every plot of the page shares: its range, with the
/// movements shaded and the key moments marked.
struct TimeAxis<'a> {
    bands: &'a [Band],
    marks: &'a [Mark<'a>],
    range: (f64, f64),
}

impl<'a> TimeAxis<'a> {
    fn spec(
        &self,
        id: &'static str,
        y_label: &'a str,
        time_s: &'a [f64],
        curves: Vec<Curve<'a>>,
        references: Vec<f64>,
    ) -> PlotSpec<'a> {
        PlotSpec {
            id,
            y_label,
            time_s,
            curves,
            references,
            bands: self.bands,
            marks: self.marks,
            time_range: self.range,
        }
    }
}

/// A peak stretch that rounds to 1.000 in the legend: the floor at rest.
const UNSTRETCHED_BELOW: f64 = 1.0005;

fn floor_plot(w: &mut String, input: &ReportInput, axis: &TimeAxis) -> Result<(), ReportError> {
    let _ = write!(
        w,
        "<figure class=\"plot\" id=\"plot-floor\"><figcaption><b>Pelvic floor: peak stretch</b> \
         <small>largest maximum principal stretch anywhere in the floor (1 = at rest)</small></figcaption>"
    );
    if input.floor_peak_stretch.is_empty() {
        let _ = write!(
            w,
            "<p class=\"note\">No pelvic floor was simulated in this run.</p></figure>"
        );
        return Ok(());
    }
    let (time_s, stretch): (Vec<f64>, Vec<f64>) = input.floor_peak_stretch.iter().copied().unzip();
    all_finite("floor_peak_stretch", &[&stretch, &time_s])?;
    // The first sample of the greatest stretch, not the last of a tie, and
    // only while the floor's elements were whole: a corner turned inside
    // out makes what follows untrustworthy.
    let untrusted_from = input.floor_untrusted_from_s.unwrap_or(f64::INFINITY);
    let greatest_of = |trusted: bool| {
        input
            .floor_peak_stretch
            .iter()
            .copied()
            .filter(|&(t, _)| (t < untrusted_from) == trusted)
            .reduce(|best, sample| if sample.1 > best.1 { sample } else { best })
    };
    let peak = greatest_of(true);
    let greatest = peak.map_or(1.0, |(_, s)| s);
    // Only the levels the run passes: a level above the data would squash
    // the curve of a floor that stays near rest.
    let passed: Vec<(f64, &str)> = carus_anatomy::floor::LEVATOR_STRETCH_AT_CROWNING
        .into_iter()
        .filter(|&(level, _)| greatest > level)
        .collect();
    let references = std::iter::once(1.0)
        .chain(passed.iter().map(|&(level, _)| level))
        .collect();
    let spec = axis.spec(
        "floor",
        "peak stretch",
        &time_s,
        vec![Curve {
            values: &stretch,
            colour: RGBColor(68, 1, 84),
        }],
        references,
    );
    let svg = plots::svg(&spec)?;
    let _ = write!(w, "{svg}");
    if peak.is_some_and(|(_, s)| s < UNSTRETCHED_BELOW) {
        let _ = write!(w, "<p class=\"legend\">The floor was not stretched (1.000 throughout).");
    } else if let Some((t, s)) = peak {
        let before = if input.floor_untrusted_from_s.is_some() { " while its elements were whole" } else { "" };
        let _ = write!(w, "<p class=\"legend\">Greatest{before}: {s:.3} at {t:.1} s.");
        if !passed.is_empty() {
            let levels: Vec<String> = passed
                .iter()
                .map(|(level, source)| format!("{level} ({source})"))
                .collect();
            let _ = write!(
                w,
                " Lines at the largest levator stretch that models of an uncomplicated birth \
                 predict at crowning, which this floor passes: {}. Beyond them the floor is \
                 stretched further than those models predict for an uncomplicated birth \
                 (this floor is elastic and cannot tear).",
                levels.join(" and ")
            );
        }
        let _ = write!(w, "</p>");
    }
    if let (Some(from), Some((_, after))) = (input.floor_untrusted_from_s, greatest_of(false)) {
        let _ = write!(
            w,
            "<p class=\"legend\" data-caveat=\"floor-corners\">From {from:.1} s floor elements had a corner \
             turned inside out (the run's figures count them), and the floor's stretches from then on \
             (up to {after:.3}) are not to be trusted.</p>"
        );
    }
    let _ = write!(w, "</figure>");
    Ok(())
}

/// A plot's data must be numbers: the first that is not is named with `what`.
fn all_finite(what: &'static str, columns: &[&[f64]]) -> Result<(), ReportError> {
    match columns.iter().flat_map(|c| c.iter()).find(|v| !v.is_finite()) {
        Some(&value) => Err(ReportError::NotFinite { what, value }),
        None => Ok(()),
    }
}

/// Adds the imposed and hybrid modes' guide to a plot's `curves` where it
/// acted (a forward run has none), and returns its key for the caption.
fn guide_curve<'a>(guide: &'a [f64], curves: &mut Vec<Curve<'a>>) -> &'static str {
    if guide.iter().all(|&g| g == 0.0) {
        return "";
    }
    curves.push(Curve {
        values: guide,
        colour: RGBColor(217, 26, 217),
    });
    " <span style=\"color:#d91ad9\">&#9632; the guide (not the physics)</span>"
}

/// What spun the head about the pelvic axis: bone, floor, neck and trunk, the
/// causes a reader checks when internal rotation does or does not happen.
fn axial_moment_plot(
    w: &mut String,
    input: &ReportInput,
    axis: &TimeAxis,
) -> Result<(), ReportError> {
    let m = &input.head_axial_moments;
    if m.is_empty() {
        return Ok(());
    }
    let column = |f: fn(&AxialMomentSample) -> f64| column_of(m, f);
    let (time_s, bone, floor, neck, push, trunk, guide) = (
        column(|s| s.time_s),
        column(|s| s.bone_nm),
        column(|s| s.floor_nm),
        column(|s| s.neck_nm),
        column(|s| s.neck_push_nm),
        column(|s| s.trunk_nm),
        column(|s| s.guide_nm),
    );
    all_finite("head_axial_moments", &[&time_s, &bone, &floor, &neck, &push, &trunk, &guide])?;
    let (bone_colour, floor_colour, neck_colour, push_colour, trunk_colour) = (
        RGBColor(200, 82, 0),
        RGBColor(68, 1, 84),
        RGBColor(31, 87, 153),
        RGBColor(95, 170, 220),
        RGBColor(53, 183, 121),
    );
    let mut curves = vec![
        Curve {
            values: &bone,
            colour: bone_colour,
        },
        Curve {
            values: &floor,
            colour: floor_colour,
        },
        Curve {
            values: &neck,
            colour: neck_colour,
        },
        Curve {
            values: &push,
            colour: push_colour,
        },
        Curve {
            values: &trunk,
            colour: trunk_colour,
        },
    ];
    let guide_key = guide_curve(&guide, &mut curves);
    let spec = axis.spec("axial-moments", "moment (N m)", &time_s, curves, vec![0.0]);
    let svg = plots::svg(&spec)?;
    let _ = write!(
        w,
        "<figure class=\"plot\" id=\"plot-axial-moments\"><figcaption><b>What turns the head \
         about the pelvic axis</b> <small>moments about the head's centre along the axis; \
         positive turns theta up (LOT towards OA): \
         <span style=\"color:#c85200\">&#9632; bone (friction included)</span> \
         <span style=\"color:#440154\">&#9632; pelvic floor</span> \
         <span style=\"color:#35b779\">&#9632; the trunk on the head (chin on chest)</span> \
         <span style=\"color:#1f5799\">&#9632; neck</span>, of which \
         <span style=\"color:#5faadc\">&#9632; the push through the pivot</span>{guide_key}</small>\
         </figcaption>{svg}</figure>"
    );
    Ok(())
}

/// Whether the contact load was recorded at every sample (`time_s`).
fn load_plotted(input: &ReportInput, time_s: &[f64]) -> bool {
    !input.contact_load_n.is_empty() && input.contact_load_n.len() == time_s.len()
}

/// How hard the fetus is pressed, on a plot of its own: a wedged head's
/// load runs to many times the push and would flatten the forces' plot.
fn contact_load_plot(w: &mut String, input: &ReportInput, axis: &TimeAxis, time_s: &[f64]) -> Result<(), ReportError> {
    let load = &input.contact_load_n;
    if !load_plotted(input, time_s) {
        return Ok(());
    }
    all_finite("contact_load_n", &[load])?;
    let curves = vec![Curve { values: load, colour: RGBColor(42, 138, 62) }];
    let svg = plots::svg(&axis.spec("contact-load", "force (N)", time_s, curves, vec![0.0]))?;
    let _ = write!(
        w,
        "<figure class=\"plot\" id=\"plot-contact-load\"><figcaption><b>Contact load</b> <small>the sum of \
         the sizes of the bone's and ligaments' contact forces, point by point, and of the floor's push: how \
         hard the fetus is pressed from all sides, where the net contact force above lets opposite pushes \
         cancel</small></figcaption>{svg}</figure>"
    );
    Ok(())
}

/// What pushed the head down the canal and what held it back: how much of
/// the expulsion reached the head through the neck, against the canal.
fn canal_force_plot(w: &mut String, input: &ReportInput, axis: &TimeAxis) -> Result<(), ReportError> {
    let f = &input.head_canal_forces;
    if f.is_empty() {
        return Ok(());
    }
    let column = |g: fn(&CanalForceSample) -> f64| column_of(f, g);
    let (time_s, push, trunk, bone, floor, guide) = (
        column(|s| s.time_s),
        column(|s| s.push_n),
        column(|s| s.trunk_n),
        column(|s| s.bone_n),
        column(|s| s.floor_n),
        column(|s| s.guide_n),
    );
    all_finite("head_canal_forces", &[&time_s, &push, &trunk, &bone, &floor, &guide])?;
    let curve = |values, colour| Curve { values, colour };
    let mut curves = vec![
        curve(&push, RGBColor(31, 87, 153)),
        curve(&trunk, RGBColor(53, 183, 121)),
        curve(&bone, RGBColor(200, 82, 0)),
        curve(&floor, RGBColor(68, 1, 84)),
    ];
    let guide_key = guide_curve(&guide, &mut curves);
    let svg = plots::svg(&axis.spec("canal-forces", "force (N)", &time_s, curves, vec![0.0]))?;
    let _ = write!(
        w,
        "<figure class=\"plot\" id=\"plot-canal-forces\"><figcaption><b>What pushes the head \
         down the canal</b> <small>forces on the head along the pelvic axis, positive deeper: \
         <span style=\"color:#1f5799\">&#9632; the push that reaches it at the pivot (through \
         the neck from the trunk)</span> \
         <span style=\"color:#35b779\">&#9632; the trunk on the head (chin on chest)</span> \
         <span style=\"color:#c85200\">&#9632; bone (friction included)</span> \
         <span style=\"color:#440154\">&#9632; pelvic floor</span>{guide_key}; what they leave \
         of the expulsion moves the fetus against the drag of its surroundings</small>\
         </figcaption>{svg}</figure>"
    );
    Ok(())
}

fn figures(w: &mut String, input: &ReportInput) {
    let run = &input.run;
    let d = input.detector;
    let _ = write!(
        w,
        "<section id=\"run\"><h2>Run</h2><table class=\"figures\">\
         <tr><th>simulated time</th><td>{:.2} s</td></tr>",
        run.simulated_s
    );
    let _ = write!(
        w,
        "<tr><th>wall time</th><td>{}</td></tr><tr><th>steps</th><td>{}</td></tr>",
        run.wall_s
            .map_or("&mdash; (no solver)".to_string(), |s| format!("{s:.1} s")),
        run.steps
            .map_or("&mdash; (no solver)".to_string(), |n| n.to_string())
    );
    let _ = write!(
        w,
        "<tr><th>pose samples</th><td>{}</td></tr><tr><th>trunk modelled</th><td>{}</td></tr>",
        d.series.len(),
        if input.history.trunk.is_some() {
            "yes"
        } else {
            "no"
        }
    );
    for (name, value) in &run.extra {
        let _ = write!(
            w,
            "<tr><th>{}</th><td>{}</td></tr>",
            escape(name),
            escape(value)
        );
    }
    let _ = write!(w, "</table>");
    if let Some(toml) = &input.scenario_toml {
        let _ = write!(
            w,
            "<details id=\"scenario\"><summary>Scenario (TOML, as run)</summary><pre>{}</pre></details>",
            escape(toml)
        );
    }
    let _ = writeln!(w, "</section>");
}

fn reading_guide(w: &mut String) {
    w.push_str(
        "<section id=\"guide\"><h2>How to read this report</h2><ul>\
         <li><b>Station</b>: the depth of the head's leading point along the curve of Carus, \
         in mm below the plane of the ischial spines (negative above).</li>\
         <li><b>Theta</b>: where the occiput points in the canal's cross-section, \
         0 = occiput anterior, \u{b1}90 = transverse, \u{b1}180 = occiput posterior.</li>\
         <li><b>Phi</b>: the head's attitude relative to the fetal spine, positive in flexion.</li>\
         <li>A movement counts as observed by the rules of Carus's docs/spec/CARDINAL_MOVEMENTS.md; its size is \
         the change of its own quantity (station, phi or theta) from start to end.</li>\
         <li>The outcome: delivered when head and trunk are past the outlet; arrested when \
         the fetus stopped progressing over the last part of the run.</li></ul></section>\n",
    );
}

/// One figure of every sample, for a plot.
fn column_of<T>(samples: &[T], figure: fn(&T) -> f64) -> Vec<f64> {
    samples.iter().map(figure).collect()
}

/// Inline style: readable on screen and on paper, no web fonts.
const STYLE: &str = "
body{margin:0;background:#f4f3ef;color:#1d1d1b;font:15px/1.45 system-ui,-apple-system,'Segoe UI',Roboto,Helvetica,Arial,sans-serif}
main{max-width:1200px;margin:0 auto;padding:24px 28px 48px;background:#fff}
h1{margin:0 0 8px;font-size:28px}h2{font-size:19px;margin:28px 0 10px;border-bottom:1px solid #ddd;padding-bottom:4px}
.kicker{margin:0;color:#777;text-transform:uppercase;letter-spacing:.08em;font-size:12px}
.notice{background:#fff4d6;border:1px solid #e0b84c;border-radius:6px;padding:8px 12px;margin:8px 0}
.headline{font-size:26px;font-weight:700;margin:12px 0 2px;padding:10px 14px;border-radius:8px}
.headline.delivered{background:#e3f2e1;color:#1e5a1a}.headline.arrested{background:#fbe3e1;color:#8a1c14}
.headline.undecided{background:#eee;color:#444}
.sub{margin:4px 0 0;color:#555}
.timeline{display:grid;gap:4px}
.row{display:grid;grid-template-columns:250px 100px 1fr 120px 80px;align-items:center;gap:10px}
.row.axis{font-size:12px;color:#777}
.name{font-weight:600}.swatch{display:inline-block;width:12px;height:12px;border-radius:3px;margin-right:8px;vertical-align:-1px}
.flag{font-size:12px;border-radius:10px;padding:1px 8px;text-align:center}
.flag.yes{background:#e3f2e1;color:#1e5a1a}.flag.no{background:#eee;color:#888}.flag.lost{background:#fdf0d5;color:#7a4a00}
.track{position:relative;height:16px;background:#f1f1f1;border-radius:3px}
.row.axis .track{background:none}
.track.empty{background:repeating-linear-gradient(45deg,#f6f6f6,#f6f6f6 6px,#ececec 6px,#ececec 12px)}
.bar{position:absolute;top:1px;bottom:1px;border-radius:3px}
.tick{position:absolute;transform:translateX(-50%);font-weight:700;color:#444}.tick.second{top:15px}
.track.two-lines{height:32px}
.when,.size{font-variant-numeric:tabular-nums;font-size:13px}
.moments{display:grid;gap:14px}
.moment{margin:0;border:1px solid #e2e2e2;border-radius:8px;padding:8px;display:grid;grid-template-columns:260px 1fr 1fr;gap:8px;align-items:start}
.moment>.note{grid-column:span 2}
.view{text-align:center;color:#888}
.view img{width:100%;max-width:440px;height:auto;display:block;margin:0 auto}
@media (max-width:900px){.moment{grid-template-columns:1fr 1fr}.moment figcaption,.moment>.note{grid-column:1/-1}}
.plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(min(540px,100%),1fr));gap:12px}
.plot{margin:0}.plot svg{width:100%;height:auto;display:block}
figcaption small,.legend,.note,.missed{color:#666;font-size:13px}
.note{background:#f6f6f6;border-left:3px solid #bbb;padding:6px 10px}
.ramp{display:inline-block;width:90px;height:10px;vertical-align:0;background:linear-gradient(90deg,#440154,#3b528b,#21918c,#5ec962,#fde725)}
table.figures{border-collapse:collapse}table.figures th{text-align:left;font-weight:500;color:#555;padding:2px 16px 2px 0}
table.figures td{font-variant-numeric:tabular-nums}
details{margin-top:12px}pre{background:#f6f6f6;padding:10px;overflow:auto;font-size:12px}
@media (max-width:700px){main{padding:16px 12px 32px}.row{grid-template-columns:minmax(0,1fr) auto auto auto}.row .track{grid-column:1/-1;grid-row:2}}
@media print{body{background:#fff}main{padding:0}details{display:none}}
";

#[cfg(test)]
mod tests {
    use super::*;
    use carus_analysis::Arrest;

    #[test]
    fn crowded_key_moment_marks_take_a_second_line() {
        assert_eq!(tick_lines(&[]), Vec::<usize>::new());
        assert_eq!(tick_lines(&[14.8, 25.3, 49.7, 92.4]), [0, 1, 0, 0]);
        assert_eq!(tick_lines(&[10.0, 15.0, 50.0, 55.0, 58.0, 70.0]), [0, 1, 0, 1, 0, 0]);
    }

    #[test]
    fn markup_characters_are_escaped() {
        assert_eq!(escape("a<b & \"c\"'"), "a&lt;b &amp; &quot;c&quot;&#39;");
    }

    #[test]
    fn an_arrest_says_where_and_against_what() {
        let arrest = |part: &str| Outcome {
            delivered: false,
            arrest: Some(Arrest {
                stage: ArrestStage::Inlet,
                station_mm: -42.4,
                against: "sacral_promontory".into(),
                part: part.into(),
                shoulders_station_mm: Some(-95.3),
                shoulders_from_ap_deg: Some(64.6),
            }),
        };
        let (class, text) = headline(&arrest("unknown"));
        assert_eq!(class, "arrested");
        assert_eq!(text, "Arrested at the pelvic inlet (not engaged: the parietal eminences stayed above the inlet plane), station -42 mm, against the sacral promontory");
        let (_, text) = headline(&arrest("trunk"));
        assert_eq!(
            text,
            "Arrested at the pelvic inlet (not engaged: the parietal eminences stayed above the inlet plane), station -42 mm, the trunk held against the sacral promontory, its shoulders at station -95 mm"
        );
        // A head counted born whose own contact holds the fetus (the
        // occiput-posterior run) is said as such, not as held shoulders.
        let mut born = arrest("head");
        born.arrest.as_mut().unwrap().stage = ArrestStage::Shoulders;
        assert_eq!(
            headline(&born).1,
            "Arrested at the shoulders (head born, trunk not), shoulders at -42 mm (65° from antero-posterior), the head, counted born (its centre past the outlet plane), still held against the sacral promontory"
        );
        // Shoulders held by the trunk: how they lie is said with where.
        let mut held = arrest("trunk");
        held.arrest.as_mut().unwrap().stage = ArrestStage::Shoulders;
        assert_eq!(
            headline(&held).1,
            "Arrested at the shoulders (head born, trunk not), shoulders at -42 mm (65° from antero-posterior), the trunk held against the sacral promontory"
        );
        let open = Outcome { delivered: false, arrest: None };
        assert!(headline(&open).1.contains("still progressing"));
    }
}
