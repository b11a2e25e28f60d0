//! A small SVG chart writer: line charts (time and triangles per step) and bar charts
//! (success rate per backend). Hand-written because the reports need two chart kinds
//! and a plotting crate would add minutes to every cold build. Output is plain SVG 1.1
//! that browsers and image viewers render.

use std::fmt::Write;

/// Canvas size and margins, in pixels.
const WIDTH: f64 = 720.0;
const HEIGHT: f64 = 420.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 160.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;
/// Ticks per axis, about.
const TICKS: usize = 6;
/// Series colours (colour-blind-safe Okabe–Ito palette), cycled.
const COLOURS: [&str; 7] = [
    "#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#F0E442",
];

/// One line of a line chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points `(x, y)`; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
}

/// Escapes text for SVG.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A "nice" tick step (1, 2 or 5 × 10ᵏ) giving about [`TICKS`] ticks over `span`.
fn tick_step(span: f64) -> f64 {
    if !(span.is_finite() && span > 0.0) {
        return 1.0;
    }
    let raw = span / TICKS as f64;
    let magnitude = 10f64.powf(raw.log10().floor());
    let scaled = raw / magnitude;
    let nice = if scaled <= 1.0 {
        1.0
    } else if scaled <= 2.0 {
        2.0
    } else if scaled <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// Formats a tick label compactly.
fn label(value: f64) -> String {
    let a = value.abs();
    if a != 0.0 && !(1e-3..1e6).contains(&a) {
        format!("{value:.1e}")
    } else if value.fract() == 0.0 {
        format!("{value:.0}")
    } else {
        let s = format!("{value:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Axis range `[lo, hi]` rounded out to ticks, never empty.
fn axis_range(lo: f64, hi: f64) -> (f64, f64, f64) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, lo + 0.5)
    };
    let step = tick_step(hi - lo);
    ((lo / step).floor() * step, (hi / step).ceil() * step, step)
}

/// The frame: background, title, axis labels, grid lines and ticks. Returns the
/// document so far.
fn frame(title: &str, x_label: &str, y_label: &str, y: (f64, f64, f64)) -> String {
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="24" text-anchor="middle" font-size="15">{}</text>"#,
        LEFT + (WIDTH - LEFT - RIGHT) / 2.0,
        escape(title)
    );
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        LEFT + (WIDTH - LEFT - RIGHT) / 2.0,
        HEIGHT - 15.0,
        escape(x_label)
    );
    let _ = writeln!(
        svg,
        r#"<text x="18" y="{}" text-anchor="middle" transform="rotate(-90 18 {})">{}</text>"#,
        TOP + (HEIGHT - TOP - BOTTOM) / 2.0,
        TOP + (HEIGHT - TOP - BOTTOM) / 2.0,
        escape(y_label)
    );
    let (lo, hi, step) = y;
    let ticks = ((hi - lo) / step).round() as usize;
    for k in 0..=ticks.min(4 * TICKS) {
        let value = lo + k as f64 * step;
        let py = y_pixel(value, lo, hi);
        let _ = writeln!(
            svg,
            r##"<line x1="{LEFT}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            WIDTH - RIGHT,
            LEFT - 6.0,
            py + 4.0,
            label(value)
        );
    }
    let _ = writeln!(
        svg,
        r##"<polyline points="{LEFT},{TOP} {LEFT},{b} {r},{b}" fill="none" stroke="#333"/>"##,
        b = HEIGHT - BOTTOM,
        r = WIDTH - RIGHT
    );
    svg
}

fn y_pixel(value: f64, lo: f64, hi: f64) -> f64 {
    HEIGHT - BOTTOM - (value - lo) / (hi - lo) * (HEIGHT - TOP - BOTTOM)
}

fn x_pixel(value: f64, lo: f64, hi: f64) -> f64 {
    LEFT + (value - lo) / (hi - lo) * (WIDTH - LEFT - RIGHT)
}

/// A line chart of several series with a legend on the right.
pub fn line_chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let finite = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    };
    let bounds = |f: fn(&(f64, f64)) -> f64| {
        finite()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (x_lo, x_hi) = bounds(|p| p.0);
    let (y_lo, y_hi) = bounds(|p| p.1);
    // Counts and times start at zero: anchoring the axis there keeps slopes honest.
    let y = axis_range(y_lo.min(0.0), y_hi);
    let (x_lo, x_hi, x_step) = axis_range(x_lo, x_hi);
    let mut svg = frame(title, x_label, y_label, y);
    let ticks = ((x_hi - x_lo) / x_step).round() as usize;
    for k in 0..=ticks.min(4 * TICKS) {
        let value = x_lo + k as f64 * x_step;
        let px = x_pixel(value, x_lo, x_hi);
        let _ = writeln!(
            svg,
            r#"<text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            HEIGHT - BOTTOM + 16.0,
            label(value)
        );
    }
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let points: Vec<String> = s
            .points
            .iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|&(x, v)| format!("{:.1},{:.1}", x_pixel(x, x_lo, x_hi), y_pixel(v, y.0, y.1)))
            .collect();
        if points.len() == 1 {
            let _ = writeln!(
                svg,
                r#"<circle cx="{}" cy="{}" r="3" fill="{colour}"/>"#,
                points[0].split(',').next().unwrap_or("0"),
                points[0].split(',').nth(1).unwrap_or("0")
            );
        } else if !points.is_empty() {
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
                points.join(" ")
            );
        }
        let ly = TOP + 10.0 + 18.0 * i as f64;
        let lx = WIDTH - RIGHT + 12.0;
        let _ = writeln!(
            svg,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="3"/><text x="{}" y="{}">{}</text>"#,
            lx + 20.0,
            lx + 26.0,
            ly + 4.0,
            escape(&s.name)
        );
    }
    svg.push_str("</svg>\n");
    svg
}

/// A bar chart, one bar per `(name, value)`; `y_max` fixes the top of the axis (1 for
/// rates) instead of fitting the data.
pub fn bar_chart(title: &str, y_label: &str, bars: &[(String, f64)], y_max: Option<f64>) -> String {
    let top = y_max.unwrap_or_else(|| {
        bars.iter()
            .map(|b| b.1)
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    });
    let y = axis_range(0.0, top);
    let mut svg = frame(title, "", y_label, y);
    let slot = (WIDTH - LEFT - RIGHT) / bars.len().max(1) as f64;
    for (i, (name, value)) in bars.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let v = if value.is_finite() { *value } else { 0.0 };
        let x = LEFT + slot * (i as f64 + 0.2);
        let py = y_pixel(v, y.0, y.1);
        let _ = writeln!(
            svg,
            r#"<rect x="{x:.1}" y="{py:.1}" width="{:.1}" height="{:.1}" fill="{colour}"/><text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            slot * 0.6,
            (HEIGHT - BOTTOM - py).max(0.0),
            x + slot * 0.3,
            HEIGHT - BOTTOM + 16.0,
            escape(name),
            x + slot * 0.3,
            py - 5.0,
            label(v)
        );
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_nice_and_cover_the_range() {
        assert_eq!(tick_step(10.0), 2.0);
        assert_eq!(tick_step(0.7), 0.2);
        assert_eq!(tick_step(3000.0), 500.0);
        let (lo, hi, step) = axis_range(0.13, 9.7);
        assert!(lo <= 0.13 && hi >= 9.7 && step > 0.0);
        // Degenerate and empty ranges still give a drawable axis.
        let (lo, hi, _) = axis_range(5.0, 5.0);
        assert!(hi > lo);
        let (lo, hi, _) = axis_range(f64::INFINITY, f64::NEG_INFINITY);
        assert!(hi > lo);
    }

    #[test]
    fn charts_are_well_formed_svg_with_every_series() {
        let series = vec![
            Series {
                name: "grid <fast>".into(),
                points: (0..10).map(|i| (i as f64, (i * i) as f64)).collect(),
            },
            Series {
                name: "collision".into(),
                points: vec![(0.0, 1.0), (f64::NAN, 2.0)],
            },
        ];
        let svg = line_chart("time per step", "step", "seconds", &series);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("grid &lt;fast&gt;") && svg.contains("collision"));
        assert_eq!(svg.matches("<polyline").count(), 2); // axes + one multi-point series
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let bars = bar_chart(
            "success",
            "rate",
            &[("grid".into(), 1.0), ("collision".into(), 0.5)],
            Some(1.0),
        );
        assert_eq!(bars.matches("<rect").count(), 3); // background + two bars
        let empty = line_chart("t", "x", "y", &[]);
        assert!(!empty.contains("NaN"));
    }
}
