//! Image textures in every common format: tiny images written with the `image` crate into a
//! scratch directory, read back through `read_texture_file` and the two scene loaders, and
//! compared with the sRGB formula written out here (IEC 61966-2-1), Mitsuba's rule (integer
//! formats sRGB unless `raw`, float formats linear) and pbrt-v4's (`encoding` "sRGB" by
//! default, "linear", "gamma g"; float formats linear).

use std::fs;
use std::path::{Path, PathBuf};

use image::{ImageBuffer, Luma, Rgb as ImageRgb, Rgb32FImage, RgbImage};
use io::{StoredValues, TextureEncoding};
use math::Vec2;
use scene::Texture;
use scene::desc::SceneDescription;
use scene::material::Material;

/// The grey codes of the test images' four columns.
const CODES: [u8; 4] = [0, 10, 128, 255];

/// sRGB decoding (IEC 61966-2-1), independent of the crate's implementation.
fn srgb_to_linear(encoded: f64) -> f64 {
    if encoded <= 0.04045 { encoded / 12.92 } else { ((encoded + 0.055) / 1.055).powf(2.4) }
}

fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-texture-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 4×2 RGB image: column `i` is grey `CODES[i]` in row 0; row 1 holds pure red, green, blue
/// and white, so channel order is checked too.
fn rgb8() -> RgbImage {
    ImageBuffer::from_fn(4, 2, |x, y| {
        if y == 0 {
            ImageRgb([CODES[x as usize]; 3])
        } else {
            ImageRgb([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]][x as usize])
        }
    })
}

/// The linear values an exact decoder gives for `rgb8()` with `decode` applied per code.
fn expected_rgb8(decode: impl Fn(f64) -> f64) -> Vec<[f64; 3]> {
    let d = |c: u8| decode(f64::from(c) / 255.0);
    let mut out: Vec<[f64; 3]> = CODES.iter().map(|&c| [d(c); 3]).collect();
    out.extend([[d(255), d(0), d(0)], [d(0), d(255), d(0)], [d(0), d(0), d(255)], [d(255); 3]]);
    out
}

/// Asserts every channel of `pixels` is within `tol` of `expected`.
fn assert_pixels(pixels: &[[f32; 3]], expected: &[[f64; 3]], tol: f64, what: &str) {
    assert_eq!(pixels.len(), expected.len(), "{what}");
    for (i, (p, e)) in pixels.iter().zip(expected).enumerate() {
        for c in 0..3 {
            assert!((f64::from(p[c]) - e[c]).abs() <= tol, "{what}: pixel {i} channel {c}: {} vs {}", p[c], e[c]);
        }
    }
}

/// The tolerance for an 8-bit format stored exactly: float rounding only.
const EXACT: f64 = 1e-6;
/// JPEG: YCbCr conversion and the DCT of flat 8×8 blocks may move a code by one. One code
/// near the top of the sRGB curve is at most (eotf(1) − eotf(254/255)) ≈ 0.0107 linear.
const JPEG: f64 = 0.011;

#[test]
fn every_integer_format_decodes_to_the_srgb_formula() {
    let dir = scratch_dir("integer_formats");
    let image = rgb8();
    let srgb = expected_rgb8(srgb_to_linear);
    for (ext, tol) in [("png", EXACT), ("tga", EXACT), ("bmp", EXACT), ("tif", EXACT), ("tiff", EXACT), ("gif", EXACT)]
    {
        let path = dir.join(format!("t.{ext}"));
        image.save(&path).unwrap();
        let file = io::read_texture_file(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.stored, StoredValues::Integer { bits: 8 }, "{ext}");
        assert_pixels(&file.linear(TextureEncoding::Srgb).pixels, &srgb, tol, ext);
        // raw / "linear": the codes / 255.
        assert_pixels(&file.linear(TextureEncoding::Linear).pixels, &expected_rgb8(|v| v), tol, ext);
    }
    // JPEG is lossy: the flat grey row is stored almost exactly; the saturated primaries of
    // the second row bleed under chroma subsampling, so only the first row is compared.
    let gray: ImageBuffer<ImageRgb<u8>, Vec<u8>> =
        ImageBuffer::from_fn(32, 8, |x, _| ImageRgb([CODES[(x / 8) as usize]; 3]));
    for ext in ["jpg", "jpeg"] {
        let path = dir.join(format!("t.{ext}"));
        gray.save(&path).unwrap();
        let file = io::read_texture_file(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.stored, StoredValues::Integer { bits: 8 });
        let linear = file.linear(TextureEncoding::Srgb);
        // Texel centres of the four 8×8 blocks, away from the block edges.
        let pixels: Vec<[f32; 3]> = (0..4).map(|b| linear.get(b * 8 + 4, 4)).collect();
        assert_pixels(&pixels, &srgb[..4], JPEG, ext);
    }
}

#[test]
fn sixteen_bit_png_keeps_its_precision_and_greyscale_is_replicated() {
    let dir = scratch_dir("png16");
    let codes: [u16; 4] = [0, 257, 29_941, 65_535];
    let image: ImageBuffer<Luma<u16>, Vec<u16>> = ImageBuffer::from_fn(4, 1, |x, _| Luma([codes[x as usize]]));
    let path = dir.join("grey16.png");
    image.save(&path).unwrap();
    let file = io::read_texture_file(&path).unwrap();
    assert_eq!(file.stored, StoredValues::Integer { bits: 16 });
    let expected: Vec<[f64; 3]> = codes.iter().map(|&c| [srgb_to_linear(f64::from(c) / 65535.0); 3]).collect();
    assert_pixels(&file.linear(TextureEncoding::Srgb).pixels, &expected, 1e-6, "16-bit PNG");
    // 29941 lies halfway between two 8-bit codes: an 8-bit path would be off by more than 1e-3.
    let eight_bit = srgb_to_linear((29_941.0f64 / 257.0).round() / 255.0);
    assert!((eight_bit - expected[2][0]).abs() > 1e-3);
}

#[test]
fn float_formats_are_linear_whatever_the_encoding() {
    let dir = scratch_dir("float_formats");
    let values = [0.0f32, 0.25, 0.5, 4.0];
    let image: Rgb32FImage = ImageBuffer::from_fn(4, 1, |x, _| ImageRgb([values[x as usize]; 3]));
    let expected: Vec<[f64; 3]> = values.iter().map(|&v| [f64::from(v); 3]).collect();
    let tiff = dir.join("f.tif");
    image.save(&tiff).unwrap();
    let exr = dir.join("f.exr");
    io::write_image(
        &exr,
        &io::Image { width: 4, height: 1, pixels: values.iter().map(|&v| [v; 3]).collect() },
        &io::WriteOptions::default(),
    )
    .unwrap();
    for path in [tiff, exr] {
        let file = io::read_texture_file(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.stored, StoredValues::Float, "{}", path.display());
        for encoding in [TextureEncoding::Srgb, TextureEncoding::Linear, TextureEncoding::Gamma(2.2)] {
            assert_pixels(&file.linear(encoding).pixels, &expected, 0.0, &path.display().to_string());
        }
    }
}

#[test]
fn unknown_extensions_and_corrupt_files_are_errors() {
    let dir = scratch_dir("bad_files");
    let odd = dir.join("t.webp");
    fs::write(&odd, b"RIFF").unwrap();
    let e = io::read_texture_file(&odd).unwrap_err().to_string();
    assert!(e.contains("t.webp") && e.contains(".jpg"), "{e}");
    let mut bytes = Vec::new();
    rgb8().write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Jpeg).unwrap();
    let cut = dir.join("cut.jpg");
    fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let e = io::read_texture_file(&cut).unwrap_err().to_string();
    assert!(e.contains("cut.jpg"), "{e}");
}

/// The texture of the first shape's diffuse material.
fn diffuse_texture(s: &SceneDescription) -> Texture {
    match &s.materials[s.shapes[0].material as usize] {
        Material::Diffuse { reflectance } => reflectance.clone(),
        Material::TwoSided { front, .. } => match front.as_ref() {
            Material::Diffuse { reflectance } => reflectance.clone(),
            m => panic!("{m:?}"),
        },
        m => panic!("{m:?}"),
    }
}

/// The texture's value at the centre of texel (`x`, row 0 of the 4×2 image) in Mitsuba's uv
/// (v down the rows).
fn texel(t: &Texture, x: usize) -> f64 {
    f64::from(t.eval(Vec2::new((x as f32 + 0.5) / 4.0, 0.25)).r)
}

fn mitsuba_bitmap(dir: &Path, file: &str, raw: bool) -> Texture {
    let scene = format!(
        r#"<scene version="3.0.0"><shape type="sphere"><bsdf type="diffuse">
            <texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/>
            <boolean name="raw" value="{raw}"/></texture></bsdf></shape></scene>"#
    );
    let path = dir.join(format!("scene-{raw}.xml"));
    fs::write(&path, scene).unwrap();
    diffuse_texture(&io::mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}")))
}

#[test]
fn mitsuba_bitmap_decodes_srgb_unless_raw() {
    let dir = scratch_dir("mitsuba_bitmap");
    for ext in ["png", "tga", "bmp", "gif", "tif"] {
        rgb8().save(dir.join(format!("t.{ext}"))).unwrap();
        let decoded = mitsuba_bitmap(&dir, &format!("t.{ext}"), false);
        let raw = mitsuba_bitmap(&dir, &format!("t.{ext}"), true);
        for (i, &c) in CODES.iter().enumerate() {
            let v = f64::from(c) / 255.0;
            assert!((texel(&decoded, i) - srgb_to_linear(v)).abs() < 1e-6, "{ext} code {c}");
            assert!((texel(&raw, i) - v).abs() < 1e-6, "{ext} raw code {c}");
        }
    }
}

#[test]
fn pbrt_imagemap_encodings() {
    let dir = scratch_dir("pbrt_imagemap");
    rgb8().save(dir.join("t.png")).unwrap();
    let load = |encoding: &str| {
        let param = if encoding.is_empty() { String::new() } else { format!("\"string encoding\" \"{encoding}\"") };
        let text = format!(
            "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\n\
             Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"t.png\" {param}\n\
             Material \"diffuse\" \"texture reflectance\" \"t\"\nShape \"sphere\"\n"
        );
        let path = dir.join("scene.pbrt");
        fs::write(&path, text).unwrap();
        io::pbrt::load(&path).map(|s| diffuse_texture(&s))
    };
    // pbrt's (s, t) has t = 0 at the bottom row: row 0 of the file is at t = 1 − 1/4.
    let at = |t: &Texture, x: usize| f64::from(t.eval(Vec2::new((x as f32 + 0.5) / 4.0, 0.75)).r);
    type Decode = fn(f64) -> f64;
    let cases: [(&str, Decode); 4] =
        [("", srgb_to_linear), ("sRGB", srgb_to_linear), ("linear", |v| v), ("gamma 2.2", |v| v.powf(2.2))];
    for (encoding, decode) in cases {
        let t = load(encoding).unwrap_or_else(|e| panic!("{e}"));
        for (i, &c) in CODES.iter().enumerate() {
            let expected = decode(f64::from(c) / 255.0);
            assert!((at(&t, i) - expected).abs() < 1e-6, "encoding '{encoding}' code {c}: {} vs {expected}", at(&t, i));
        }
    }
    // The tolerance separates the encodings: code 128 under sRGB and under gamma 2.2 differ
    // by far more than 1e-6, so a wrong transfer function fails the check above.
    let v = 128.0 / 255.0;
    assert!((srgb_to_linear(v) - v.powf(2.2)).abs() > 1e-3);
    for bad in ["gamma", "gamma -1", "sRGB-ish"] {
        let e = load(bad).unwrap_err();
        assert!(e.message.contains("encoding") && e.line == Some(3), "{e}");
    }
}
