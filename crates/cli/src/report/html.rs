//! The report's page (`index.html`) and its numbers (`report.json`).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use serde_json::{Value, json};

use super::{ReportBudget, SceneReport};

/// Formats a number with 3 significant digits: fixed-point for moderate magnitudes, scientific
/// otherwise; `-` for non-finite values.
pub(super) fn number(x: f64) -> String {
    let magnitude = x.abs();
    if !x.is_finite() {
        "-".to_string()
    } else if x == 0.0 {
        "0".to_string()
    } else if (1e-2..1e5).contains(&magnitude) {
        let decimals = (2 - magnitude.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// Escapes text for HTML content and attribute values.
fn escape(text: &str) -> String {
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

/// Writes `index.html` and `report.json` into `out`.
pub(super) fn write_outputs(
    out: &Path,
    scenes: &[SceneReport],
    budget: ReportBudget,
    references: &[String],
    seed: u64,
) -> Result<()> {
    let page = out.join("index.html");
    std::fs::write(&page, page_html(scenes, budget, seed))
        .with_context(|| format!("cannot write '{}'", page.display()))?;
    let numbers = out.join("report.json");
    let text = serde_json::to_string_pretty(&report_json(scenes, budget, references, seed))
        .context("cannot encode the report's numbers")?;
    std::fs::write(&numbers, text + "\n").with_context(|| format!("cannot write '{}'", numbers.display()))?;
    Ok(())
}

/// The page: per scene a row of previews with their numbers, a table and the convergence plot.
fn page_html(scenes: &[SceneReport], budget: ReportBudget, seed: u64) -> String {
    let mut h = String::new();
    h.push_str(concat!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n",
        "<title>vcm report</title>\n<style>\n",
        "body { font-family: sans-serif; margin: 1.5em; color: #222; }\n",
        ".row { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; }\n",
        "figure { margin: 0; }\n",
        "figure img { image-rendering: pixelated; display: block; border: 1px solid #ccc; }\n",
        "figcaption { font-size: 0.85em; line-height: 1.35; margin-top: 4px; }\n",
        "table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }\n",
        "th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }\n",
        "th:first-child, td:first-child { text-align: left; }\n",
        "img.plot { max-width: 100%; }\n",
        "</style>\n</head>\n<body>\n<h1>vcm report</h1>\n"
    ));
    let _ = writeln!(
        h,
        "<p>Every algorithm renders each scene for {} (seed {seed}). Render time excludes setup and \
         the error measurements. Errors against the reference: RMSE and relative MSE \
         (mean of (a&minus;b)&sup2;/(b&sup2;+0.01) over all pixel channels).</p>",
        escape(&budget.describe())
    );
    for scene in scenes {
        write_scene(&mut h, scene);
    }
    h.push_str("<p><a href=\"report.json\">All numbers (report.json)</a></p>\n</body>\n</html>\n");
    h
}

fn write_scene(h: &mut String, scene: &SceneReport) {
    let label = escape(&scene.label);
    // Small renders are magnified (pixelated), large ones shrunk, to a width of 256-512 px.
    let display_width = scene.width.clamp(256, 512);
    let display_height =
        (f64::from(display_width) * f64::from(scene.height) / f64::from(scene.width.max(1))).round() as u32;
    let _ = writeln!(h, "<section>\n<h2 id=\"{label}\">{label}</h2>");
    let _ = writeln!(h, "<p>{}x{} pixels.</p>\n<div class=\"row\">", scene.width, scene.height);
    let img = |src: &str, alt: &str| {
        format!(
            "<img src=\"{}\" alt=\"{}\" width=\"{display_width}\" height=\"{display_height}\">",
            escape(src),
            escape(alt)
        )
    };
    if let Some((file, preview)) = &scene.reference {
        let _ = writeln!(
            h,
            "<figure>{}<figcaption><b>reference</b><br>{}</figcaption></figure>",
            img(preview, &format!("{} reference", scene.label)),
            escape(file)
        );
    }
    for r in &scene.results {
        let mut caption = format!(
            "<b>{}</b> (<a href=\"{}\">EXR</a>)<br>{} iterations, {} ms/iteration",
            escape(r.algorithm),
            escape(&r.image),
            r.iterations,
            number(r.ms_per_iteration())
        );
        if let Some(e) = r.final_error() {
            let _ = write!(caption, "<br>RMSE {}, relMSE {}", number(e.rmse), number(e.relative_mse));
        }
        let _ = writeln!(
            h,
            "<figure>{}<figcaption>{caption}</figcaption></figure>",
            img(&r.preview, &format!("{} rendered with {}", scene.label, r.algorithm))
        );
    }
    h.push_str("</div>\n<table>\n<tr><th>algorithm</th><th>iterations</th><th>time (s)</th><th>ms/iteration</th>");
    if scene.reference.is_some() {
        h.push_str("<th>RMSE</th><th>relMSE</th>");
    }
    h.push_str("<th>rejected samples</th></tr>\n");
    for r in &scene.results {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
            escape(r.algorithm),
            r.iterations,
            number(r.seconds),
            number(r.ms_per_iteration())
        );
        if scene.reference.is_some() {
            let (rmse, rel) = r.final_error().map_or((f64::NAN, f64::NAN), |e| (e.rmse, e.relative_mse));
            let _ = write!(h, "<td>{}</td><td>{}</td>", number(rmse), number(rel));
        }
        let _ = writeln!(h, "<td>{}</td></tr>", r.rejected_samples);
    }
    h.push_str("</table>\n");
    match (&scene.plot, &scene.reference) {
        (Some(plot), _) => {
            let _ = writeln!(
                h,
                "<p><img class=\"plot\" src=\"{}\" alt=\"{label}: relative MSE against render time, log-log\"></p>",
                escape(plot)
            );
        }
        (None, Some(_)) => h.push_str("<p>No convergence plot: no positive error was measured.</p>\n"),
        (None, None) => h.push_str("<p>No reference given: no errors, no convergence plot.</p>\n"),
    }
    h.push_str("</section>\n");
}

/// A finite number, or `null`.
fn finite(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// Every number of the report.
fn report_json(scenes: &[SceneReport], budget: ReportBudget, references: &[String], seed: u64) -> Value {
    let (time, iterations) = match budget {
        ReportBudget::Time(t) => (Some(t.as_secs_f64()), None),
        ReportBudget::Iterations(n) => (None, Some(n)),
    };
    let scenes: Vec<Value> = scenes
        .iter()
        .map(|s| {
            let results: Vec<Value> = s
                .results
                .iter()
                .map(|r| {
                    let error = r.final_error();
                    json!({
                        "algorithm": r.algorithm,
                        "iterations": r.iterations,
                        "seconds": finite(r.seconds),
                        "ms_per_iteration": finite(r.ms_per_iteration()),
                        "rejected_samples": r.rejected_samples,
                        "image": r.image,
                        "preview": r.preview,
                        "rmse": error.map_or(Value::Null, |e| finite(e.rmse)),
                        "relative_mse": error.map_or(Value::Null, |e| finite(e.relative_mse)),
                        "convergence": r.convergence.iter().map(|p| json!({
                            "iterations": p.iterations,
                            "seconds": finite(p.seconds),
                            "rmse": finite(p.rmse),
                            "relative_mse": finite(p.relative_mse),
                        })).collect::<Vec<_>>(),
                    })
                })
                .collect();
            json!({
                "scene": s.label,
                "width": s.width,
                "height": s.height,
                "reference": s.reference.as_ref().map(|(file, _)| file),
                "reference_preview": s.reference.as_ref().map(|(_, preview)| preview),
                "plot": s.plot,
                "results": results,
            })
        })
        .collect();
    json!({
        "time_per_combination_s": time,
        "iterations_per_combination": iterations,
        "seed": seed,
        "references": references,
        "relative_mse_epsilon": crate::compare::RELATIVE_MSE_EPSILON,
        "scenes": scenes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_three_significant_digits() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.23456), "1.23");
        assert_eq!(number(123.456), "123");
        assert_eq!(number(0.0123456), "0.0123");
        assert_eq!(number(0.00123456), "1.23e-3");
        assert_eq!(number(f64::NAN), "-");
    }

    #[test]
    fn html_is_escaped() {
        assert_eq!(escape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
    }
}
