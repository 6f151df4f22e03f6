//! The engine's memory: the memory-efficient mode renders the default mode's image bit for bit
//! (it traces the same light sub-paths twice instead of storing them), and the memory estimate
//! that guards renders is within ±15 % of the peak resident memory measured in a child process,
//! for every algorithm.

mod common;

use std::process::Command;

use common::settings;
use render::RenderSettings;
use render::driver::Budget;
use render::vcm::RadiusMode;
use render::vcm::memory;
use scene::cornell;

fn sums(mask: u32, settings: &RenderSettings) -> Vec<[f64; 3]> {
    let scene = cornell::build(mask, 48, 40).unwrap();
    render::render(&scene, settings).unwrap().film.sums().to_vec()
}

#[test]
fn memory_efficient_mode_renders_the_default_image_bit_for_bit() {
    let cases = [
        (273, settings("vcm", 3), "vcm"),
        (456, settings("bpm", 4), "bpm"),
        (273, settings("ppm", 5), "ppm"),
        (452, settings("bpt", 6), "bpt"),
        (273, RenderSettings { radius_mode: RadiusMode::PerPixel, ..settings("vcm", 7) }, "vcm per-pixel"),
        (273, RenderSettings { spectral: true, ..settings("vcm", 8) }, "vcm spectral"),
        (cornell::FLUORESCENT | 1, RenderSettings { spectral: true, ..settings("vcm", 9) }, "vcm fluorescent"),
    ];
    for (mask, base, what) in cases {
        let base = RenderSettings { budget: Budget::Iterations(3), threads: 2, ..base };
        let efficient = RenderSettings { memory_efficient: true, ..base.clone() };
        let (a, b) = (sums(mask, &base), sums(mask, &efficient));
        assert!(a.iter().flatten().any(|v| *v > 0.0), "{what}: black image");
        assert!(a == b, "{what}: the memory-efficient mode changed the image");
    }
}

/// Environment variable that makes the test binary, started as a child, render one
/// configuration and report its memory instead of running the test.
const CHILD: &str = "VCM_MEMORY_CHILD";

/// Resident memory of this process from `/proc/self/status` (`VmRSS` or `VmHWM`), in bytes.
fn status_bytes(key: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with(key)).unwrap();
    line.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() * 1024
}

/// The child's side: renders configuration `spec` (`algorithm[,memory-efficient][,spectral]`)
/// of scene 1 at 512² for two iterations (the first leaves the film's pages untouched until
/// it ends); prints the resident memory before the render, the
/// estimate and the peak.
fn child(spec: &str) {
    let mut parts = spec.split(',');
    let algorithm = parts.next().unwrap();
    let mut settings = RenderSettings { threads: 2, budget: Budget::Iterations(2), ..settings(algorithm, 1) };
    for flag in parts {
        match flag {
            "memory-efficient" => settings.memory_efficient = true,
            "spectral" => settings.spectral = true,
            "no-variance" => settings.variance = false,
            "pixels" => settings.parallelism = render::Parallelism::Pixels,
            other => panic!("unknown flag {other}"),
        }
    }
    let scene = cornell::build(cornell::BUILTIN_SCENES[1].mask, 512, 512).unwrap();
    let before = status_bytes("VmRSS:");
    let pixels = scene.camera.pixel_count();
    let one_lane = match settings.vcm_settings() {
        Some(vcm) => {
            let e = memory::estimate(&scene, &vcm, settings.seed);
            if settings.memory_efficient { e.memory_efficient_bytes } else { e.two_stage_bytes }
        }
        None => memory::driver_bytes(pixels, settings.variance),
    };
    // Iterations side by side (the VCM engine's default at this size) hold one set of buffers
    // per lane.
    let lanes = settings.lanes(settings.threads, pixels);
    let estimate = memory::lanes_bytes(one_lane, pixels, settings.variance, lanes);
    let output = render::render(&scene, &settings).unwrap();
    assert_eq!(output.film.iterations(), 2);
    assert_eq!(output.lanes, lanes);
    println!("memory {before} {estimate} {}", status_bytes("VmHWM:"));
}

#[test]
fn memory_estimate_is_within_15_percent_of_the_measured_peak() {
    if let Ok(spec) = std::env::var(CHILD) {
        return child(&spec);
    }
    let specs = [
        "pt",
        "pt,no-variance",
        "lt",
        "ppm",
        "bpm",
        "bpt",
        "vcm",
        "vcm,pixels",
        "vcm,no-variance",
        "bpt,pixels",
        "vcm,memory-efficient",
        "vcm,memory-efficient,no-variance",
        "bpt,memory-efficient",
        "vcm,spectral",
    ];
    let mut failures = Vec::new();
    for spec in specs {
        let out = Command::new(std::env::current_exe().unwrap())
            .args(["memory_estimate_is_within_15_percent_of_the_measured_peak", "--exact", "--nocapture"])
            .env(CHILD, spec)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{spec}: child failed: {stdout}{}", String::from_utf8_lossy(&out.stderr));
        let line = stdout.lines().find(|l| l.starts_with("memory ")).unwrap_or_else(|| panic!("{spec}: {stdout}"));
        let numbers: Vec<f64> = line.split_whitespace().skip(1).map(|n| n.parse().unwrap()).collect();
        let (before, estimate, peak) = (numbers[0], numbers[1], numbers[2]);
        let predicted = before + estimate;
        let error = predicted / peak - 1.0;
        let mib = |b: f64| b / f64::from(1 << 20);
        eprintln!(
            "{spec:<32} before {:6.1} MiB, estimate {:6.1} MiB, predicted {:6.1} MiB, peak {:6.1} MiB: {:+.1} %",
            mib(before),
            mib(estimate),
            mib(predicted),
            mib(peak),
            100.0 * error
        );
        if error.abs() > 0.15 {
            failures.push(spec);
        }
    }
    assert!(failures.is_empty(), "estimate off by more than 15 % for {failures:?}");
}
