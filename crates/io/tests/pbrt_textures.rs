//! pbrt-v4's `scale` and `mix` textures: evaluated against pbrt's formulas (`tex · scale`,
//! `(1 − amount)·tex1 + amount·tex2`) at texel centres of a small linear image.

use std::fs;
use std::path::{Path, PathBuf};

use math::Vec2;
use scene::Texture;
use scene::desc::SceneDescription;
use scene::material::Material;
use spectrum::Rgb;

fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-pbrt-texture-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Loads `textures` followed by a diffuse sphere whose reflectance is the texture "out"; the
/// directory holds `ramp.png`, 2×1 pixels with codes (51, 102, 153) and (204, 255, 0),
/// referenced with "linear" encoding so the texels are the codes / 255.
fn load(test: &str, textures: &str) -> Result<SceneDescription, io::SceneError> {
    let dir = scratch_dir(test);
    image::RgbImage::from_fn(2, 1, |x, _| image::Rgb([[51, 102, 153], [204, 255, 0]][x as usize]))
        .save(dir.join("ramp.png"))
        .unwrap();
    let text = format!(
        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\n\
         Texture \"ramp\" \"spectrum\" \"imagemap\" \"string filename\" \"ramp.png\" \"string encoding\" \"linear\"\n\
         {textures}\nMaterial \"diffuse\" \"texture reflectance\" \"out\"\nShape \"sphere\"\n"
    );
    let path = dir.join("scene.pbrt");
    fs::write(&path, text).unwrap();
    io::pbrt::load(&path)
}

fn reflectance(s: &SceneDescription) -> Texture {
    match &s.materials[s.shapes[0].material as usize] {
        Material::TwoSided { front, .. } => match front.as_ref() {
            Material::Diffuse { reflectance } => reflectance.clone(),
            m => panic!("{m:?}"),
        },
        m => panic!("{m:?}"),
    }
}

/// The texel values of `ramp.png` (left, right).
fn ramp() -> [Rgb; 2] {
    [Rgb::new(0.2, 0.4, 0.6), Rgb::new(0.8, 1.0, 0.0)]
}

/// The texture at the centre of texel `x` (pbrt's t = 0.5 on a one-row image).
fn at(t: &Texture, x: usize) -> Rgb {
    t.eval(Vec2::new((x as f32 + 0.5) / 2.0, 0.5))
}

fn assert_rgb(a: Rgb, b: Rgb) {
    let tol = 1e-6;
    assert!((a.r - b.r).abs() < tol && (a.g - b.g).abs() < tol && (a.b - b.b).abs() < tol, "{a:?} vs {b:?}");
}

#[test]
fn scale_multiplies_a_texture_by_a_constant_or_a_texture() {
    let s =
        load("scale", "Texture \"out\" \"spectrum\" \"scale\" \"texture tex\" \"ramp\" \"float scale\" 0.5").unwrap();
    let t = reflectance(&s);
    for x in 0..2 {
        assert_rgb(at(&t, x), ramp()[x] * 0.5);
    }
    // A texture times itself.
    let s =
        load("scale_tex", "Texture \"out\" \"spectrum\" \"scale\" \"texture tex\" \"ramp\" \"texture scale\" \"ramp\"")
            .unwrap();
    let t = reflectance(&s);
    for x in 0..2 {
        assert_rgb(at(&t, x), ramp()[x] * ramp()[x]);
    }
    // Constants fold.
    let s = load("scale_const", "Texture \"out\" \"spectrum\" \"scale\" \"rgb tex\" [0.2 0.4 0.8] \"float scale\" 0.5")
        .unwrap();
    assert_eq!(reflectance(&s), Texture::Constant(Rgb::new(0.1, 0.2, 0.4)));
}

#[test]
fn mix_blends_with_a_constant_or_textured_amount() {
    let s = load(
        "mix",
        "Texture \"out\" \"spectrum\" \"mix\" \"rgb tex1\" [0.1 0.1 0.1] \"texture tex2\" \"ramp\" \"float amount\" 0.25",
    )
    .unwrap();
    let t = reflectance(&s);
    for x in 0..2 {
        assert_rgb(at(&t, x), Rgb::splat(0.1) * 0.75 + ramp()[x] * 0.25);
    }
    // The amount from a float image texture (its first channel): 0.2 left, 0.8 right.
    let s = load(
        "mix_amount",
        "Texture \"a\" \"float\" \"imagemap\" \"string filename\" \"ramp.png\" \"string encoding\" \"linear\"\n\
         Texture \"out\" \"spectrum\" \"mix\" \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1] \"texture amount\" \"a\"",
    )
    .unwrap();
    let t = reflectance(&s);
    assert_rgb(at(&t, 0), Rgb::new(0.8, 0.0, 0.2));
    assert_rgb(at(&t, 1), Rgb::new(0.2, 0.0, 0.8));
    // pbrt's defaults: tex1 = 0, tex2 = 1, amount = 0.5.
    let s = load("mix_default", "Texture \"out\" \"spectrum\" \"mix\"").unwrap();
    assert_eq!(reflectance(&s), Texture::Constant(Rgb::splat(0.5)));
    // A constant amount outside [0, 1] (which pbrt would extrapolate with) is an error.
    let e = load("mix_bad", "Texture \"out\" \"spectrum\" \"mix\" \"float amount\" 1.5").unwrap_err();
    assert!(e.message.contains("amount") && e.line == Some(4), "{e}");
}
