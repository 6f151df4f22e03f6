//! Alpha masks in the loaders: Mitsuba's `mask` BSDF (float or texture opacity; outermost, inside
//! a `twosided`, referenced by id, in a `shapegroup`) and pbrt-v4's shape `alpha` (float or
//! texture) become the shapes' opacity textures, and bad values or placements are errors at
//! the right line.

use std::fs;
use std::path::{Path, PathBuf};

use math::Vec2;
use scene::Texture;
use scene::desc::SceneDescription;
use scene::material::Material;
use spectrum::Rgb;

fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-alpha-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    // A 2 × 1 mask: black on the left, white on the right.
    image::GrayImage::from_fn(2, 1, |x, _| image::Luma([if x == 0 { 0 } else { 255 }]))
        .save(dir.join("mask.png"))
        .unwrap();
    dir
}

fn mitsuba(test: &str, body: &str) -> Result<SceneDescription, io::SceneError> {
    let dir = scratch_dir(test);
    let path = dir.join("scene.xml");
    fs::write(&path, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    io::mitsuba::load(&path, &[])
}

fn pbrt(test: &str, body: &str) -> Result<SceneDescription, io::SceneError> {
    let dir = scratch_dir(test);
    let path = dir.join("scene.pbrt");
    fs::write(&path, format!("Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\n{body}\n"))
        .unwrap();
    io::pbrt::load(&path)
}

/// Asserts an error at `line` that mentions every needle.
fn error_at(result: Result<SceneDescription, io::SceneError>, line: u32, needles: &[&str]) {
    let e = match result {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    };
    let text = e.to_string();
    assert_eq!(e.line, Some(line), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

fn constant(t: &Texture) -> f32 {
    t.as_constant().expect("a constant opacity").r
}

const DIFFUSE: &str = r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf>"#;
const BITMAP: &str = r#"<texture name="opacity" type="bitmap"><string name="filename" value="mask.png"/>
    <string name="filter_type" value="nearest"/></texture>"#;

fn diffuse_reflectance(m: &Material) -> f32 {
    match m {
        Material::Diffuse { reflectance } => reflectance.as_constant().unwrap().r,
        other => panic!("expected a diffuse material, got {other:?}"),
    }
}

#[test]
fn mitsuba_masks_with_texture_and_float_opacity() {
    let body = format!(
        r#"<shape type="rectangle"><bsdf type="mask">{BITMAP}{DIFFUSE}</bsdf></shape>
<shape type="rectangle"><bsdf type="mask"><float name="opacity" value="0.25"/>{DIFFUSE}</bsdf></shape>
<shape type="rectangle">{DIFFUSE}</shape>"#
    );
    let desc = mitsuba("mitsuba_basic", &body).unwrap_or_else(|e| panic!("{e}"));
    let [textured, float, plain] = &desc.shapes[..] else { panic!("three shapes") };
    let texture = textured.alpha.as_ref().expect("the bitmap opacity");
    assert_eq!(texture.eval(Vec2::new(0.25, 0.5)), Rgb::BLACK);
    assert_eq!(texture.eval(Vec2::new(0.75, 0.5)), Rgb::WHITE);
    assert_eq!(constant(float.alpha.as_ref().unwrap()), 0.25);
    assert!(plain.alpha.is_none());
    // The material is the nested BSDF.
    for shape in [textured, float, plain] {
        assert_eq!(diffuse_reflectance(&desc.materials[shape.material as usize]), 0.3);
    }
}

#[test]
fn mitsuba_masks_inside_and_around_twosided_by_reference_and_in_shapegroups() {
    let body = format!(
        r#"<bsdf type="mask" id="leaf"><float name="opacity" value="0.5"/>{DIFFUSE}</bsdf>
<shape type="rectangle"><bsdf type="twosided"><bsdf type="mask">{BITMAP}{DIFFUSE}</bsdf></bsdf></shape>
<shape type="rectangle"><bsdf type="mask">{BITMAP}<bsdf type="twosided">{DIFFUSE}</bsdf></bsdf></shape>
<shape type="rectangle"><ref id="leaf"/></shape>
<shape type="rectangle"><bsdf type="twosided"><ref id="leaf"/></bsdf></shape>
<shape type="shapegroup" id="group"><shape type="rectangle"><ref id="leaf"/></shape></shape>
<shape type="instance"><ref id="group"/></shape>"#
    );
    let desc = mitsuba("mitsuba_nesting", &body).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(desc.shapes.len(), 4);
    for (i, shape) in desc.shapes.iter().enumerate() {
        let alpha = shape.alpha.as_ref().unwrap_or_else(|| panic!("shape {i} has no mask"));
        let material = &desc.materials[shape.material as usize];
        match (i, material) {
            (2, m) => assert_eq!(diffuse_reflectance(m), 0.3),
            (_, Material::TwoSided { front, back: None }) => assert_eq!(diffuse_reflectance(front), 0.3),
            (_, other) => panic!("shape {i}: {other:?}"),
        }
        if i >= 2 {
            assert_eq!(constant(alpha), 0.5, "shape {i}");
        } else {
            assert_eq!(alpha.eval(Vec2::new(0.25, 0.5)), Rgb::BLACK, "shape {i}");
            assert_eq!(alpha.eval(Vec2::new(0.75, 0.5)), Rgb::WHITE, "shape {i}");
        }
    }
    let object = &desc.objects[0].shapes[0];
    assert_eq!(constant(object.alpha.as_ref().expect("the instanced shape's mask")), 0.5);
}

#[test]
fn mitsuba_mask_errors_name_the_line() {
    error_at(
        mitsuba(
            "bad_value",
            &format!(
                r#"<shape type="rectangle"><bsdf type="mask">
<float name="opacity" value="1.5"/>{DIFFUSE}</bsdf></shape>"#
            ),
        ),
        3,
        &["opacity", "[0, 1]"],
    );
    error_at(
        mitsuba(
            "no_nested",
            r#"<shape type="rectangle"><bsdf type="mask"><float name="opacity" value="0.5"/></bsdf></shape>"#,
        ),
        2,
        &["mask", "exactly one nested BSDF"],
    );
    error_at(
        mitsuba(
            "in_blend",
            &format!(
                r#"<shape type="rectangle"><bsdf type="blendbsdf"><float name="weight" value="0.5"/>
{DIFFUSE}<bsdf type="mask">{DIFFUSE}</bsdf></bsdf></shape>"#
            ),
        ),
        2,
        &["blendbsdf", "outermost"],
    );
    error_at(
        mitsuba(
            "in_mask",
            &format!(r#"<shape type="rectangle"><bsdf type="mask"><bsdf type="mask">{DIFFUSE}</bsdf></bsdf></shape>"#),
        ),
        2,
        &["another mask"],
    );
    error_at(
        mitsuba(
            "texture_file",
            r#"<shape type="rectangle"><bsdf type="mask">
<texture name="opacity" type="bitmap"><string name="filename" value="missing.png"/></texture><bsdf type="diffuse"/></bsdf></shape>"#,
        ),
        3,
        &["missing.png"],
    );
}

#[test]
fn pbrt_float_and_texture_alpha() {
    let body = "Texture \"cut\" \"float\" \"imagemap\" \"string filename\" \"mask.png\" \"string encoding\" \"linear\"\n\
        Shape \"sphere\" \"float alpha\" 0.5\n\
        Shape \"sphere\" \"float alpha\" 1\n\
        Shape \"sphere\" \"texture alpha\" \"cut\"\n\
        Shape \"sphere\" \"float alpha\" 0";
    let desc = pbrt("pbrt_alpha", body).unwrap_or_else(|e| panic!("{e}"));
    let alphas: Vec<Option<&Texture>> = desc.shapes.iter().map(|s| s.alpha.as_ref()).collect();
    assert_eq!(constant(alphas[0].unwrap()), 0.5);
    assert!(alphas[1].is_none(), "alpha 1 is no mask");
    let texture = alphas[2].unwrap();
    assert!(texture.eval(Vec2::new(0.25, 0.5)).r < 0.01 && texture.eval(Vec2::new(0.75, 0.5)).r > 0.99);
    assert_eq!(constant(alphas[3].unwrap()), 0.0);
    assert!(desc.warnings.iter().all(|w| !w.contains("alpha")), "{:?}", desc.warnings);
}

#[test]
fn pbrt_alpha_errors_name_the_line() {
    error_at(pbrt("too_big", "Shape \"sphere\" \"float alpha\" 2"), 3, &["alpha", "[0, 1]"]);
    error_at(pbrt("negative", "\nShape \"sphere\" \"float alpha\" -0.5"), 4, &["alpha", "[0, 1]"]);
    error_at(pbrt("unknown", "Shape \"sphere\" \"texture alpha\" \"nope\""), 3, &["nope"]);
    error_at(pbrt("wrong_type", "Shape \"sphere\" \"rgb alpha\" [0.5 0.5 0.5]"), 3, &["alpha", "float or texture"]);
    error_at(pbrt("two_values", "Shape \"sphere\" \"float alpha\" [0.5 0.5]"), 3, &["alpha", "one value"]);
}

#[test]
fn masked_area_emitters_load_from_both_formats_and_emit_their_opaque_fraction() {
    // pbrt-v4: a diffuse area light on a 2 × 2 quad of alpha 0.25; Mitsuba 3: an area emitter
    // on a rectangle (also 2 × 2) inside a mask of opacity 0.25. Both emit a quarter of the
    // unmasked flux π · L · A = π · 2 · 4 (the tabulated selection power of a constant mask is
    // exact).
    let pbrt_desc = pbrt(
        "pbrt_masked_emitter",
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n\
         Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] \"integer indices\" [0 1 2 0 2 3] \
         \"float alpha\" 0.25\nAttributeEnd\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mitsuba_desc = mitsuba(
        "mitsuba_masked_emitter",
        &format!(
            r#"<shape type="rectangle"><bsdf type="mask"><float name="opacity" value="0.25"/>{DIFFUSE}</bsdf>
<emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>"#
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for (what, desc) in [("pbrt", pbrt_desc), ("mitsuba", mitsuba_desc)] {
        let scene = scene::Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{what}: {e}")).0;
        let sphere = scene.bounding_sphere;
        let power: f32 = scene.lights.iter().map(|l| l.power(&sphere)).sum();
        let expected = 0.25 * std::f32::consts::PI * 2.0 * 4.0;
        assert!((power - expected).abs() < 1e-4 * expected, "{what}: power {power}, expected {expected}");
        assert!(scene.lights.iter().all(|l| matches!(l, scene::Light::TexturedTriangle(_))), "{what}");
    }
}
