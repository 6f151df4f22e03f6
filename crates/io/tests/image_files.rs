//! Round trips and error behaviour of the image file readers and writers.

use std::fs;
use std::path::{Path, PathBuf};

use io::{Image, ImageError, ImageFormat, WriteOptions, downsample_box, linear_to_srgb8, read_image, write_image};

/// A fresh, empty directory for one test under Cargo's per-target temp dir
/// (emptied at the start of each run, left behind for inspection).
fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// 5 wide, 3 high, every pixel and channel distinct, so transposes and
/// flipped row orders are caught.
fn asymmetric_image() -> Image {
    Image::from_fn(5, 3, |x, y| {
        let base = (y * 5 + x) as f32;
        [0.125 + base, 0.5 * base + 0.03, 0.01 + base * base * 0.37]
    })
}

/// Like [`asymmetric_image`] but with awkward values that must survive a
/// lossless format bit for bit.
fn awkward_image() -> Image {
    let mut image = asymmetric_image();
    image.set(0, 0, [-1.5, f32::MIN_POSITIVE / 4.0, 1.0e30]);
    image.set(4, 2, [f32::INFINITY, f32::NEG_INFINITY, -0.0]);
    image.set(2, 1, [f32::NAN, 1.0 / 3.0, f32::EPSILON]);
    image
}

fn assert_bit_exact(a: &Image, b: &Image) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        assert_eq!(pa.map(f32::to_bits), pb.map(f32::to_bits), "pixel {i}: {pa:?} vs {pb:?}");
    }
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = scratch_dir("exr_round_trip");
    let path = dir.join("image.exr");
    let image = awkward_image();
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    assert_bit_exact(&image, &read_image(&path).unwrap());
}

#[test]
fn pfm_round_trip_is_bit_exact() {
    let dir = scratch_dir("pfm_round_trip");
    let path = dir.join("image.pfm");
    let image = awkward_image();
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    assert_bit_exact(&image, &read_image(&path).unwrap());
}

#[test]
fn hdr_round_trip_is_within_rgbe_precision() {
    let dir = scratch_dir("hdr_round_trip");
    let path = dir.join("image.hdr");
    let mut image = asymmetric_image();
    image.set(1, 0, [1.0e4, 2.0e-3, 0.0]);
    image.set(3, 2, [1.0e-6, 1.0e-6, 3.0e-6]);
    // Wide enough (>= 8) to exercise the run-length encoded scanlines too.
    let wide = Image::from_fn(19, 2, |x, y| [x as f32 + 0.5, y as f32 * 7.0 + 0.25, 3.0]);
    for image in [&image, &wide] {
        write_image(&path, image, &WriteOptions::default()).unwrap();
        let back = read_image(&path).unwrap();
        assert_eq!((back.width, back.height), (image.width, image.height));
        for (i, (a, b)) in image.pixels.iter().zip(&back.pixels).enumerate() {
            // RGBE truncates each channel to 8 bits relative to 2^e > max.
            let tolerance = a.iter().copied().fold(0.0f32, f32::max) / 128.0;
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= tolerance, "pixel {i} channel {c}: wrote {} read {}", a[c], b[c]);
            }
        }
    }
}

#[test]
fn hdr_sanitizes_unrepresentable_values() {
    let dir = scratch_dir("hdr_sanitize");
    let path = dir.join("image.hdr");
    let image = Image::from_fn(3, 1, |x, _| match x {
        0 => [f32::NAN, -2.0, 1.0],
        1 => [f32::INFINITY, 0.5, 1.0e-40],
        _ => [1.0e-39, 0.0, 0.0],
    });
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let back = read_image(&path).unwrap();
    assert_eq!(back.get(0, 0)[0], 0.0);
    assert_eq!(back.get(0, 0)[1], 0.0);
    assert!((back.get(0, 0)[2] - 1.0).abs() < 1.0 / 128.0);
    assert!(back.get(1, 0)[0] > 1.0e37 && back.get(1, 0)[0].is_finite());
    assert_eq!(back.get(2, 0), [0.0; 3]);
}

#[test]
fn pfm_layout_is_standard() {
    let dir = scratch_dir("pfm_layout");
    let path = dir.join("layout.pfm");
    let image = Image::from_fn(2, 3, |x, y| {
        let v = (10 * y + x) as f32;
        [v, v + 0.25, v + 0.5]
    });
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let bytes = fs::read(&path).unwrap();
    let header = b"PF\n2 3\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let data = &bytes[header.len()..];
    assert_eq!(data.len(), 2 * 3 * 3 * 4);
    let samples: Vec<f32> = data.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    // First stored row is the bottom row (y = 2), left to right.
    assert_eq!(&samples[0..6], &[20.0, 20.25, 20.5, 21.0, 21.25, 21.5]);
    // Last stored row is the top row (y = 0).
    assert_eq!(&samples[12..18], &[0.0, 0.25, 0.5, 1.0, 1.25, 1.5]);
}

#[test]
fn pfm_reads_big_endian_and_greyscale() {
    let dir = scratch_dir("pfm_variants");

    // 2x2 RGB, big-endian (positive scale, magnitude ignored).
    let mut bytes = b"PF 2 2 4.5\n".to_vec();
    let rows_bottom_first = [[[1.0f32, 2.0, 3.0], [4.0, 5.0, 6.0]], [[7.0, 8.0, 9.0], [10.0, 11.0, 12.0]]];
    for row in rows_bottom_first {
        for sample in row.iter().flatten() {
            bytes.extend_from_slice(&sample.to_be_bytes());
        }
    }
    let path = dir.join("big.pfm");
    fs::write(&path, &bytes).unwrap();
    let image = read_image(&path).unwrap();
    assert_eq!((image.width, image.height), (2, 2));
    assert_eq!(image.get(0, 1), [1.0, 2.0, 3.0]);
    assert_eq!(image.get(1, 1), [4.0, 5.0, 6.0]);
    assert_eq!(image.get(0, 0), [7.0, 8.0, 9.0]);
    assert_eq!(image.get(1, 0), [10.0, 11.0, 12.0]);

    // 3x2 greyscale, little-endian.
    let mut bytes = b"Pf\n3 2\n-1.000000\n".to_vec();
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let path = dir.join("grey.PFM");
    fs::write(&path, &bytes).unwrap();
    let image = read_image(&path).unwrap();
    assert_eq!((image.width, image.height), (3, 2));
    assert_eq!(image.get(0, 1), [1.0; 3]);
    assert_eq!(image.get(2, 1), [3.0; 3]);
    assert_eq!(image.get(0, 0), [4.0; 3]);
    assert_eq!(image.get(2, 0), [6.0; 3]);
}

#[test]
fn srgb_encoding_matches_the_standard() {
    assert_eq!(linear_to_srgb8(0.0), 0);
    // 12.92 * 0.0031308 * 255 = 10.31
    assert_eq!(linear_to_srgb8(0.003_130_8), 10);
    // (1.055 * 0.5^(1/2.4) - 0.055) * 255 = 187.52
    assert_eq!(linear_to_srgb8(0.5), 188);
    assert_eq!(linear_to_srgb8(1.0), 255);
    assert_eq!(linear_to_srgb8(2.0), 255);
    assert_eq!(linear_to_srgb8(-1.0), 0);
    assert_eq!(linear_to_srgb8(f64::NAN), 0);
    assert_eq!(linear_to_srgb8(f64::INFINITY), 255);
    // Just below the 0.5 code boundary of the linear segment: 0.001 -> 3.29
    assert_eq!(linear_to_srgb8(0.001), 3);
}

/// Decodes a PNG written by us to its raw 8-bit RGB codes.
fn png_codes(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoded = image::open(path).unwrap().into_rgb8();
    (decoded.width(), decoded.height(), decoded.into_raw())
}

#[test]
fn png_applies_exposure_clamp_and_srgb() {
    let dir = scratch_dir("png_exposure");
    let path = dir.join("preview.png");
    let image = Image::from_fn(3, 2, |x, y| match (x, y) {
        (0, 0) => [0.0, 0.003_130_8, 0.5],
        (1, 0) => [1.0, 2.0, f32::NAN],
        (2, 0) => [-3.0, f32::INFINITY, 0.25],
        (0, 1) => [0.25, 0.125, 0.001_565_4],
        _ => [0.0; 3],
    });

    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let (w, h, codes) = png_codes(&path);
    assert_eq!((w, h), (3, 2));
    assert_eq!(&codes[0..9], &[0, 10, 188, 255, 255, 0, 0, 255, 137]);

    // +1 stop doubles before encoding: 0.25 -> 0.5, 0.0015654 -> 0.0031308.
    write_image(&path, &image, &WriteOptions { exposure_stops: 1.0 }).unwrap();
    let (_, _, codes) = png_codes(&path);
    assert_eq!(&codes[9..12], &[188, 137, 10]);
    // -1 stop halves: 1.0 -> 0.5, 2.0 -> 1.0.
    write_image(&path, &image, &WriteOptions { exposure_stops: -1.0 }).unwrap();
    let (_, _, codes) = png_codes(&path);
    assert_eq!(&codes[3..5], &[188, 255]);
}

#[test]
fn png_reads_back_as_linear() {
    let dir = scratch_dir("png_read");
    let path = dir.join("image.png");
    let image = Image::from_fn(4, 3, |x, y| {
        let v = (y * 4 + x) as f32 / 11.0;
        [v, 1.0 - v, v * v]
    });
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let back = read_image(&path).unwrap();
    assert_eq!((back.width, back.height), (4, 3));
    for (a, b) in image.pixels.iter().zip(&back.pixels) {
        for c in 0..3 {
            // Half an 8-bit sRGB step is at most ~0.0045 in linear near 1.
            assert!((a[c] - b[c]).abs() < 0.005, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn extension_is_case_insensitive_and_checked() {
    assert_eq!(ImageFormat::from_path(Path::new("a/b.EXR")).unwrap(), ImageFormat::Exr);
    assert_eq!(ImageFormat::from_path(Path::new("b.Pfm")).unwrap(), ImageFormat::Pfm);
    assert_eq!(ImageFormat::from_path(Path::new("b.hdr")).unwrap(), ImageFormat::Hdr);
    assert_eq!(ImageFormat::from_path(Path::new("b.PNG")).unwrap(), ImageFormat::Png);

    let error = write_image(Path::new("a.bmp"), &Image::new(1, 1), &WriteOptions::default()).unwrap_err();
    assert!(matches!(error, ImageError::UnsupportedExtension { .. }));
    assert_eq!(error.to_string(), "unsupported image extension '.bmp' in 'a.bmp' (expected .exr, .pfm, .hdr or .png)");
    assert!(!Path::new("a.bmp").exists());

    let error = read_image(Path::new("noext")).unwrap_err();
    assert!(matches!(error, ImageError::MissingExtension { .. }));
    assert!(error.to_string().contains("'noext'"), "{error}");
}

#[test]
fn unwritable_path_names_the_file() {
    let dir = scratch_dir("unwritable");
    for ext in ["exr", "pfm", "hdr", "png"] {
        let path = dir.join("does-not-exist").join(format!("y.{ext}"));
        let error = write_image(&path, &asymmetric_image(), &WriteOptions::default()).unwrap_err();
        match &error {
            ImageError::Write { cause, .. } => {
                assert_eq!(cause.kind(), std::io::ErrorKind::NotFound);
            }
            other => panic!("expected a write error for .{ext}, got {other:?}"),
        }
        let message = error.to_string();
        assert!(message.starts_with(&format!("cannot write '{}': ", path.display())), "{message}");
    }
}

#[test]
fn missing_file_names_the_file() {
    let dir = scratch_dir("missing");
    for ext in ["exr", "pfm", "hdr", "png"] {
        let path = dir.join(format!("absent.{ext}"));
        let error = read_image(&path).unwrap_err();
        assert!(matches!(error, ImageError::Read { .. }), "{error:?}");
        assert!(error.to_string().starts_with(&format!("cannot read '{}': ", path.display())));
    }
}

#[test]
fn invalid_images_are_refused() {
    let dir = scratch_dir("invalid_images");
    let path = dir.join("bad.exr");
    let empty = Image::new(0, 4);
    let error = write_image(&path, &empty, &WriteOptions::default()).unwrap_err();
    assert!(error.to_string().contains("empty"), "{error}");
    let wrong = Image { width: 3, height: 2, pixels: vec![[0.0; 3]; 5] };
    let error = write_image(&path, &wrong, &WriteOptions::default()).unwrap_err();
    assert!(error.to_string().contains("3x2 but has 5 pixels"), "{error}");
    assert!(!path.exists());
}

#[test]
fn truncated_pfm_is_an_error() {
    let dir = scratch_dir("truncated_pfm");
    let path = dir.join("cut.pfm");
    write_image(&path, &asymmetric_image(), &WriteOptions::default()).unwrap();
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..bytes.len() - 7]).unwrap();
    let error = read_image(&path).unwrap_err();
    assert!(matches!(error, ImageError::Decode { format: ImageFormat::Pfm, .. }));
    let message = error.to_string();
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert!(message.contains("truncated"), "{message}");
    assert!(message.contains("expected 180 bytes"), "{message}");

    // Extra bytes are reported too.
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0; 4]);
    fs::write(&path, &longer).unwrap();
    let message = read_image(&path).unwrap_err().to_string();
    assert!(message.contains("4 unexpected bytes"), "{message}");
}

#[test]
fn malformed_pfm_headers_explain_what_was_expected() {
    let dir = scratch_dir("malformed_pfm");
    let path = dir.join("bad.pfm");
    let cases: [(&[u8], &str); 9] = [
        (b"", "expected magic 'PF' (RGB) or 'Pf' (greyscale), found ''"),
        (b"P6\n2 2\n255\n", "expected magic 'PF' (RGB) or 'Pf' (greyscale), found 'P6'"),
        (b"PFX 2 2 -1\n", "expected whitespace after the magic"),
        (b"PF\n", "file ends before the width"),
        (b"PF\n0 2\n-1\n", "expected a positive integer width, found '0'"),
        (b"PF\n2 x\n-1\n", "expected a positive integer height, found 'x'"),
        (b"PF\n2 2\n0\n", "expected a finite non-zero scale"),
        (b"PF\n99999999999 99999999999\n-1\n", "exceed the limit"),
        (b"PF\n10000 10000\n-1\n", "truncated pixel data"),
    ];
    for (bytes, expected) in cases {
        fs::write(&path, bytes).unwrap();
        let error = read_image(&path).unwrap_err();
        let message = error.to_string();
        assert!(message.contains(expected), "{:?}: {message}", bytes.escape_ascii().to_string());
        assert!(message.contains("bad.pfm"), "{message}");
    }
}

#[test]
fn corrupt_files_of_every_format_give_errors() {
    let dir = scratch_dir("corrupt");
    let image = asymmetric_image();
    for ext in ["exr", "hdr", "png"] {
        let path = dir.join(format!("image.{ext}"));
        write_image(&path, &image, &WriteOptions::default()).unwrap();
        let bytes = fs::read(&path).unwrap();
        // A PNG missing only the end of its IEND chunk still holds every
        // pixel and decodes, so cut PNGs deeper.
        let last = if ext == "png" { bytes.len() - 13 } else { bytes.len() - 1 };
        for keep in [0, 1, 3, bytes.len() / 2, last] {
            fs::write(&path, &bytes[..keep]).unwrap();
            let error =
                read_image(&path).map(|_| ()).expect_err(&format!(".{ext} cut to {keep} of {} bytes", bytes.len()));
            assert!(error.to_string().contains(&path.display().to_string()), "{error}");
        }
        fs::write(&path, b"this is not an image file at all, just text").unwrap();
        assert!(read_image(&path).is_err());
    }
}

#[test]
fn channel_means_and_downsampling() {
    let image = Image::from_fn(4, 2, |x, y| [x as f32, y as f32, (x + 4 * y) as f32]);
    assert_eq!(image.channel_means(), [1.5, 0.5, 3.5]);
    assert_eq!(Image::new(0, 0).channel_means(), [0.0; 3]);

    let small = downsample_box(&image, 2).unwrap();
    assert_eq!((small.width, small.height), (2, 1));
    assert_eq!(small.get(0, 0), [0.5, 0.5, 2.5]);
    assert_eq!(small.get(1, 0), [2.5, 0.5, 4.5]);
    assert_eq!(small.channel_means(), image.channel_means());
    assert_eq!(downsample_box(&image, 1).unwrap(), image);

    let error = downsample_box(&image, 3).unwrap_err();
    assert!(error.to_string().contains("4x2 image is not divisible into 3x3 blocks"), "{error}");
    assert!(downsample_box(&image, 0).is_err());
}

#[test]
fn corrupted_bytes_never_panic() {
    let dir = scratch_dir("bit_flips");
    let image = Image::from_fn(19, 7, |x, y| [x as f32 * 0.3, y as f32, 0.5]);
    // Small deterministic generator (64-bit LCG, high bits).
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move |bound: usize| {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) as usize) % bound
    };
    for ext in ["exr", "pfm", "hdr", "png"] {
        let path = dir.join(format!("image.{ext}"));
        write_image(&path, &image, &WriteOptions::default()).unwrap();
        let original = fs::read(&path).unwrap();
        for _ in 0..100 {
            let mut bytes = original.clone();
            for _ in 0..=next(4) {
                let at = next(bytes.len());
                bytes[at] ^= 1 << next(8);
            }
            fs::write(&path, &bytes).unwrap();
            // Either outcome is fine; only a panic fails the test.
            if let Err(error) = read_image(&path) {
                assert!(error.to_string().contains(&path.display().to_string()));
            }
        }
    }
}
