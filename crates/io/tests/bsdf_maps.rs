//! Mitsuba `normalmap` and `bumpmap` end to end: loading (and its errors), and rendered images
//! of a Lambertian plane under a constant sky against closed forms. A plane whose shading
//! normal is tilted by `a` reflects `ρ L (1 + cos a)/2` (the part of the tilted cosine lobe
//! above the geometric tangent plane), so the path tracer's image mean must match that value;
//! an identity normal map must render the plain material's image.

use std::path::{Path, PathBuf};

use io::mitsuba::load;
use io::{Image, SceneError, WriteOptions, write_image};
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::Scene;
use scene::desc::SceneDescription;
use scene::material::Material;
use testkit::{MeanVar, TempDir, sidak, z_test_p};

fn load_in(dir: &Path, body: &str) -> Result<SceneDescription, (SceneError, PathBuf)> {
    let path = dir.join("scene.xml");
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    load(&path, &[]).map_err(|e| (e, path))
}

fn load_ok(body: &str) -> SceneDescription {
    load_in(&TempDir::new("bsdf-maps"), body).unwrap_or_else(|(e, _)| panic!("{e}"))
}

/// Asserts the error is at `line` (the body starts on line 2) and mentions every needle.
fn load_error(body: &str, line: u32, needles: &[&str]) {
    let dir = TempDir::new("bsdf-maps");
    let (e, path) = match load_in(&dir, body) {
        Ok(_) => panic!("expected an error for\n{body}"),
        Err(x) => x,
    };
    let text = e.to_string();
    assert_eq!(e.file, path, "{text}");
    assert_eq!(e.line, Some(line), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

const RHO: f64 = 0.5;

/// A camera 5 units above a 20 × 20 Lambertian plane (reflectance [`RHO`]) under a unit
/// constant sky; `bsdf` wraps the diffuse BSDF (`{}` is replaced by it).
fn plane_scene(wrapper: &str) -> String {
    plane_scene_scaled(wrapper, 10.0)
}

/// [`plane_scene`] with the plane `2 · half_width` wide (the camera sees its central 2.68 units).
fn plane_scene_scaled(wrapper: &str, half_width: f64) -> String {
    let diffuse = format!(r#"<bsdf type="diffuse"><rgb name="reflectance" value="{RHO}"/></bsdf>"#);
    let bsdf = if wrapper.is_empty() { diffuse } else { wrapper.replace("{}", &diffuse) };
    format!(
        r#"<integrator type="path"><integer name="max_depth" value="2"/></integrator>
        <sensor type="perspective">
            <float name="fov" value="30"/>
            <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
        </sensor>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
        <shape type="rectangle">
            <transform name="to_world"><scale value="{half_width}"/></transform>
            {bsdf}
        </shape>"#
    )
}

/// Path-traced frames of `description`: per-iteration image means and the final frame.
fn render(description: &SceneDescription, iterations: u64) -> (MeanVar, Vec<f32>) {
    render_with(description, iterations, "pt")
}

/// [`render`] with the algorithm `algorithm`.
fn render_with(description: &SceneDescription, iterations: u64, algorithm: &str) -> (MeanVar, Vec<f32>) {
    let (scene, _) = Scene::from_description(description, None).unwrap();
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        max_length: 2,
        seed: 5,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(&scene, &settings).unwrap();
    let mut stats = MeanVar::new();
    let mut last = Vec::new();
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "no rejected samples");
        let pixels = &renderer.frame().pixels;
        last = pixels.iter().map(|p| p.to_array()[1]).collect();
        stats.push(last.iter().map(|&v| f64::from(v)).sum::<f64>() / last.len() as f64);
    }
    (stats, last)
}

/// The expected image value of the plane with its shading normal tilted by `a` radians
/// (pbrt's maps, and Mitsuba's without `use_shadowing_function`).
fn sky_view(a: f64) -> f64 {
    RHO * (1.0 + a.cos()) / 2.0
}

/// The expected image value of the plane with its shading normal tilted by `a` radians under
/// Mitsuba's shadowing function (the default).
fn shadowed(a: f64) -> f64 {
    testkit::mitsuba_maps::tilted_diffuse_albedo(RHO, a, true)
}

/// A raw-constant normal map tilting by `a` radians about the surface's v direction.
fn tilted_normal_map(a: f64) -> String {
    tilted_normal_map_with(a, "")
}

/// [`tilted_normal_map`] with extra properties `extra` (XML).
fn tilted_normal_map_with(a: f64, extra: &str) -> String {
    format!(
        r#"<bsdf type="normalmap">
            <texture name="normalmap" type="rawconstant"><vector name="value" value="{}, 0.5, {}"/></texture>
            {extra}
            {{}}
        </bsdf>"#,
        0.5 + 0.5 * a.sin(),
        0.5 + 0.5 * a.cos()
    )
}

#[test]
fn maps_load_and_their_errors_name_the_element() {
    let d = load_ok(&plane_scene(&tilted_normal_map(0.3)));
    assert!(
        matches!(&d.materials[0], Material::NormalMap { nested, .. } if matches!(**nested, Material::Diffuse { .. })),
        "{:?}",
        d.materials[0]
    );
    load_error(r#"<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>"#, 2, &["normalmap", "missing the texture"]);
    load_error(
        r#"<bsdf type="bumpmap"><texture name="h" type="rawconstant"><float name="value" value="0"/></texture></bsdf>"#,
        2,
        &["bumpmap", "exactly one nested BSDF"],
    );
    load_error(r#"<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>"#, 2, &["missing the height texture"]);
    load_error(
        r#"<bsdf type="blendbsdf">
            <float name="weight" value="0.5"/>
            <bsdf type="diffuse"/>
            <bsdf type="normalmap">
                <texture name="normalmap" type="rawconstant"><vector name="value" value="0.5, 0.5, 1"/></texture>
                <bsdf type="diffuse"/>
            </bsdf>
        </bsdf>"#,
        2,
        &["blendbsdf", "outermost"],
    );
}

#[test]
fn identity_normal_map_renders_the_plain_image() {
    let iterations = 16;
    let (plain_stats, plain) = render(&load_ok(&plane_scene("")), iterations);
    let (_, identity) = render(&load_ok(&plane_scene(&tilted_normal_map(0.0))), iterations);
    let (_, tilted) = render(&load_ok(&plane_scene(&tilted_normal_map(0.4))), iterations);
    // Same random numbers, shading normals equal up to rounding: the same image.
    let largest = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    let scale = plain.iter().fold(0.0f32, |m, &v| m.max(v.abs()));
    assert!(largest(&plain, &identity) <= 1e-5 * scale, "identity map: {}", largest(&plain, &identity));
    // The comparison resolves a real perturbation.
    assert!(largest(&plain, &tilted) > 1e-2 * scale, "a tilted map changes the image");
    // And the plain image is the unperturbed plane's ρ L.
    let z = (plain_stats.mean() - RHO) / plain_stats.std_error();
    assert!(z.abs() < 4.5, "plain plane: {} vs {RHO} (z = {z})", plain_stats.mean());
}

/// Normal maps tilting by 0.5 and 1.0 rad, and a bump map whose height ramp tilts by 45°, each
/// against `ρ/π ∫ max(0, l·n) G(l) dω` with Mitsuba's shadowing `G` (the default), and a
/// normal map without it against `ρ (1 + cos a)/2`; each also rejects the untilted value, and
/// the shadowed ones the unshadowed value.
#[test]
fn tilted_planes_reflect_the_sky_view_factor() {
    let dir = TempDir::new("bsdf-maps");
    // A 64 × 1 ramp h(u) = u (texel centres), clamped: over the rectangle (u across 20 units)
    // a bump scale of 20 gives ∂h/∂u · scale / |∂p/∂u| = 1, a 45° tilt; the camera sees
    // u ∈ [0.43, 0.57], far from the clamped edges.
    let width = 64;
    let pixels = (0..width).map(|i| [(i as f32 + 0.5) / width as f32; 3]).collect();
    write_image(&dir.join("ramp.pfm"), &Image { width, height: 1, pixels }, &WriteOptions::default()).unwrap();
    let bump = r#"<bsdf type="bumpmap">
            <float name="scale" value="20"/>
            <texture name="height" type="bitmap">
                <string name="filename" value="ramp.pfm"/>
                <string name="wrap_mode" value="clamp"/>
                <boolean name="raw" value="true"/>
            </texture>
            {}
        </bsdf>"#;
    let unshadowed = r#"<boolean name="use_shadowing_function" value="false"/>"#;
    let cases = [
        ("normal map 0.5 rad", tilted_normal_map(0.5), shadowed(0.5)),
        ("normal map 1.0 rad", tilted_normal_map(1.0), shadowed(1.0)),
        ("bump map 45°", bump.to_string(), shadowed(std::f64::consts::FRAC_PI_4)),
        ("unshadowed normal map 1.0 rad", tilted_normal_map_with(1.0, unshadowed), sky_view(1.0)),
    ];
    let alpha = sidak(1e-4, cases.len());
    for (name, wrapper, expected) in cases {
        let description = load_in(&dir, &plane_scene(&wrapper)).unwrap_or_else(|(e, _)| panic!("{e}"));
        let (stats, _) = render(&description, 64);
        let (mean, se) = (stats.mean(), stats.std_error());
        let p = z_test_p(mean - expected, se);
        assert!(p > alpha, "{name}: {mean} ± {se} vs {expected} (p = {p:.2e})");
        let p_flat = z_test_p(mean - RHO, se);
        assert!(p_flat < 1e-6, "{name}: not distinguishable from the untilted plane (p = {p_flat:.2e})");
    }
    // The shadowing is resolved: the 1.0 rad map is not the unshadowed value.
    let description = load_in(&dir, &plane_scene(&tilted_normal_map(1.0))).unwrap_or_else(|(e, _)| panic!("{e}"));
    let (stats, _) = render(&description, 64);
    let p = z_test_p(stats.mean() - sky_view(1.0), stats.std_error());
    assert!(p < 1e-6, "the shadowing is not resolved: {} vs {} (p = {p:.2e})", stats.mean(), sky_view(1.0));
}

/// pbrt-v4's `normalmap` (an image, read linear) and `displacement` (a float texture) on a
/// 20 × 20 quad with uv over [0, 1]² under a unit constant sky, against `ρ (1 + cos a)/2`.
#[test]
fn pbrt_normal_map_and_displacement_tilt_the_plane() {
    let dir = TempDir::new("bsdf-maps");
    // One texel encoding the normal tilted by 0.8 rad about v.
    let a = 0.8f32;
    let texel = [0.5 + 0.5 * a.sin(), 0.5, 0.5 + 0.5 * a.cos()];
    write_image(&dir.join("normal.pfm"), &Image { width: 1, height: 1, pixels: vec![texel] }, &WriteOptions::default())
        .unwrap();
    // h(u) = 20 u: over 20 units of surface per unit of u, a 45° tilt.
    let width = 64;
    let pixels = (0..width).map(|i| [(i as f32 + 0.5) / width as f32; 3]).collect();
    write_image(&dir.join("ramp.pfm"), &Image { width, height: 1, pixels }, &WriteOptions::default()).unwrap();
    let scene = |material: &str| {
        format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Texture "h" "float" "imagemap" "string filename" "ramp.pfm" "float scale" 20 "string wrap" "clamp"
{material}
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "point2 uv" [0 0  1 0  1 1  0 1]
"#
        )
    };
    let cases = [
        ("plain", r#"Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]"#, 0.0),
        ("normal map", r#"Material "diffuse" "rgb reflectance" [0.5 0.5 0.5] "string normalmap" "normal.pfm""#, 0.8),
        (
            "displacement",
            r#"Material "diffuse" "rgb reflectance" [0.5 0.5 0.5] "texture displacement" "h""#,
            std::f64::consts::FRAC_PI_4,
        ),
    ];
    let alpha = sidak(1e-4, cases.len());
    for (name, material, a) in cases {
        let path = dir.join(format!("{}.pbrt", name.replace(' ', "_")));
        std::fs::write(&path, scene(material)).unwrap();
        let description = io::pbrt::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(description.warnings.is_empty(), "{name}: {:?}", description.warnings);
        let (stats, _) = render(&description, 64);
        let (mean, se) = (stats.mean(), stats.std_error());
        let p = z_test_p(mean - sky_view(a), se);
        assert!(p > alpha, "{name}: {mean} ± {se} vs {} (p = {p:.2e})", sky_view(a));
        if a > 0.0 {
            let p_flat = z_test_p(mean - RHO, se);
            assert!(p_flat < 1e-6, "{name}: not distinguishable from the untilted plane (p = {p_flat:.2e})");
        }
    }
    // Both at once is an error naming the parameter.
    let path = dir.join("both.pbrt");
    let both = r#"Material "diffuse" "string normalmap" "normal.pfm" "texture displacement" "h""#;
    std::fs::write(&path, scene(both)).unwrap();
    let Err(e) = io::pbrt::load(&path) else { panic!("both maps: expected an error") };
    assert!(e.to_string().contains("not both"), "{e}");
}

/// Textured `alpha_u`/`alpha_v` (Mitsuba) and `roughness` (pbrt, remapped by default) load as
/// [`Material::TexturedRoughness`] around the rough model.
#[test]
fn textured_roughness_loads() {
    let checks = r#"<float name="color0" value="0.05"/><float name="color1" value="0.3"/>"#;
    let d = load_ok(&format!(
        r#"<shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
            <texture name="alpha_u" type="checkerboard">{checks}</texture>
            <float name="alpha_v" value="0.2"/>
        </bsdf></shape>
        <shape type="sphere"><bsdf type="roughplastic"><string name="distribution" value="ggx"/>
            <texture name="alpha" type="checkerboard">{checks}</texture>
        </bsdf></shape>"#
    ));
    match &d.materials[0] {
        Material::TexturedRoughness { alpha_u, alpha_v, remap: false, nested } => {
            // Mitsuba's float evaluation of a checkerboard has the opposite parity of its colour
            // evaluation: color0 where the parities of u and v differ, so the colours swap.
            let scene::Texture::Checkerboard { color0, color1, .. } = alpha_u else { panic!("{alpha_u:?}") };
            assert_eq!((color0.r, color1.r), (0.3, 0.05));
            assert_eq!(alpha_v.as_constant().map(|c| c.r), Some(0.2));
            assert!(matches!(**nested, Material::RoughConductor { .. }), "{nested:?}");
        }
        m => panic!("{m:?}"),
    }
    assert!(
        matches!(&d.materials[1], Material::TexturedRoughness { nested, .. } if matches!(**nested, Material::RoughPlastic { .. })),
        "{:?}",
        d.materials[1]
    );
    load_error(
        &format!(
            r#"<bsdf type="roughconductor"><texture name="alpha_u" type="checkerboard">{checks}</texture></bsdf>"#
        ),
        2,
        &["both 'alpha_u' and 'alpha_v'"],
    );

    let dir = TempDir::new("bsdf-maps");
    let path = dir.join("rough.pbrt");
    std::fs::write(
        &path,
        r#"Film "rgb" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
Texture "r" "float" "checkerboard" "float tex1" 0.01 "float tex2" 0.09
Material "dielectric" "texture roughness" "r"
Shape "sphere"
"#,
    )
    .unwrap();
    let d = io::pbrt::load(&path).unwrap_or_else(|e| panic!("{e}"));
    match &d.materials[d.shapes[0].material as usize] {
        Material::TexturedRoughness { remap: true, nested, .. } => {
            assert!(matches!(**nested, Material::RoughDielectric { .. }), "{nested:?}");
        }
        m => panic!("{m:?}"),
    }
}

/// Light sub-paths see the perturbed normal too (it is the hit's shading normal, stored in the
/// light vertices, with the adjoint shading-normal factor and Mitsuba's shadowing on the light
/// side): light tracing, BPT and VCM render the normal-mapped plane's value as the path tracer
/// does.
#[test]
fn light_paths_see_the_normal_map() {
    let a = 0.9;
    // A plane just larger than the view, so that most light sub-paths land where the camera
    // looks.
    let description = load_ok(&plane_scene_scaled(&tilted_normal_map(a), 1.5));
    let algorithms = ["lt", "bpt", "vcm"];
    let alpha = sidak(1e-4, algorithms.len());
    for algorithm in algorithms {
        let (stats, _) = render_with(&description, 64, algorithm);
        let (mean, se) = (stats.mean(), stats.std_error());
        let p = z_test_p(mean - shadowed(a), se);
        assert!(p > alpha, "{algorithm}: {mean} ± {se} vs {} (p = {p:.2e})", shadowed(a));
        let p_flat = z_test_p(mean - RHO, se);
        assert!(p_flat < 1e-6, "{algorithm}: {mean} ± {se}, not distinguishable from the untilted plane");
    }
}
