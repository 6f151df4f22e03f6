//! Per-sample variance of the path tracer's Russian-roulette policies and MIS heuristics on the
//! four built-in Cornell scenes: `cargo run --release -p render --example pt_variance [iterations]`.
//!
//! For each configuration it renders `iterations` (default 64) one-sample iterations at 128²
//! and prints Σ(per-sample variance) / Σ(mean²) over pixels and channels, the CPU seconds per
//! iteration of the process (both threads), and their product relative to the previous default
//! (albedo roulette, balance heuristic): below 1 is more efficient.

use render::path_tracer::{Heuristic, RussianRoulette};
use render::{RenderSettings, driver::Budget};
use scene::cornell;

/// CPU seconds (user + system) of this process.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat.rsplit_once(')').map_or(vec![], |s| s.1.split_whitespace().collect());
    let get = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(0.0);
    (get(11) + get(12)) / 100.0
}

fn main() {
    let iterations: u64 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(64);
    let configs = [
        ("albedo, balance", RussianRoulette::Albedo, Heuristic::Balance),
        ("rr_depth 5, balance", RussianRoulette::Throughput { start: 5 }, Heuristic::Balance),
        ("rr_depth 5, power", RussianRoulette::Throughput { start: 5 }, Heuristic::Power),
        ("albedo, power", RussianRoulette::Albedo, Heuristic::Power),
    ];
    println!("{:<22} {:<22} {:>12} {:>12} {:>14}", "scene", "configuration", "rel. var", "CPU-s/iter", "var×time rel.");
    for builtin in &cornell::BUILTIN_SCENES {
        let scene = cornell::build(builtin.mask, 128, 128).unwrap();
        let mut reference = None;
        for (name, russian_roulette, heuristic) in configs {
            let settings = RenderSettings {
                budget: Budget::Iterations(iterations),
                russian_roulette,
                heuristic,
                seed: 11,
                ..RenderSettings::default()
            };
            let before = cpu_seconds();
            let film = render::render(&scene, &settings).unwrap().film;
            let cpu = (cpu_seconds() - before) / iterations as f64;
            let (mut variance, mut square) = (0.0f64, 0.0f64);
            for (v, m) in film.variance_of_mean().expect("kept by default").iter().zip(film.mean()) {
                for c in 0..3 {
                    variance += f64::from(v[c]) * iterations as f64;
                    square += f64::from(m[c]) * f64::from(m[c]);
                }
            }
            let relative = variance / square;
            let product = relative * cpu;
            let base = *reference.get_or_insert(product);
            println!("{:<22} {name:<22} {relative:>12.4} {cpu:>12.4} {:>14.3}", builtin.name, product / base);
        }
    }
}
