//! Where the failing entries of a conformance render lie, by distance to the image border.
//!
//! Usage: `conformance-by-border RENDER RENDER_VARIANCE REFERENCE REFERENCE_VARIANCE REF_SPP`
//! (`RENDER_VARIANCE` as `vcm render --variance` writes it, the variance of the mean;
//! `REFERENCE_VARIANCE` Mitsuba's variance of one sample, divided by `REF_SPP`). The test per
//! pixel channel is `vcm conformance`'s: z with the relative variance floor 1e-3, two-sided,
//! Šidák-corrected α = 0.01 over all entries.

use std::path::Path;

use image_metrics::ztest::two_sided_p;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 6 {
        eprintln!("usage: conformance-by-border RENDER RENDER_VARIANCE REFERENCE REFERENCE_VARIANCE REF_SPP");
        std::process::exit(2);
    }
    let read = |p: &str| io::read_image(Path::new(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    let (test, test_var, reference, reference_var) = (read(&args[1]), read(&args[2]), read(&args[3]), read(&args[4]));
    let spp: f64 = args[5].parse().expect("REF_SPP: a number");
    let (w, h) = (reference.width, reference.height);
    let mut scores = Vec::new();
    for i in 0..w * h {
        for c in 0..3 {
            let (a, b) = (test.pixels[i][c] as f64, reference.pixels[i][c] as f64);
            let (var_a, var_b) = (test_var.pixels[i][c] as f64, reference_var.pixels[i][c] as f64 / spp);
            if !(b.is_finite() && var_b.is_finite()) {
                continue;
            }
            let floor = 1e-3 * a.abs().max(b.abs());
            let z = if a == b { 0.0 } else { (a - b) / (var_a.max(0.0) + var_b.max(0.0)).max(floor * floor).sqrt() };
            scores.push((i, z));
        }
    }
    let threshold = -((-0.01f64).ln_1p() / scores.len() as f64).exp_m1();
    let (mut failing, mut total) = ([0usize; 5], [0usize; 5]);
    for &(i, z) in &scores {
        let (x, y) = (i % w, i / w);
        let distance = x.min(y).min(w - 1 - x).min(h - 1 - y).min(4);
        total[distance] += 1;
        if !(two_sided_p(z.abs()) >= threshold) {
            failing[distance] += 1;
        }
    }
    println!("{w}x{h}, {} entries; failing entries by distance to the border (pixels):", scores.len());
    for d in 0..5 {
        let label = if d == 4 { ">=4".to_string() } else { d.to_string() };
        let share = 100.0 * failing[d] as f64 / total[d].max(1) as f64;
        println!("  {label:>3}: {}/{} ({share:.2} %)", failing[d], total[d]);
    }
    let all: usize = failing.iter().sum();
    println!("  all: {all} ({:.2} %)", 100.0 * all as f64 / scores.len() as f64);
}
