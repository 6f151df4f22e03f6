//! Hair end to end: pbrt-v4's `hair` material (every parameter and the absorption priority
//! sigma_a > reflectance/color > melanin) and `curve` shape (bases, degrees, types, widths,
//! errors at file:line), Mitsuba 3's `<bsdf type="hair">`, and the repository scene
//! `scenes/hair.xml`, which renders with pt and bpt to the same image mean (and with vcm).

use std::fs;
use std::path::{Path, PathBuf};

use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::Scene;
use scene::desc::{Geometry, MeshData, SceneDescription};
use scene::material::{EUMELANIN_SIGMA_A, HairParameters, Material, PHEOMELANIN_SIGMA_A};
use spectrum::Rgb;
use testkit::{MeanVar, z_test_p};

fn scratch(test: &str, name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-hair-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path
}

const HEADER: &str = "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nWorldBegin\n";

fn pbrt(test: &str, body: &str) -> Result<SceneDescription, io::SceneError> {
    io::pbrt::load(&scratch(test, "scene.pbrt", &format!("{HEADER}{body}")))
}

fn pbrt_hair(test: &str, params: &str) -> HairParameters {
    let body = format!(
        "Material \"hair\" {params}\nShape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width\" 0.1\n"
    );
    let d = pbrt(test, &body).unwrap_or_else(|e| panic!("{e}"));
    let hair = d.materials.iter().find_map(|m| match m {
        Material::Hair(h) => Some(*h),
        _ => None,
    });
    hair.expect("a hair material")
}

fn close(a: Rgb, b: Rgb) -> bool {
    (a - b).to_array().iter().all(|d| d.abs() < 1e-5)
}

#[test]
fn pbrt_hair_parameters_load() {
    let default = pbrt_hair("default", "");
    assert_eq!(default, HairParameters::default());
    assert!(close(default.sigma_a, EUMELANIN_SIGMA_A * 1.3));
    let h = pbrt_hair(
        "all",
        "\"float eta\" 1.4 \"float beta_m\" 0.2 \"float beta_n\" 0.5 \"float alpha\" 3 \"rgb sigma_a\" [0.1 0.2 0.3] \"float eumelanin\" 4",
    );
    assert_eq!((h.eta, h.beta_m, h.beta_n, h.alpha), (1.4, 0.2, 0.5, 3.0));
    assert!(close(h.sigma_a, Rgb::new(0.1, 0.2, 0.3)), "sigma_a wins: {:?}", h.sigma_a);
    let c = pbrt_hair("color", "\"rgb reflectance\" [0.5 0.4 0.3] \"float beta_n\" 0.4");
    assert!(close(c.sigma_a, HairParameters::sigma_a_from_color(Rgb::new(0.5, 0.4, 0.3), 0.4)));
    let c3 = pbrt_hair("color3", "\"rgb color\" [0.5 0.4 0.3]");
    assert!(close(c3.sigma_a, HairParameters::sigma_a_from_color(Rgb::new(0.5, 0.4, 0.3), 0.3)));
    // Only pheomelanin: eumelanin is then 0, not pbrt's 1.3 default.
    let p = pbrt_hair("pheo", "\"float pheomelanin\" 2");
    assert!(close(p.sigma_a, PHEOMELANIN_SIGMA_A * 2.0));
    let e = pbrt_hair("eu", "\"float eumelanin\" 0.5 \"float pheomelanin\" 0.25");
    assert!(close(e.sigma_a, EUMELANIN_SIGMA_A * 0.5 + PHEOMELANIN_SIGMA_A * 0.25));
}

#[test]
fn pbrt_hair_errors_name_the_line() {
    let body = "Material \"hair\"\n  \"float beta_m\" 1.5\nShape \"sphere\"\n";
    let e = pbrt("bad_beta", body).unwrap_err();
    assert_eq!(e.line, Some(3 - 1 + 1), "{e}");
    assert!(e.to_string().contains("beta_m"), "{e}");
    let e =
        pbrt("textured", "Texture \"t\" \"spectrum\" \"checkerboard\"\nMaterial \"hair\" \"texture sigma_a\" \"t\"\n")
            .unwrap_err();
    assert!(e.to_string().contains("textured 'sigma_a'") && e.line == Some(4), "{e}");
}

fn only_mesh(d: &SceneDescription) -> &MeshData {
    match &d.shapes[0].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("not a mesh: {g:?}"),
    }
}

/// Every vertex lies at distance `radius(y)` from the curve, here the y axis.
fn on_tube(mesh: &MeshData, radius: impl Fn(f32) -> f32, y_range: (f32, f32)) {
    mesh.validate().unwrap();
    for p in &mesh.positions {
        let r = p.x.hypot(p.z);
        assert!(p.y >= y_range.0 - 1e-4 && p.y <= y_range.1 + 1e-4, "{p}");
        // Rings are scaled so that their perimeter is the circle's (within 1 % of the radius).
        assert!((r - radius(p.y)).abs() <= 0.015 * radius(p.y) + 1e-5, "{p}: {r} vs {}", radius(p.y));
    }
}

#[test]
fn pbrt_curves_tessellate_every_basis_degree_and_type() {
    // Collinear control points on the y axis at unit spacing: every basis traces the axis.
    let cases = [
        ("bezier3", "\"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0]", (0.0, 3.0)),
        ("bezier3x2", "\"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0]", (0.0, 6.0)),
        ("bezier2", "\"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0 0 4 0] \"integer degree\" 2", (0.0, 4.0)),
        ("bspline3", "\"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0 0 4 0] \"string basis\" \"bspline\"", (1.0, 3.0)),
        (
            "bspline2",
            "\"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"string basis\" \"bspline\" \"integer degree\" 2",
            (0.5, 2.5),
        ),
    ];
    for (name, params, range) in cases {
        for ty in ["flat", "cylinder", "ribbon"] {
            let extra = if ty == "ribbon" { " \"normal N\" [0 0 1 0 0 1]" } else { "" };
            let body = format!("Shape \"curve\" {params} \"string type\" \"{ty}\" \"float width\" 0.2{extra}\n");
            let d = pbrt(name, &body).unwrap_or_else(|e| panic!("{name} {ty}: {e}"));
            assert!(d.warnings.is_empty(), "{name} {ty}: {:?}", d.warnings);
            on_tube(only_mesh(&d), |_| 0.1, range);
        }
    }
    // width0 → width1 linearly along the curve; the transformation scales the tube.
    let d = pbrt(
        "widths",
        "Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width0\" 0.4 \"float width1\" 0.2\n",
    )
    .unwrap();
    on_tube(only_mesh(&d), |y| 0.2 - 0.1 * y / 3.0, (0.0, 3.0));
    let d = pbrt("scaled", "Scale 2 2 2\nShape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width\" 0.1\n")
        .unwrap();
    on_tube(only_mesh(&d), |_| 0.1, (0.0, 6.0));
    // splitdepth sets the samples per segment: 2^2 + 1 rings of SIDES + 1 vertices.
    let d = pbrt("split", "Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"integer splitdepth\" 2\n").unwrap();
    assert_eq!(only_mesh(&d).positions.len(), 5 * 17);
}

#[test]
fn pbrt_curve_errors_name_the_line() {
    let cases = [
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0]\n", "3n + 1 control points, got 3"),
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"string basis\" \"hermite\"\n", "basis \"hermite\""),
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"integer degree\" 4\n", "degree 4"),
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"string type\" \"tube\"\n", "type \"tube\""),
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width\" -1\n", "non-negative"),
        ("Shape \"curve\"\n", "needs \"point3 P\""),
        ("Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0] \"string basis\" \"bspline\"\n", "at least 4"),
    ];
    for (i, (body, expected)) in cases.iter().enumerate() {
        let e = pbrt(&format!("curve_err{i}"), &format!("\n{body}")).unwrap_err();
        assert!(e.to_string().contains(expected), "{e}");
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.file.ends_with("scene.pbrt"));
    }
}

fn mitsuba(test: &str, bsdf: &str) -> Result<SceneDescription, io::SceneError> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-hair-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    fs::write(dir.join("c.txt"), "0 0 0 0.01\n0 1 0 0.01\n0 2 0 0.01\n0 3 0 0.01\n").unwrap();
    let path = dir.join("scene.xml");
    let text = format!(
        "<scene version=\"3.0.0\">\n<shape type=\"bsplinecurve\">\n<string name=\"filename\" value=\"c.txt\"/>\n{bsdf}\n</shape>\n</scene>\n"
    );
    fs::write(&path, text).unwrap();
    io::mitsuba::load(&path, &[])
}

fn mitsuba_hair(test: &str, bsdf: &str) -> HairParameters {
    let d = mitsuba(test, bsdf).unwrap_or_else(|e| panic!("{e}"));
    // The test scenes have no sensor; nothing else may be reported.
    assert!(d.warnings.iter().all(|w| w.contains("no <sensor>")), "{:?}", d.warnings);
    match d.materials.iter().find(|m| matches!(m, Material::Hair(_))) {
        Some(Material::Hair(h)) => *h,
        _ => panic!("no hair material"),
    }
}

#[test]
fn mitsuba_hair_loads_and_checks() {
    let d = mitsuba_hair("m_default", "<bsdf type=\"hair\"/>");
    assert!(close(d.sigma_a, EUMELANIN_SIGMA_A * 1.3 + PHEOMELANIN_SIGMA_A * 0.2));
    assert!((d.eta - 1.55 / 1.000277).abs() < 1e-6 && d.beta_m == 0.3 && d.beta_n == 0.3 && d.alpha == 2.0);
    let h = mitsuba_hair(
        "m_all",
        "<bsdf type=\"hair\"><rgb name=\"sigma_a\" value=\"0.2, 0.25, 0.7\"/><float name=\"scale\" value=\"2\"/>\
         <float name=\"int_ior\" value=\"1.5\"/><float name=\"ext_ior\" value=\"1\"/>\
         <float name=\"longitudinal_roughness\" value=\"0.1\"/><float name=\"azimuthal_roughness\" value=\"0.7\"/>\
         <float name=\"scale_tilt\" value=\"-3\"/></bsdf>",
    );
    assert!(close(h.sigma_a, Rgb::new(0.4, 0.5, 1.4)));
    assert_eq!((h.eta, h.beta_m, h.beta_n, h.alpha), (1.5, 0.1, 0.7, -3.0));
    let e = mitsuba(
        "m_both",
        "<bsdf type=\"hair\"><rgb name=\"sigma_a\" value=\"0.2\"/><float name=\"eumelanin\" value=\"1\"/></bsdf>",
    )
    .unwrap_err();
    assert!(e.to_string().contains("not both") && e.line == Some(4), "{e}");
    let e =
        mitsuba("m_rough", "<bsdf type=\"hair\"><float name=\"azimuthal_roughness\" value=\"2\"/></bsdf>").unwrap_err();
    assert!(e.to_string().contains("beta_n") && e.line == Some(4), "{e}");
}

/// A hair tube is seen from outside only: a ray from inside passes through its wall (both ray
/// queries), while the same tube with a diffuse material stops it; from outside both stop it.
#[test]
fn hair_tubes_are_transparent_from_inside() {
    let curve = "Shape \"curve\" \"point3 P\" [0 -3 0 0 -1 0 0 1 0 0 3 0] \"float width\" 0.5\n";
    for (material, hair) in [("Material \"hair\"\n", true), ("Material \"diffuse\"\n", false)] {
        let d = pbrt(if hair { "inside_hair" } else { "inside_diffuse" }, &format!("{material}{curve}")).unwrap();
        let (scene, _) = Scene::from_description(&d, None).unwrap();
        let inside = math::Ray::new(math::Vec3::ZERO, math::Vec3::X);
        assert_eq!(scene.intersect(&inside).is_none(), hair, "{material}");
        assert_eq!(scene.occluded(math::Vec3::ZERO, math::Vec3::X, 10.0), !hair, "{material}");
        let outside = math::Ray::new(math::Vec3::new(-5.0, 0.0, 0.0), math::Vec3::X);
        let hit = scene.intersect(&outside).expect("the tube is hit from outside");
        assert!((hit.distance - 4.75).abs() < 0.01, "{}", hit.distance);
        assert!(scene.occluded(math::Vec3::new(-5.0, 0.0, 0.0), math::Vec3::X, 10.0));
    }
}

/// Per-iteration means (green channel) over the hair's part of the image of `algorithm` on
/// `description`.
fn render(description: &SceneDescription, algorithm: &str, iterations: u64) -> MeanVar {
    let (scene, _) = Scene::from_description(description, None).unwrap();
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        max_length: 8,
        seed: 14,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(&scene, &settings).unwrap();
    let mut stats = MeanVar::new();
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "no rejected samples");
        let frame = renderer.frame();
        assert!(frame.pixels.iter().all(|p| p.is_finite()));
        // The tuft's box in the 48 × 32 image: rows 8..20, columns 8..40.
        let width = description.film.width as usize;
        let crop = (8..20).flat_map(|y| (8..40).map(move |x| y * width + x));
        let sum: f64 = crop.map(|i| f64::from(frame.pixels[i].g)).sum();
        stats.push(sum / (12.0 * 32.0));
    }
    stats
}

/// `scenes/hair.xml` loads (160 B-spline hairs with the hair BSDF) and renders with pt and bpt
/// to the same mean over the tuft's part of the image (z-test over the per-iteration means: the camera-side `h` and the
/// exact adjoint make both estimators of one integral); vcm renders it too.
#[test]
fn the_repository_hair_scene_renders_the_same_mean_with_pt_and_bpt() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hair.xml");
    let description = io::mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(description.warnings.is_empty(), "{:?}", description.warnings);
    assert_eq!(description.materials.iter().filter(|m| matches!(m, Material::Hair(_))).count(), 1);
    let n = 384;
    let pt = render(&description, "pt", n);
    let bpt = render(&description, "bpt", n);
    let d = pt.mean() - bpt.mean();
    let se = (pt.variance() / n as f64 + bpt.variance() / n as f64).sqrt();
    eprintln!("hair scene: pt {} ± {}, bpt {} ± {}", pt.mean(), pt.std_error(), bpt.mean(), bpt.std_error());
    assert!(pt.mean() > 0.01, "a visible image: {}", pt.mean());
    assert!(z_test_p(d, se) >= 1e-4, "pt {} vs bpt {} (se {se})", pt.mean(), bpt.mean());
    // The comparison has power: a 3 % bias would be rejected.
    assert!(z_test_p(0.03 * pt.mean(), se) < 1e-4, "se {se} too large to see a 3 % bias");
    // Light tracing evaluates every hair vertex in importance mode (the adjoint, with h from
    // the generated direction); weak: its standard error is about 9 % here.
    let lt = render(&description, "lt", n);
    let se_lt = (pt.variance() / n as f64 + lt.variance() / n as f64).sqrt();
    eprintln!("hair scene: lt {} ± {}", lt.mean(), lt.std_error());
    assert!(z_test_p(pt.mean() - lt.mean(), se_lt) >= 1e-4, "pt {} vs lt {} (se {se_lt})", pt.mean(), lt.mean());
    let vcm = render(&description, "vcm", 4);
    assert!(vcm.mean() > 0.01 && vcm.mean().is_finite());
}
