//! Mitsuba `principled` / `principledthin` end to end: every documented parameter loads as a
//! number or a texture (with `specular` mapped to `eta`), bad values are errors at the element,
//! rendered planes under a unit sky match closed forms with pt and vcm, and the repository's
//! scene `scenes/principled-spheres.xml` loads and renders with both algorithms to the same
//! image mean.

use std::path::{Path, PathBuf};

use io::SceneError;
use io::mitsuba::load;
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::desc::SceneDescription;
use scene::material::Material;
use scene::{Scene, Texture};
use testkit::{MeanVar, TempDir, sidak, z_test_p};

/// Loads `body` from a scene file in a fresh directory, removed before this returns (the error's
/// path is only compared).
fn load_body(body: &str) -> Result<SceneDescription, (SceneError, PathBuf)> {
    let dir = TempDir::new("principled");
    let path = dir.join("scene.xml");
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    load(&path, &[]).map_err(|e| (e, path))
}

fn load_ok(body: &str) -> SceneDescription {
    load_body(body).unwrap_or_else(|(e, _)| panic!("{e}"))
}

/// The material of a sphere with the BSDF `bsdf`.
fn load_material(bsdf: &str) -> Material {
    load_ok(&format!(r#"<shape type="sphere">{bsdf}</shape>"#)).materials.remove(0)
}

/// Asserts the error is at line 2 (where a one-line body starts) and mentions every needle.
fn load_error(body: &str, needles: &[&str]) {
    let (e, path) = match load_body(body) {
        Ok(_) => panic!("expected an error for\n{body}"),
        Err(x) => x,
    };
    let text = e.to_string();
    assert_eq!(e.file, path, "{text}");
    assert_eq!(e.line, Some(2), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

fn checker(name: &str, a: f32, b: f32) -> String {
    format!(
        r#"<texture name="{name}" type="checkerboard"><float name="color0" value="{a}"/><float name="color1" value="{b}"/></texture>"#
    )
}

#[test]
fn every_parameter_loads_as_a_number_or_a_texture() {
    let textured: String = ["roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen", "sheen_tint"]
        .iter()
        .chain(&["flatness", "clearcoat", "clearcoat_gloss"])
        .map(|n| checker(n, 0.2, 0.7))
        .collect();
    let m = load_material(&format!(
        r#"<bsdf type="principled">{}{textured}<float name="specular" value="0.7"/></bsdf>"#,
        checker("base_color", 0.1, 0.9)
    ));
    let Material::Principled(p) = &m else { panic!("{m:?}") };
    assert!(p.textures().iter().all(|t| matches!(t, Texture::Checkerboard { .. })));
    // Mitsuba reads scalar checkerboards with the colours swapped (`eval_1`), colours as given.
    let colours = |t: &Texture| match t {
        Texture::Checkerboard { color0, color1, .. } => (color0.g, color1.g),
        _ => panic!(),
    };
    assert_eq!(colours(&p.base_color), (0.1, 0.9));
    assert_eq!(colours(&p.metallic), (0.7, 0.2));
    // specular = 0.7 ↔ R0 = 0.08·0.7 = ((η − 1)/(η + 1))².
    let r0 = ((p.eta - 1.0) / (p.eta + 1.0)).powi(2);
    assert!((r0 - 0.056).abs() < 1e-6, "eta {} gives R0 {r0}", p.eta);

    let m = load_material(&format!(
        r#"<bsdf type="principledthin">{}{}{}<float name="eta" value="1.33"/><float name="roughness" value="0.2"/></bsdf>"#,
        checker("diff_trans", 0.4, 1.4),
        checker("spec_trans", 0.2, 0.8),
        checker("flatness", 0.0, 1.0)
    ));
    let Material::PrincipledThin(p) = &m else { panic!("{m:?}") };
    assert!(matches!(p.diff_trans, Texture::Checkerboard { .. }));
    assert_eq!(p.eta.as_constant().map(|c| c.g), Some(1.33));
    assert_eq!(p.roughness.as_constant().map(|c| c.g), Some(0.2));

    // Defaults: specular 0.5 is η = 1.5; a transmissive interface never has η = 1.
    let Material::Principled(p) = load_material(r#"<bsdf type="principled"/>"#) else { panic!() };
    assert!((p.eta - 1.5).abs() < 1e-6);
    let transmissive =
        r#"<bsdf type="principled"><float name="spec_trans" value="1"/><float name="eta" value="1"/></bsdf>"#;
    let Material::Principled(p) = load_material(transmissive) else { panic!() };
    assert_eq!(p.eta, 1.001);
}

#[test]
fn bad_parameters_are_errors_at_the_element() {
    load_error(
        r#"<bsdf type="principled"><float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf>"#,
        &["principled", "either 'eta' or 'specular'"],
    );
    load_error(r#"<bsdf type="principled"><float name="metallic" value="1.5"/></bsdf>"#, &["'metallic'", "[0, 1]"]);
    load_error(r#"<bsdf type="principled"><float name="eta" value="-2"/></bsdf>"#, &["'eta'", "positive"]);
    load_error(r#"<bsdf type="principled"><float name="specular" value="3"/></bsdf>"#, &["'specular'"]);
    load_error(
        r#"<bsdf type="principledthin"><float name="diff_trans" value="2.5"/></bsdf>"#,
        &["'diff_trans'", "[0, 2]"],
    );
    load_error(r#"<bsdf type="principledthin"><float name="eta" value="0"/></bsdf>"#, &["'eta'"]);
}

/// A camera 5 units above a 20 × 20 plane with the BSDF `bsdf` under a unit sky (which also
/// lights the plane from below), paths of at most two segments.
fn plane_scene(bsdf: &str) -> String {
    format!(
        r#"<sensor type="perspective">
            <float name="fov" value="30"/>
            <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
        </sensor>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
        <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>{bsdf}</shape>"#
    )
}

/// Per-iteration means of the green channel of `algorithm`'s frames of `description`.
fn render(description: &SceneDescription, algorithm: &str, iterations: u64, max_length: u32) -> MeanVar {
    let (scene, _) = Scene::from_description(description, None).unwrap();
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        max_length,
        seed: 9,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(&scene, &settings).unwrap();
    let mut stats = MeanVar::new();
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "no rejected samples");
        let pixels = &renderer.frame().pixels;
        let sum: f64 = pixels.iter().map(|p| f64::from(p.to_array()[1])).sum();
        assert!(sum.is_finite());
        stats.push(sum / pixels.len() as f64);
    }
    stats
}

/// Under a unit sky, a thin sheet with `diff_trans = 2` (Lambertian transmission only) shows
/// its base colour 0.6; a `principled` plane with η = 1 (no specular), roughness 0 and no
/// flatness shows the smooth Disney diffuse's albedo `0.6·(1 − 1/42)` (`2∫(1 − μ)⁵ μ dμ =
/// 1/21`; the camera's view angles ≤ 15° make `(1 − cos θ_i)⁵ < 1e-7`). Each value is checked
/// with pt and vcm (z-test over the per-iteration means), and the diffuse case must reject the
/// plain base colour (a 2.4 % error).
#[test]
fn planes_under_a_unit_sky_show_the_closed_forms() {
    let cases = [
        (
            r#"<bsdf type="principledthin"><rgb name="base_color" value="0.6"/><float name="diff_trans" value="2"/></bsdf>"#,
            0.6,
        ),
        (
            r#"<bsdf type="principled"><rgb name="base_color" value="0.6"/><float name="roughness" value="0"/><float name="eta" value="1"/></bsdf>"#,
            0.6 * (1.0 - 1.0 / 42.0),
        ),
    ];
    let alpha = sidak(1e-4, 2 * cases.len());
    for (i, (bsdf, truth)) in cases.iter().enumerate() {
        let description = load_ok(&plane_scene(bsdf));
        for algorithm in ["pt", "vcm"] {
            // 1024 iterations: the 2.4 % error is then about 11 standard errors, so the power
            // check below fails for no seed in practice (at 256 it was 5.5, against a critical
            // value of 4.2: about one seed in ten missed it).
            let stats = render(&description, algorithm, 1024, 2);
            let (mean, se) = (stats.mean(), stats.std_error());
            let p = z_test_p(mean - truth, se);
            assert!(p >= alpha, "case {i} {algorithm}: {mean} ± {se} vs {truth} (p = {p})");
            if i == 1 {
                let wrong = z_test_p(mean - 0.6, se);
                assert!(wrong < alpha, "case {i} {algorithm}: {mean} ± {se} does not reject 0.6 (p = {wrong})");
            }
        }
    }
}

/// `scenes/principled-spheres.xml` loads and renders with pt and vcm to the
/// same image mean (z-test over 24 iterations each: two independent implementations).
#[test]
fn the_repository_scene_renders_the_same_mean_with_pt_and_vcm() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/principled-spheres.xml");
    let description = load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let count = |f: fn(&Material) -> bool| description.materials.iter().filter(|m| f(m)).count();
    assert_eq!(count(|m| matches!(m, Material::Principled(_))), 2);
    assert_eq!(count(|m| matches!(m, Material::PrincipledThin(_))), 1);
    let pt = render(&description, "pt", 24, 6);
    let vcm = render(&description, "vcm", 24, 6);
    let d = pt.mean() - vcm.mean();
    let se = (pt.variance() / 24.0 + vcm.variance() / 24.0).sqrt();
    assert!(pt.mean() > 0.01, "a visible image: {}", pt.mean());
    assert!(z_test_p(d, se) >= 1e-4, "pt {} vs vcm {} (se {se})", pt.mean(), vcm.mean());
}
