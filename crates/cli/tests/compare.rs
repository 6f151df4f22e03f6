//! End-to-end tests of `vcm compare`: metrics of identical and offset images, the exit code of
//! `--threshold` and of the per-pixel Z-test (with its variance floor for deterministic pixels),
//! non-finite pixels, size mismatches and `--diff`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn vcm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm")).args(args).output().expect("the vcm binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("compare-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes `image` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, image: &io::Image) -> PathBuf {
    let file = dir.join(name);
    io::write_image(&file, image, &io::WriteOptions::default()).unwrap();
    file
}

fn gradient() -> io::Image {
    io::Image::from_fn(6, 4, |x, y| [0.1 * x as f32, 0.2 * y as f32, 0.5 + 0.05 * (x + y) as f32])
}

fn offset(a: &io::Image, by: f32) -> io::Image {
    io::Image { pixels: a.pixels.iter().map(|p| p.map(|v| v + by)).collect(), ..a.clone() }
}

fn constant(like: &io::Image, value: f32) -> io::Image {
    io::Image::from_fn(like.width, like.height, |_, _| [value; 3])
}

/// The first number after `label` on the line that starts with it.
fn value(text: &str, label: &str) -> f64 {
    let line = text.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("no '{label}' in {text}"));
    line[label.len()..].split_whitespace().next().unwrap().parse().unwrap_or_else(|_| panic!("bad number: {line}"))
}

/// The per-channel means row of `channel`: mean A, mean B, A − B.
fn means(text: &str, channel: &str) -> [f64; 3] {
    let row = text.lines().find_map(|line| {
        let mut fields = line.split_whitespace();
        if fields.next() != Some(channel) {
            return None;
        }
        let numbers: Vec<f64> = fields.take(3).map_while(|f| f.parse().ok()).collect();
        (numbers.len() == 3).then(|| [numbers[0], numbers[1], numbers[2]])
    });
    row.unwrap_or_else(|| panic!("no means row for {channel} in {text}"))
}

#[test]
fn identical_images_give_zero() {
    let dir = temp_dir("identical");
    let a = write(&dir, "a.pfm", &gradient());
    let b = write(&dir, "b.exr", &gradient());
    let output = vcm(&["compare", path(&a), path(&b)]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = stdout(&output);
    for label in ["RMSE:", "relative MSE:", "MAE:"] {
        assert_eq!(value(&text, label), 0.0, "{label} in {text}");
    }
    for channel in ["R", "G", "B"] {
        let [ma, mb, d] = means(&text, channel);
        assert_eq!((ma, d), (mb, 0.0), "{text}");
    }
    assert!(text.contains("24 compared, 0 non-finite"), "{text}");
}

#[test]
fn offset_gives_the_known_numbers() {
    let dir = temp_dir("offset");
    let a_image = gradient();
    let b_image = offset(&a_image, 0.1);
    let a = write(&dir, "a.pfm", &a_image);
    let b = write(&dir, "b.pfm", &b_image);
    let output = vcm(&["compare", path(&a), path(&b)]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = stdout(&output);
    assert!((value(&text, "RMSE:") - 0.1).abs() < 1e-6, "{text}");
    assert!((value(&text, "MAE:") - 0.1).abs() < 1e-6, "{text}");
    let values: Vec<f64> = b_image.pixels.iter().flatten().map(|&v| f64::from(v)).collect();
    let expected = values.iter().map(|v| 0.01 / (v * v + 0.01)).sum::<f64>() / values.len() as f64;
    let relative_mse = value(&text, "relative MSE:");
    assert!((relative_mse - expected).abs() < 1e-6 * expected, "{relative_mse} vs {expected}: {text}");
    let (means_a, means_b) = (a_image.channel_means(), b_image.channel_means());
    for (c, channel) in ["R", "G", "B"].into_iter().enumerate() {
        let [ma, mb, d] = means(&text, channel);
        assert!((ma - means_a[c]).abs() < 1e-6 && (mb - means_b[c]).abs() < 1e-6, "{text}");
        assert!((d + 0.1).abs() < 1e-6, "A − B = −0.1: {text}");
    }

    // --threshold: just below the measured relative MSE fails with exit code 1, above passes.
    let below = format!("{}", expected * 0.99);
    let output = vcm(&["compare", path(&a), path(&b), "--threshold", &below]);
    assert_eq!(output.status.code(), Some(1), "{}{}", stdout(&output), stderr(&output));
    assert!(stdout(&output).contains("FAILED"));
    let above = format!("{}", expected * 1.01);
    let output = vcm(&["compare", path(&a), path(&b), "--threshold", &above]);
    assert_eq!(output.status.code(), Some(0), "{}{}", stdout(&output), stderr(&output));
    assert!(stdout(&output).contains("PASSED"));
}

#[test]
fn size_mismatch_and_missing_files_fail_clearly() {
    let dir = temp_dir("errors");
    let a = write(&dir, "a.pfm", &gradient());
    let b = write(&dir, "b.exr", &io::Image::new(3, 5));
    let output = vcm(&["compare", path(&a), path(&b)]);
    assert!(!output.status.success());
    let message = stderr(&output);
    for expected in ["error:", "6x4", "3x5", "a.pfm", "b.exr"] {
        assert!(message.contains(expected), "{message:?} lacks {expected:?}");
    }

    let missing = dir.join("missing.pfm");
    let output = vcm(&["compare", path(&a), path(&missing)]);
    assert!(!output.status.success());
    assert!(stderr(&output).contains("missing.pfm"), "{}", stderr(&output));
}

#[test]
fn z_test_fails_an_offset_and_passes_identical_images() {
    let dir = temp_dir("z-test");
    let a_image = gradient();
    let a = write(&dir, "a.exr", &a_image);
    let b = write(&dir, "b.exr", &offset(&a_image, 0.01));
    let variance = write(&dir, "variance.pfm", &constant(&a_image, 1e-6));
    let v = path(&variance);

    let output = vcm(&["compare", path(&a), path(&a), "--variance-a", v, "--variance-b", v]);
    assert_eq!(output.status.code(), Some(0), "{}{}", stdout(&output), stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("per-pixel Z-test: 72 entries") && text.contains("0 failing: PASSED"), "{text}");

    let output = vcm(&["compare", path(&a), path(&b), "--variance-a", v, "--variance-b", v]);
    assert_eq!(output.status.code(), Some(1), "{}{}", stdout(&output), stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("72 failing: FAILED"), "{text}");

    // Large variances make the same offset insignificant.
    let noisy = write(&dir, "noisy.pfm", &constant(&a_image, 1e-2));
    let output = vcm(&["compare", path(&a), path(&b), "--variance-a", path(&noisy), "--variance-b", path(&noisy)]);
    assert_eq!(output.status.code(), Some(0), "{}{}", stdout(&output), stderr(&output));
}

/// A deterministic background (constant 0.25, 0.5, 1.0: zero variance, like a constant
/// environment seen by every sample) around a noisy 4×4 object (variance 1e-4 per channel).
fn background_and_object(noise_sign: f32, background_factor: f32) -> (io::Image, io::Image) {
    let object = |x: usize, y: usize| (2..6).contains(&x) && (1..5).contains(&y);
    let image = io::Image::from_fn(8, 6, |x, y| {
        if object(x, y) {
            // Within ±1 standard error (0.01) of 0.3.
            [0.3 + noise_sign * 0.005 * ((x + y) % 3) as f32; 3]
        } else {
            [0.25 * background_factor, 0.5 * background_factor, background_factor]
        }
    });
    let variance = io::Image::from_fn(8, 6, |x, y| if object(x, y) { [1e-4; 3] } else { [0.0; 3] });
    (image, variance)
}

#[test]
fn zero_variance_background_passes_rounding_and_fails_a_real_difference() {
    let dir = temp_dir("variance-floor");
    let (reference, reference_variance) = background_and_object(1.0, 1.0);
    let a = write(&dir, "reference.pfm", &reference);
    let va = write(&dir, "reference-variance.pfm", &reference_variance);
    let compare = |b_image: &io::Image, b_variance: &io::Image, name: &str, extra: &[&str]| {
        let b = write(&dir, &format!("{name}.pfm"), b_image);
        let vb = write(&dir, &format!("{name}-variance.pfm"), b_variance);
        // The other image is the test image A, the deterministic one the reference B.
        let mut args = vec!["compare", path(&b), path(&a), "--variance-a", path(&vb), "--variance-b", path(&va)];
        args.extend_from_slice(extra);
        vcm(&args)
    };
    // The same scene by "another renderer": other noise on the object, the background off by
    // rounding (one half-float step, 2⁻¹¹ relative). 144 entries, 96 of them deterministic.
    let (rounded, rounded_variance) = background_and_object(-1.0, 1.0 + 2f32.powi(-11));
    let output = compare(&rounded, &rounded_variance, "rounded", &[]);
    let text = stdout(&output);
    assert_eq!(output.status.code(), Some(0), "{text}{}", stderr(&output));
    assert!(text.contains("per-pixel Z-test: 144 entries") && text.contains("0 failing: PASSED"), "{text}");
    assert!(text.contains("variance floor 0.001 of the value"), "{text}");
    // Without the floor, the rounding fails every background entry with an infinite z.
    let output = compare(&rounded, &rounded_variance, "rounded", &["--relative-floor", "0"]);
    let text = stdout(&output);
    assert_eq!(output.status.code(), Some(1), "{text}{}", stderr(&output));
    assert!(text.contains("96 failing: FAILED") && text.contains("worst z inf"), "{text}");
    // A background 1 % too bright is a real difference: z = 0.01 / 1.01e-3 ≈ 9.9 on every
    // background entry, while the object still passes.
    let (brighter, brighter_variance) = background_and_object(-1.0, 1.01);
    let output = compare(&brighter, &brighter_variance, "brighter", &[]);
    let text = stdout(&output);
    assert_eq!(output.status.code(), Some(1), "{text}{}", stderr(&output));
    assert!(text.contains("96 failing: FAILED") && text.contains("worst z 9.90"), "{text}");
    // A negative floor is refused.
    let output = compare(&rounded, &rounded_variance, "rounded", &["--relative-floor=-1"]);
    assert!(!output.status.success() && stderr(&output).contains("--relative-floor"), "{}", stderr(&output));
}

#[test]
fn non_finite_pixels_are_counted_and_excluded() {
    let dir = temp_dir("non-finite");
    let a_image = gradient();
    let mut b_image = a_image.clone();
    b_image.set(1, 2, [0.3, f32::NAN, 0.3]);
    let a = write(&dir, "a.pfm", &a_image);
    let b = write(&dir, "b.exr", &b_image);
    let output = vcm(&["compare", path(&a), path(&b)]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("23 compared, 1 non-finite excluded"), "{text}");
    assert_eq!(value(&text, "RMSE:"), 0.0, "{text}");
    assert!(!text.to_lowercase().contains("nan"), "{text}");
}

#[test]
fn diff_writes_a_png_of_the_right_size() {
    let dir = temp_dir("diff");
    let a_image = gradient();
    let a = write(&dir, "a.pfm", &a_image);
    let b = write(&dir, "b.pfm", &constant(&a_image, 0.4));
    let out = dir.join("diff.png");
    let output = vcm(&["compare", path(&a), path(&b), "--diff", path(&out)]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let diff = io::read_image(&out).unwrap();
    assert_eq!((diff.width, diff.height), (6, 4));
    // Pixel (0, 0) is darker than the reference (blue), (5, 3) brighter (red).
    let [r, g, b] = diff.get(0, 0);
    assert!(b > 0.1 && r == 0.0 && g == 0.0, "{:?}", diff.get(0, 0));
    let [r, g, b] = diff.get(5, 3);
    assert!(r > 0.1 && g == 0.0 && b == 0.0, "{:?}", diff.get(5, 3));
}

#[test]
fn rendered_variances_drive_the_per_pixel_z_test() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("compare-tests").join("rendered-variance");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let render = |name: &str, seed: &str, max_length: &str| {
        let image = dir.join(format!("{name}.pfm"));
        let variance = dir.join(format!("{name}-variance.pfm"));
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_vcm"))
            .args(["render", "--scene", "1", "-a", "pt", "-i", "64", "-r", "24x24", "--quiet", "--seed", seed])
            .args(["--max-length", max_length, "-o"])
            .arg(&image)
            .arg("--variance")
            .arg(&variance)
            .output()
            .unwrap();
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        (image, variance)
    };
    let compare = |a: &(std::path::PathBuf, std::path::PathBuf), b: &(std::path::PathBuf, std::path::PathBuf)| {
        std::process::Command::new(env!("CARGO_BIN_EXE_vcm"))
            .arg("compare")
            .arg(&a.0)
            .arg(&b.0)
            .arg("--variance-a")
            .arg(&a.1)
            .arg("--variance-b")
            .arg(&b.1)
            .output()
            .unwrap()
    };
    let first = render("first", "1", "10");
    let second = render("second", "2", "10");
    let short = render("short", "3", "2");
    let same = compare(&first, &second);
    assert_eq!(same.status.code(), Some(0), "{}", String::from_utf8_lossy(&same.stdout));
    // Direct lighting only is darker than the full solution: the Z-test must see it.
    let different = compare(&short, &second);
    assert_eq!(different.status.code(), Some(1), "{}", String::from_utf8_lossy(&different.stdout));
}
