//! `vcm bench`: times iterations of the algorithms on scenes, and measures each
//! configuration's peak memory beside the memory guard's estimate for it.
//!
//! Every (scene, algorithm) configuration runs in a child process of this binary (`vcm bench
//! --child …`), which prints its one row. Peak memory is the child's `VmHWM` (peak resident
//! set size) from `/proc/self/status`. A fresh process is what makes the peak belong to one
//! configuration: resetting the peak in one long process (`echo 5 > /proc/self/clear_refs`,
//! which does work on Linux) only lowers it to the *current* resident size, and that still
//! holds the earlier configurations' heap that the allocator keeps for reuse, plus their
//! thread pools; the peak of a fresh process is also what `vcm render` of that configuration
//! needs.

use std::process::Command;

use anyhow::{Context, Result, bail};
use clap::Args;
use render::RenderSettings;
use render::driver::Budget;
use scene::cornell::BUILTIN_SCENES;

use crate::{AlgorithmName, LoadedScene, RadiusModeName, load_scene, parse_resolution};

#[derive(Args)]
pub struct BenchArgs {
    /// Algorithms to time (default: pt, lt, ppm, bpm, bpt, vcm).
    #[arg(long, short, value_enum, value_delimiter = ',')]
    algorithm: Vec<AlgorithmName>,
    /// Scenes to time (ids or names; default: all four).
    #[arg(long, short, value_delimiter = ',')]
    scene: Vec<String>,
    /// Iterations per scene (after one warm-up iteration).
    #[arg(long, short, default_value_t = 8)]
    iterations: u64,
    /// Image size in pixels.
    #[arg(long, short, value_name = "WxH", default_value = "512x512", value_parser = parse_resolution)]
    resolution: (u32, u32),
    /// Worker threads (default: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// How the threads share the work (as `vcm render --parallelism`).
    #[arg(long, default_value = "auto", value_name = "auto|pixels|iterations", value_parser = crate::parse_parallelism)]
    parallelism: render::Parallelism,
    /// Memory-efficient progressive VCM (tech report §6.2) for the VCM engine's algorithms.
    #[arg(long)]
    memory_efficient: bool,
    /// Spectral rendering (four hero-rotated wavelengths per path).
    #[arg(long)]
    spectral: bool,
    /// Merging radius of the VCM engine's algorithms (as `vcm render --radius-mode`).
    #[arg(long, value_enum, default_value_t = RadiusModeName::Global)]
    radius_mode: RadiusModeName,
    /// Time the acceleration structure instead: BVH build and Mrays/s (closest hit and shadow
    /// rays, one thread and all) on each scene's geometry.
    #[arg(long)]
    accel: bool,
    /// Internal: run exactly one scene and one algorithm in this process and print its row.
    #[arg(long, hide = true)]
    child: bool,
}

/// The table's header; rows come from `row`.
const HEADER: [&str; 9] = [
    "scene",
    "algorithm",
    "ms/iteration",
    "CPU-s/iter",
    "light vertices",
    "B/vertex",
    "threads",
    "peak RSS KiB",
    "guard KiB",
];

pub fn run(args: BenchArgs) -> Result<()> {
    use AlgorithmName::*;
    let algorithms = if args.algorithm.is_empty() { vec![Pt, Lt, Ppm, Bpm, Bpt, Vcm] } else { args.algorithm.clone() };
    let scenes: Vec<String> = if args.scene.is_empty() {
        BUILTIN_SCENES.iter().map(|s| s.id.to_string()).collect()
    } else {
        args.scene.clone()
    };
    // Fail on a bad scene name before starting any child.
    let sources = scenes.iter().map(|s| session::scene_source(s, &[])).collect::<Result<Vec<_>>>()?;
    if args.accel {
        crate::bench_accel::header();
        for source in &sources {
            let LoadedScene { scene, .. } = load_scene(source, Some(args.resolution), true)?;
            crate::bench_accel::run(&scene, args.threads);
        }
        return Ok(());
    }
    if args.child {
        let ([source], [algorithm]) = (&sources[..], &algorithms[..]) else {
            bail!("bench --child takes exactly one scene and one algorithm");
        };
        return child(&args, source, *algorithm);
    }
    let h = HEADER;
    println!(
        "{:<22} {:>9} {:>13} {:>11} {:>15} {:>9} {:>8} {:>13} {:>10}  phases of the last iteration (ms)",
        h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]
    );
    let exe = std::env::current_exe().context("cannot find the vcm binary to run the configurations")?;
    for scene in &scenes {
        for algorithm in &algorithms {
            let name = algorithm.algorithm().name();
            let mut command = Command::new(&exe);
            command.args(["bench", "--child", "-s", scene, "-a", name]);
            command.args(["-i", &args.iterations.to_string()]);
            command.args(["-r", &format!("{}x{}", args.resolution.0, args.resolution.1)]);
            command.args(["--threads", &args.threads.to_string()]);
            command.args(["--parallelism", args.parallelism.name()]);
            if args.memory_efficient {
                command.arg("--memory-efficient");
            }
            if args.spectral {
                command.arg("--spectral");
            }
            command.args(["--radius-mode", args.radius_mode.name()]);
            let output = command.output().with_context(|| format!("cannot run '{}'", exe.display()))?;
            eprint!("{}", String::from_utf8_lossy(&output.stderr));
            if !output.status.success() {
                bail!("bench of {scene} with {name} failed ({})", output.status);
            }
            print!("{}", String::from_utf8_lossy(&output.stdout));
        }
    }
    Ok(())
}

/// Times one configuration in this process and prints its row.
fn child(args: &BenchArgs, source: &session::SceneSource, name: AlgorithmName) -> Result<()> {
    let LoadedScene { scene, file_max_length, .. } = load_scene(source, Some(args.resolution), true)?;
    let algorithm = name.algorithm();
    let settings = |budget| RenderSettings {
        algorithm,
        budget,
        threads: args.threads,
        parallelism: args.parallelism,
        max_length: file_max_length.unwrap_or(RenderSettings::default().max_length),
        memory_efficient: args.memory_efficient,
        spectral: args.spectral,
        radius_mode: args.radius_mode.mode(),
        // As `vcm render` without --variance or a checkpoint.
        variance: false,
        // As `vcm render`'s default.
        primary_samples: session::DEFAULT_SAMPLER,
        ..RenderSettings::default()
    };
    // The guard's estimate, made where the session makes it: after loading, before rendering.
    let one = settings(Budget::Iterations(1));
    // Side by side only as many as there are iterations to render.
    let lanes =
        one.lanes(render::worker_threads(args.threads), scene.camera.pixel_count()).min(args.iterations as usize);
    let guard_bytes = match one.vcm_settings() {
        Some(vcm) => session::guard::estimate_bytes(&scene, &vcm, 0, lanes),
        None => {
            render::vcm::memory::resident_bytes().unwrap_or(0)
                + render::vcm::memory::driver_bytes(scene.camera.pixel_count(), false)
        }
    };
    render::render(&scene, &settings(Budget::Iterations(1))).map_err(anyhow::Error::msg)?;
    let cpu_before = process_cpu_seconds();
    let result = render::render(&scene, &settings(Budget::Iterations(args.iterations))).map_err(anyhow::Error::msg)?;
    let ms = 1e3 * result.elapsed.as_secs_f64() / args.iterations as f64;
    let cpu = match (cpu_before, process_cpu_seconds()) {
        (Some(a), Some(b)) => format!("{:.3}", (b - a) / args.iterations as f64),
        _ => "-".to_string(),
    };
    let peak = peak_rss_kib().map_or("-".to_string(), |k| k.to_string());
    let guard = guard_bytes.div_ceil(1024).to_string();
    let (vertices, bytes) = match result.light_vertices {
        Some((count, bytes)) => (count.to_string(), bytes.to_string()),
        None => ("-".to_string(), "-".to_string()),
    };
    let phases = match result.vcm_stats {
        Some(s) => format!(
            "  light {:.0}, grid {:.0}, camera {:.0}{}",
            s.phases.light_pass.as_secs_f64() * 1e3,
            s.phases.grid_build.as_secs_f64() * 1e3,
            s.phases.camera_pass.as_secs_f64() * 1e3,
            if result.lanes > 1 {
                format!(" ({} iterations at a time, one thread each)", result.lanes)
            } else {
                String::new()
            }
        ),
        None => String::new(),
    };
    println!(
        "{:<22} {:>9} {:>13.1} {:>11} {:>15} {:>9} {:>8} {:>13} {:>10}{phases}",
        scene.name,
        algorithm.name(),
        ms,
        cpu,
        vertices,
        bytes,
        result.threads,
        peak,
        guard
    );
    Ok(())
}

/// Peak resident set size of this process (`VmHWM` in `/proc/self/status`, KiB); `None`
/// where that file does not exist (not Linux).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    line.trim().strip_suffix("kB")?.trim().parse().ok()
}

/// CPU time (user + system, all threads) of this process in seconds, from `/proc/self/stat`
/// (Linux; clock ticks of 1/100 s, the kernel's fixed USER_HZ). `None` elsewhere.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let user: f64 = fields.get(11)?.parse().ok()?;
    let system: f64 = fields.get(12)?.parse().ok()?;
    Some((user + system) / 100.0)
}
