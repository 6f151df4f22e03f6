//! The convergence plot: relative MSE against render time, log–log, one line per algorithm,
//! drawn with `plotters`' SVG backend.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// Line colour of an algorithm: fixed per name, so that a colour means the same algorithm in
/// every scene's plot.
fn colour(algorithm: &str) -> RGBColor {
    match algorithm {
        "pt" => RGBColor(31, 119, 180),
        "lt" => RGBColor(255, 127, 14),
        "ppm" => RGBColor(44, 160, 44),
        "bpm" => RGBColor(148, 103, 189),
        "bpt" => RGBColor(140, 86, 75),
        "vcm" => RGBColor(214, 39, 40),
        _ => RGBColor(127, 127, 127),
    }
}

/// Tick label of a log axis: 3 significant digits without trailing zeros.
fn tick(value: &f64) -> String {
    let text = super::html::number(*value);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// The bounds `[lo, hi]` of `values` widened by `margin` (a factor) on both sides, so that the
/// extreme points do not sit on the axes; a single value gets a decade around it.
fn log_bounds(values: impl Iterator<Item = f64>, margin: f64) -> Option<(f64, f64)> {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && lo > 0.0) {
        return None;
    }
    if hi / lo < 1.0 + 1e-9 { Some((lo / 3.0, hi * 3.0)) } else { Some((lo / margin, hi * margin)) }
}

/// Draws `series` (algorithm name, points `(seconds, relative MSE)`) into the SVG file `path`
/// under `title`. Points that cannot be shown on log axes (zero, negative, non-finite) are left
/// out; returns `false` without writing a file when no point is left.
pub(super) fn convergence_plot(path: &Path, title: &str, series: &[(&str, Vec<(f64, f64)>)]) -> Result<bool> {
    let shown: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(name, points)| {
            let points =
                points.iter().copied().filter(|&(t, e)| t.is_finite() && t > 0.0 && e.is_finite() && e > 0.0).collect();
            (*name, points)
        })
        .collect();
    let all = || shown.iter().flat_map(|(_, p)| p.iter().copied());
    let (Some((t0, t1)), Some((e0, e1))) = (log_bounds(all().map(|p| p.0), 1.25), log_bounds(all().map(|p| p.1), 1.5))
    else {
        return Ok(false);
    };
    let failed = |e: &dyn std::fmt::Display| anyhow!("cannot draw the convergence plot '{}': {e}", path.display());

    let root = SVGBackend::new(path, (720, 440)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| failed(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
        .map_err(|e| failed(&e))?;
    chart
        .configure_mesh()
        .x_desc("render time (s)")
        .y_desc("relative MSE")
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| failed(&e))?;
    for (name, points) in shown.iter().filter(|(_, p)| !p.is_empty()) {
        let c = colour(name);
        chart
            .draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(2)))
            .map_err(|e| failed(&e))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, c.filled()))).map_err(|e| failed(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| failed(&e))?;
    root.present().map_err(|e| failed(&e))?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_widen_the_data_range() {
        let (lo, hi) = log_bounds([0.1, 2.0, 0.5].into_iter(), 1.25).unwrap();
        assert!((lo - 0.08).abs() < 1e-12 && (hi - 2.5).abs() < 1e-12, "{lo} {hi}");
        let (lo, hi) = log_bounds([4.0].into_iter(), 1.25).unwrap();
        assert!((lo - 4.0 / 3.0).abs() < 1e-12 && (hi - 12.0).abs() < 1e-12, "{lo} {hi}");
        assert_eq!(log_bounds(std::iter::empty(), 1.25), None);
    }

    #[test]
    fn ticks_drop_trailing_zeros() {
        assert_eq!(tick(&0.0100), "0.01");
        assert_eq!(tick(&1.0), "1");
        assert_eq!(tick(&250.0), "250");
        assert_eq!(tick(&0.00125), "1.25e-3");
    }

    #[test]
    fn plot_draws_every_series_and_skips_unplottable_points() {
        let dir = testkit::TempDir::new("report-plot");
        let path = dir.join("plot.svg");
        let series = vec![
            ("pt", vec![(0.01, 1.0), (0.02, 0.5), (0.04, 0.25)]),
            ("vcm", vec![(0.01, 0.8), (0.03, 0.0), (0.05, 0.2)]),
        ];
        assert!(convergence_plot(&path, "test", &series).unwrap());
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
        // One polyline per series (the legend's marks are polylines too) and one circle per
        // plottable point: 3 + 2 (the zero error is left out).
        assert_eq!(svg.matches("<circle").count(), 5, "{svg}");
        assert!(svg.contains("\npt\n") && svg.contains("\nvcm\n") && svg.contains("relative MSE"), "{svg}");
        assert!(!convergence_plot(&dir.join("none.svg"), "test", &[("pt", vec![(0.1, 0.0)])]).unwrap());
        assert!(!dir.join("none.svg").exists());
    }
}
