//! Measures the wavelength groups of the merging algorithms in spectral mode: renders a
//! built-in scene with a given number of groups K and writes the mean image (EXR), printing
//! the per-channel image mean. `vcm compare` then compares images.
//!
//! `cargo run --release -p render --example spectral_groups -- SCENE ALGORITHM ITERATIONS
//! SIZE SEED rgb|spectral K OUT.exr [RADIUS_FACTOR]` (SCENE a built-in id, SIZE the square
//! resolution, radius factor 0.003 by default).

use render::driver::Renderer;
use render::{Algorithm, RenderSettings};
use std::path::Path;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (radius, args) = match args.len() {
        9 => (args[8].parse::<f32>().map_err(|e| format!("radius factor: {e}"))?, &args[..8]),
        _ => (0.003, &args[..]),
    };
    let [scene, algorithm, iterations, size, seed, mode, groups, out] = args else {
        return Err("usage: SCENE ALGORITHM ITERATIONS SIZE SEED rgb|spectral K OUT.exr [RADIUS_FACTOR]".into());
    };
    let number = |s: &str, what: &str| s.parse::<u64>().map_err(|e| format!("{what} '{s}': {e}"));
    let id = number(scene, "scene")?;
    let size = number(size, "size")? as u32;
    let mask = scene::cornell::builtin_scenes()
        .find(|s| u64::from(s.id) == id)
        .ok_or_else(|| format!("no built-in scene {id}"))?
        .mask;
    let scene = scene::cornell::build(mask, size, size).ok_or("invalid scene")?;
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).ok_or_else(|| format!("unknown algorithm {algorithm}"))?,
        seed: number(seed, "seed")?,
        spectral: mode == "spectral",
        wavelength_groups: number(groups, "K")? as u32,
        radius_factor: radius,
        ..RenderSettings::default()
    };
    let iterations = number(iterations, "iterations")?;
    let mut renderer = Renderer::new(&scene, &settings)?;
    let mut sum = vec![[0.0f64; 3]; (size * size) as usize];
    for _ in 0..iterations {
        renderer.step();
        for (s, p) in sum.iter_mut().zip(&renderer.frame().pixels) {
            for (c, v) in s.iter_mut().zip([p.r, p.g, p.b]) {
                *c += f64::from(v);
            }
        }
    }
    let n = iterations as f64;
    let pixels: Vec<[f32; 3]> = sum.iter().map(|s| s.map(|c| (c / n) as f32)).collect();
    let mut mean = [0.0f64; 3];
    for p in &pixels {
        for c in 0..3 {
            mean[c] += f64::from(p[c]) / pixels.len() as f64;
        }
    }
    println!("mean {:.6} {:.6} {:.6}", mean[0], mean[1], mean[2]);
    let image = io::Image { width: size as usize, height: size as usize, pixels };
    io::write_image(Path::new(out), &image, &io::WriteOptions::default()).map_err(|e| e.to_string())
}
