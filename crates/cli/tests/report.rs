//! End-to-end tests of `vcm report`: a tiny report links existing files and its numbers agree
//! with an independent computation from the written images; a reference equal to the output
//! gives zero error; bad arguments fail with exit code 2 naming the offending value.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn vcm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm")).args(args).output().expect("the vcm binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn read_json(file: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(file).unwrap()).expect("report.json is valid JSON")
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("expected a number, got {v}"))
}

/// RMSE and relative MSE (ε = 1e-2) of `a` against `b`, computed here from their definitions.
fn errors(a: &io::Image, b: &io::Image) -> (f64, f64) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let (mut squared, mut relative, mut n) = (0.0, 0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            let (x, y) = (f64::from(p[c]), f64::from(q[c]));
            squared += (x - y) * (x - y);
            relative += (x - y) * (x - y) / (y * y + 1e-2);
            n += 1.0;
        }
    }
    ((squared / n).sqrt(), relative / n)
}

/// The values of every `src="…"` and `href="…"` attribute of an HTML page.
fn links(html: &str) -> Vec<String> {
    let mut found = Vec::new();
    for attribute in ["src=\"", "href=\""] {
        let mut rest = html;
        while let Some(start) = rest.find(attribute) {
            rest = &rest[start + attribute.len()..];
            let end = rest.find('"').expect("closed attribute");
            found.push(rest[..end].to_string());
            rest = &rest[end..];
        }
    }
    found
}

#[test]
fn tiny_report_links_its_files_and_its_errors_shrink() {
    let dir = temp_dir("tiny");
    // The reference: the same scene, another seed, many iterations. cornell-env: its sky lights
    // the box broadly, so path tracing has no fireflies and the errors fall as 1/iterations.
    let reference = dir.join("reference.exr");
    let output = vcm(&[
        "render",
        "--scene",
        "3",
        "-a",
        "pt",
        "-i",
        "512",
        "--seed",
        "99",
        "-r",
        "32x32",
        "--quiet",
        "-o",
        path(&reference),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));

    let out = dir.join("report");
    let reference_arg = format!("cornell-env={}", path(&reference));
    let output = vcm(&[
        "report",
        "--scenes",
        "3",
        "--algorithms",
        "pt,vcm",
        "--time",
        "0.3",
        "-r",
        "32x32",
        "--reference",
        &reference_arg,
        "-o",
        path(&out),
    ]);
    let message = stderr(&output);
    assert!(output.status.success(), "{message}");
    assert!(message.contains("[1/2] cornell-env with pt") && message.contains("[2/2]"), "{message}");

    // Every image, the SVG and the JSON that the page links exist.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let linked = links(&html);
    for expected in [
        "cornell-env/pt.png",
        "cornell-env/vcm.png",
        "cornell-env/reference.png",
        "cornell-env/pt.exr",
        "cornell-env/convergence.svg",
        "report.json",
    ] {
        assert!(linked.iter().any(|l| l == expected), "index.html does not link {expected}: {linked:?}");
    }
    for link in &linked {
        assert!(out.join(link).is_file(), "index.html links {link}, which does not exist");
    }
    let svg = std::fs::read_to_string(out.join("cornell-env/convergence.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("\npt\n") && svg.contains("\nvcm\n"), "{svg}");

    let json = read_json(&out.join("report.json"));
    let scene = &json["scenes"][0];
    assert_eq!(scene["scene"], "cornell-env");
    let results = scene["results"].as_array().unwrap();
    let names: Vec<&str> = results.iter().map(|r| r["algorithm"].as_str().unwrap()).collect();
    assert_eq!(names, ["pt", "vcm"], "one entry per algorithm, in order");
    let reference_image = io::read_image(&reference).unwrap();
    for r in results {
        let name = r["algorithm"].as_str().unwrap();
        let iterations = r["iterations"].as_u64().unwrap();
        let seconds = num(&r["seconds"]);
        assert!(iterations >= 1 && (0.3..30.0).contains(&seconds), "{name}: {iterations} iterations in {seconds} s");
        let ms = num(&r["ms_per_iteration"]);
        assert!((ms - 1e3 * seconds / iterations as f64).abs() <= 1e-9 * ms, "{name}: {ms} ms/iteration");

        // The final errors agree with an independent computation from the written image.
        let image = io::read_image(&out.join(r["image"].as_str().unwrap())).unwrap();
        let (rmse, relative_mse) = errors(&image, &reference_image);
        assert!(rmse > 0.0 && relative_mse > 0.0, "{name}: a noisy render differs from the reference");
        assert!((num(&r["rmse"]) - rmse).abs() <= 1e-9 * rmse, "{name}: RMSE {} vs {rmse}", r["rmse"]);
        assert!(
            (num(&r["relative_mse"]) - relative_mse).abs() <= 1e-9 * relative_mse,
            "{name}: relMSE {} vs {relative_mse}",
            r["relative_mse"]
        );

        // Recorded after iterations 1, 2, 4, … and at the end, at increasing times.
        let points = r["convergence"].as_array().unwrap();
        let at: Vec<u64> = points.iter().map(|p| p["iterations"].as_u64().unwrap()).collect();
        let mut expected: Vec<u64> = (0..64).map(|k| 1u64 << k).take_while(|&n| n <= iterations).collect();
        if expected.last() != Some(&iterations) {
            expected.push(iterations);
        }
        assert_eq!(at, expected, "{name}: recorded iterations");
        let times: Vec<f64> = points.iter().map(|p| num(&p["seconds"])).collect();
        assert!(times.windows(2).all(|w| w[0] < w[1]) && (times[times.len() - 1] - seconds).abs() < 1e-12);
        assert_eq!(points.last().unwrap()["relative_mse"], r["relative_mse"]);

        // The error trend decreases, up to noise: no point is above 1.5x the best before it,
        // and when 16 or more iterations were rendered the last error is below a quarter of
        // the first one (the variance of a mean of 16 iterations is 1/16 of one).
        let relative: Vec<f64> = points.iter().map(|p| num(&p["relative_mse"])).collect();
        assert!(relative.iter().all(|e| e.is_finite() && *e > 0.0), "{name}: {relative:?}");
        let mut best = f64::INFINITY;
        for &e in &relative {
            assert!(e <= 1.5 * best, "{name}: error rises from {best} to {e}: {relative:?}");
            best = best.min(e);
        }
        if iterations >= 16 {
            assert!(relative[relative.len() - 1] < 0.25 * relative[0], "{name}: {relative:?}");
        }
    }
}

#[test]
fn a_reference_equal_to_the_output_gives_zero_error() {
    let dir = temp_dir("identical");
    let reference = dir.join("reference.pfm");
    let output = vcm(&[
        "render",
        "--scene",
        "cornell-area-mirror",
        "-a",
        "bpt",
        "-i",
        "4",
        "--seed",
        "5",
        "-r",
        "24x16",
        "--quiet",
        "-o",
        path(&reference),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let out = dir.join("report");
    let reference_arg = format!("1={}", path(&reference));
    let output = vcm(&[
        "report",
        "--scenes",
        "1",
        "--algorithms",
        "bpt",
        "--iterations",
        "4",
        "--seed",
        "5",
        "-r",
        "24x16",
        "--threads",
        "1",
        "--reference",
        &reference_arg,
        "-o",
        path(&out),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let json = read_json(&out.join("report.json"));
    let r = &json["scenes"][0]["results"][0];
    assert_eq!(r["iterations"], 4);
    assert_eq!(num(&r["rmse"]), 0.0, "the same seed and iterations give the reference, bit for bit");
    assert_eq!(num(&r["relative_mse"]), 0.0);
    let points = r["convergence"].as_array().unwrap();
    let at: Vec<u64> = points.iter().map(|p| p["iterations"].as_u64().unwrap()).collect();
    assert_eq!(at, [1, 2, 4]);
    assert!(num(&points[0]["relative_mse"]) > 0.0, "one iteration differs from four");
    // The zero cannot be drawn on log axes; the plot shows the other points.
    assert!(out.join("cornell-area-mirror/convergence.svg").is_file());
}

/// Runs `vcm` with `args`, expecting exit code 2 and every `expected` text in the message.
fn assert_fails(args: &[&str], expected: &[&str]) {
    let output = vcm(args);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{args:?}: {message}");
    assert!(!message.contains("panicked"), "{args:?}: {message}");
    for e in expected {
        assert!(message.contains(e), "{args:?}: message {message:?} lacks {e:?}");
    }
}

#[test]
fn bad_arguments_fail_with_exit_code_2() {
    let dir = temp_dir("errors");
    let out = dir.join("report");
    let o = path(&out);
    let small = dir.join("small.pfm");
    let image = io::Image::from_fn(24, 16, |_, _| [0.5; 3]);
    io::write_image(&small, &image, &io::WriteOptions::default()).unwrap();
    let bad_size = format!("1={}", path(&small));
    let common = ["report", "--time", "0.1", "-r", "32x32", "-o", o];
    let with = |extra: &[&'static str]| -> Vec<&str> { common.iter().copied().chain(extra.iter().copied()).collect() };

    assert_fails(&with(&["--scenes", "1,cornell-moon"]), &["unknown scene 'cornell-moon'", "cornell-sun"]);
    assert_fails(&with(&["--scenes", "1", "--algorithms", "pt,foo"]), &["invalid value 'foo'", "--algorithms"]);
    assert_fails(
        &with(&["--scenes", "1", "--reference", "1=/nonexistent/ref.exr"]),
        &["--reference '1=/nonexistent/ref.exr'", "/nonexistent/ref.exr"],
    );
    assert_fails(
        &common.iter().copied().chain(["--scenes", "1", "--reference", &bad_size]).collect::<Vec<_>>(),
        &[path(&small), "24x16", "32x32"],
    );
    assert_fails(&with(&["--scenes", "1", "--reference", "2=x.exr"]), &["--reference '2=x.exr'", "scene '2'"]);
    assert_fails(&with(&["--scenes", "1", "--reference", "x.exr"]), &["--reference 'x.exr'", "NAME=FILE"]);
    assert_fails(&["report", "--scenes", "1", "--time", "0", "-o", o], &["--time must be a positive number"]);
    assert_fails(&["report", "--scenes", "1", "-o", o], &["--time"]);
    assert_fails(&["report", "--scenes", "1", "--time", "1", "-r", "32", "-o", o], &["invalid resolution '32'"]);
    assert!(!out.exists(), "nothing is written before the arguments are checked");

    // An output "directory" below a regular file cannot be created.
    let file = dir.join("file");
    std::fs::write(&file, b"x").unwrap();
    let below = file.join("report");
    assert_fails(
        &["report", "--scenes", "1", "--time", "0.1", "-r", "8x8", "-o", path(&below)],
        &["cannot create the output directory", path(&below)],
    );
}

#[test]
fn sigint_finishes_the_running_combination_and_writes_the_page() {
    let dir = temp_dir("sigint");
    let out = dir.join("report");
    // Two scenes of 60 s per algorithm: only an interrupt ends this quickly.
    let child = Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(["report", "--scenes", "1,3", "--algorithms", "pt,vcm", "--time", "60", "-r", "24x24", "-o"])
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let start = std::time::Instant::now();
    let output = child.wait_with_output().unwrap();
    assert!(start.elapsed().as_secs() < 30, "the report stopped within an iteration, not at its budget");
    let message = stderr(&output);
    assert!(output.status.success(), "an interrupted report exits cleanly: {message}");
    assert!(message.contains("interrupted: the report has 1 of 4 combinations"), "{message}");
    // The page shows the combination that ran, with the images it links.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let linked = links(&html);
    assert!(linked.iter().any(|l| l == "cornell-area-mirror/pt.png"), "{linked:?}");
    assert!(!linked.iter().any(|l| l.contains("vcm.png")), "{linked:?}");
    for link in &linked {
        assert!(out.join(link).is_file(), "index.html links {link}, which does not exist");
    }
}
