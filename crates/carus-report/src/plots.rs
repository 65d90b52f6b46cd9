//! Plots against time as inline SVG (plotters' SVG backend): one shared
//! time axis, the movements shaded behind the curves, the key moments
//! marked by dashed lines.

use plotters::prelude::*;

use crate::error::ReportError;

/// Width and height of one plot, px (the page scales them to fit).
pub const PLOT_SIZE: (u32, u32) = (560, 300);

/// One curve (the page's caption names it, in its colour: a legend
/// inside the plot would hide the curves).
pub struct Curve<'a> {
    pub values: &'a [f64],
    pub colour: RGBColor,
}

/// A shaded time span (a movement).
pub struct Band {
    pub start_s: f64,
    pub end_s: f64,
    pub colour: RGBColor,
}

/// A dashed vertical line with a short label (a key moment).
pub struct Mark<'a> {
    pub time_s: f64,
    pub label: &'a str,
}

/// What one plot shows.
pub struct PlotSpec<'a> {
    /// Identifier used in errors ("station").
    pub id: &'static str,
    pub y_label: &'a str,
    pub time_s: &'a [f64],
    pub curves: Vec<Curve<'a>>,
    /// Horizontal reference lines (the spines at station 0, OA at theta 0).
    pub references: Vec<f64>,
    pub bands: &'a [Band],
    pub marks: &'a [Mark<'a>],
    /// The time axis's range, shared by every plot of the page.
    pub time_range: (f64, f64),
}

/// Lower and upper limits of the values, padded by 5 % (1 unit when flat).
pub fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (low, high) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if low > high {
        return (-1.0, 1.0);
    }
    let pad = if high - low > 1e-9 {
        0.05 * (high - low)
    } else {
        1.0
    };
    (low - pad, high + pad)
}

/// Draws the plot as an `<svg>` element (no XML prolog, no namespace
/// attribute: HTML5 needs neither and the page must name no URL).
pub fn svg(spec: &PlotSpec) -> Result<String, ReportError> {
    let mut out = String::new();
    draw(spec, &mut out).map_err(|message| ReportError::Plot {
        plot: spec.id,
        message,
    })?;
    Ok(out.replace(" xmlns=\"http://www.w3.org/2000/svg\"", ""))
}

fn draw(spec: &PlotSpec, out: &mut String) -> Result<(), String> {
    let e = |err: &dyn std::fmt::Display| err.to_string();
    let root = SVGBackend::with_string(out, PLOT_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (t0, t1) = spec.time_range;
    let (y0, y1) = padded_range(
        spec.curves
            .iter()
            .flat_map(|c| c.values.iter().copied())
            .chain(spec.references.iter().copied()),
    );
    let mut chart = ChartBuilder::on(&root)
        .margin(10)
        .margin_top(18)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.12))
        .x_desc("time (s)")
        .y_desc(spec.y_label)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .draw()
        .map_err(|x| e(&x))?;
    chart
        .draw_series(spec.bands.iter().map(|b| {
            Rectangle::new(
                [(b.start_s, y0), (b.end_s, y1)],
                b.colour.mix(0.16).filled(),
            )
        }))
        .map_err(|x| e(&x))?;
    for &level in &spec.references {
        chart
            .draw_series(LineSeries::new(
                [(t0, level), (t1, level)],
                BLACK.mix(0.45).stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
    }
    for mark in spec.marks {
        chart
            .draw_series(DashedLineSeries::new(
                [(mark.time_s, y0), (mark.time_s, y1)],
                4,
                3,
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
        // A few pixels right of its line, so that the line does not strike
        // through the label ("IR" read as "|R").
        chart
            .draw_series(std::iter::once(
                EmptyElement::at((mark.time_s, y1))
                    + Text::new(mark.label.to_string(), (3, 1), ("sans-serif", 12).into_font().color(&BLACK)),
            ))
            .map_err(|x| e(&x))?;
    }
    for curve in &spec.curves {
        chart
            .draw_series(LineSeries::new(
                spec.time_s
                    .iter()
                    .copied()
                    .zip(curve.values.iter().copied()),
                curve.colour.stroke_width(2),
            ))
            .map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_series_gets_a_range_around_it() {
        assert_eq!(padded_range([3.0, 3.0].into_iter()), (2.0, 4.0));
        assert_eq!(padded_range(std::iter::empty()), (-1.0, 1.0));
        let (low, high) = padded_range([0.0, 10.0].into_iter());
        assert!((low + 0.5).abs() < 1e-12 && (high - 10.5).abs() < 1e-12);
    }

    #[test]
    fn a_plot_is_one_svg_element_with_its_curve_and_labels() {
        let time = [0.0, 1.0, 2.0];
        let values = [0.0, 5.0, 3.0];
        let bands = [Band {
            start_s: 0.5,
            end_s: 1.5,
            colour: RGBColor(200, 0, 0),
        }];
        let marks = [Mark {
            time_s: 1.0,
            label: "IR",
        }];
        let spec = PlotSpec {
            id: "test",
            y_label: "station (mm)",
            time_s: &time,
            curves: vec![Curve {
                values: &values,
                colour: RGBColor(0, 0, 200),
            }],
            references: vec![0.0],
            bands: &bands,
            marks: &marks,
            time_range: (0.0, 2.0),
        };
        let svg = svg(&spec).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        assert_eq!(svg.matches("<svg").count(), 1);
        assert!(
            svg.contains("station (mm)") && svg.contains("time (s)") && svg.contains("IR\n</text>")
        );
        assert!(!svg.contains("http"), "no URL in an inline plot");
    }
}
