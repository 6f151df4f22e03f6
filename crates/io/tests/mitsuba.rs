//! Tests of the Mitsuba 3 XML loader: small inline scenes written to a temporary directory,
//! error messages, and the real scenes in `../shared/scenes/mitsuba` (tests `shared_*`, ignored:
//! `.ci/run` runs them where `../shared` is present).

use std::path::{Path, PathBuf};

use io::mitsuba::{load, tabulated_spectrum_to_rgb, xyz_to_linear_srgb};
use io::{Image, SceneError, WriteOptions, write_image};
use math::{Vec2, Vec3};
use scene::Texture;
use scene::desc::{FilterDesc, Geometry, LightDesc, MeshData, Projection, SceneDescription, UvTransform};
use scene::material::Material;
use scene::microfacet::Distribution;
use spectrum::Rgb;
use testkit::TempDir;

/// A fresh empty directory under the system temp dir, removed when the guard is dropped.
fn temp_dir() -> TempDir {
    TempDir::new("mitsuba-test")
}

fn write(dir: &Path, name: &str, contents: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, contents).unwrap();
    path
}

fn scene(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

fn load_body(body: &str) -> SceneDescription {
    let dir = temp_dir();
    let path = write(&dir, "scene.xml", &scene(body));
    match load(&path, &[]) {
        Ok(s) => s,
        Err(e) => panic!("loading failed: {e}"),
    }
}

fn load_err(body: &str) -> (SceneError, PathBuf) {
    let dir = temp_dir();
    let path = write(&dir, "scene.xml", &scene(body));
    match load(&path, &[]) {
        Ok(_) => panic!("expected an error for\n{body}"),
        Err(e) => (e, path),
    }
}

/// Asserts that the error is in `file` at `line` and mentions every piece of `needles`.
fn assert_error(error: &SceneError, file: &Path, line: u32, needles: &[&str]) {
    let text = error.to_string();
    assert_eq!(error.file, file, "{text}");
    assert_eq!(error.line, Some(line), "{text}");
    assert!(text.starts_with(&format!("{}:{line}:", file.display())), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

fn assert_vec(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a:?} != {b:?}");
}

fn assert_rgb(a: Rgb, b: [f32; 3], tol: f32) {
    assert!(close(a.r, b[0], tol) && close(a.g, b[1], tol) && close(a.b, b[2], tol), "{a:?} != {b:?}");
}

fn mesh(s: &SceneDescription, i: usize) -> &MeshData {
    match &s.shapes[i].geometry {
        Geometry::Mesh(m) => m,
        other => panic!("shape {i} is not a mesh: {other:?}"),
    }
}

/// Unnormalised geometric normal of triangle `t` (right-hand rule).
fn face_cross(m: &MeshData, t: usize) -> Vec3 {
    let [a, b, c] = m.triangles[t].map(|i| m.positions[i as usize]);
    (b - a).cross(c - a)
}

fn total_area(m: &MeshData) -> f32 {
    (0..m.triangles.len()).map(|t| 0.5 * face_cross(m, t).length()).sum()
}

const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="40"/>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film></sensor>"#;

// ---------------------------------------------------------------------------------------------
// Transforms
// ---------------------------------------------------------------------------------------------

#[test]
fn transforms_compose_in_document_order() {
    // scale 2 then translate x 1: the centre moves by 1 (not 2).
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="sphere"><transform name="to_world"><scale value="2"/><translate x="1"/></transform></shape>
        <shape type="sphere"><transform name="to_world"><translate x="1"/><scale value="2"/></transform></shape>"#
    ));
    match s.shapes[0].geometry {
        Geometry::Sphere { center, radius, flip_normals } => {
            assert_vec(center, Vec3::new(1.0, 0.0, 0.0), 1e-6);
            assert!(close(radius, 2.0, 1e-6));
            assert!(!flip_normals);
        }
        ref g => panic!("{g:?}"),
    }
    match s.shapes[1].geometry {
        Geometry::Sphere { center, radius, .. } => {
            assert_vec(center, Vec3::new(2.0, 0.0, 0.0), 1e-6);
            assert!(close(radius, 2.0, 1e-6));
        }
        ref g => panic!("{g:?}"),
    }
}

#[test]
fn rotation_is_right_handed_in_degrees_and_matrix_is_row_major() {
    // Rotating +z by 90° about +x gives -y.
    let s = load_body(&format!(
        r#"{SENSOR}
        <emitter type="directional"><transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>
        <emitter type="point"><transform name="to_world">
            <matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/></transform></emitter>"#
    ));
    match s.lights[0] {
        LightDesc::Directional { direction, irradiance } => {
            assert_vec(direction, Vec3::new(0.0, -1.0, 0.0), 1e-6);
            assert_rgb(irradiance, [1.0; 3], 0.0);
        }
        ref l => panic!("{l:?}"),
    }
    match s.lights[1] {
        LightDesc::Point { position, .. } => assert_vec(position, Vec3::new(5.0, 6.0, 7.0), 0.0),
        ref l => panic!("{l:?}"),
    }
}

#[test]
fn lookat_builds_mitsubas_camera_frame() {
    let s = load_body(
        r#"<sensor type="perspective"><float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 4" up="0, 1, 0"/></transform></sensor>"#,
    );
    let c = s.camera;
    assert_vec(c.position, Vec3::new(1.0, 2.0, 3.0), 1e-6);
    assert_vec(c.forward, Vec3::new(0.0, 0.0, 1.0), 1e-6);
    assert_vec(c.up, Vec3::new(0.0, 1.0, 0.0), 1e-6);
    // Looking along +z with +y up, the image's right is -x (Mitsuba's camera +x is left).
    assert_vec(c.right, Vec3::new(-1.0, 0.0, 0.0), 1e-6);
    // Defaults: 768×576 film, Gaussian filter σ = 0.5 truncated at 2, fov along x.
    assert_eq!((s.film.width, s.film.height), (768, 576));
    assert_eq!(s.film.filter, FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 });
    assert_eq!(c.projection, Projection::Perspective { horizontal_fov_degrees: 30.0 });
}

#[test]
fn fov_axis_conversions() {
    let horizontal = |axis: &str, w: u32, h: u32| -> f64 {
        let s = load_body(&format!(
            r#"<sensor type="perspective"><float name="fov" value="60"/><string name="fov_axis" value="{axis}"/>
            <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film>
            </sensor>"#
        ));
        match s.camera.projection {
            Projection::Perspective { horizontal_fov_degrees } => f64::from(horizontal_fov_degrees),
            p => panic!("{p:?}"),
        }
    };
    // Image plane at distance 1: half-extent along the given axis is tan(30°); square pixels.
    let t = 30f64.to_radians().tan();
    let from_half_width = |hw: f64| 2.0 * hw.atan().to_degrees();
    let tol = 1e-4;
    assert!((horizontal("x", 400, 200) - 60.0).abs() < tol);
    let via_y = from_half_width(t * 2.0);
    assert!((horizontal("y", 400, 200) - via_y).abs() < tol);
    let via_diagonal = from_half_width(t * 400.0 / (400.0f64 * 400.0 + 200.0 * 200.0).sqrt());
    assert!((horizontal("diagonal", 400, 200) - via_diagonal).abs() < tol);
    // Landscape: the smaller axis is y, the larger x; portrait the other way round.
    assert!((horizontal("smaller", 400, 200) - via_y).abs() < tol);
    assert!((horizontal("larger", 400, 200) - 60.0).abs() < tol);
    assert!((horizontal("smaller", 200, 400) - 60.0).abs() < tol);
    assert!((horizontal("larger", 200, 400) - from_half_width(t * 0.5)).abs() < tol);
}

// ---------------------------------------------------------------------------------------------
// Parameters, includes, references
// ---------------------------------------------------------------------------------------------

#[test]
fn defaults_are_substituted_and_defines_override_them() {
    let dir = temp_dir();
    let path = write(
        &dir,
        "scene.xml",
        &scene(&format!(
            r#"<default name="r" value="0.25"/><default name="x" value="3"/>
            {SENSOR}
            <shape type="sphere"><float name="radius" value="$r"/><point name="center" value="$x, $x, 1"/></shape>"#
        )),
    );
    let radius_center = |s: &SceneDescription| match s.shapes[0].geometry {
        Geometry::Sphere { radius, center, .. } => (radius, center),
        ref g => panic!("{g:?}"),
    };
    let s = load(&path, &[]).unwrap();
    assert_eq!(radius_center(&s), (0.25, Vec3::new(3.0, 3.0, 1.0)));
    let s = load(&path, &[("r".into(), "0.5".into())]).unwrap();
    assert_eq!(radius_center(&s), (0.5, Vec3::new(3.0, 3.0, 1.0)));
}

#[test]
fn undefined_parameter_is_an_error() {
    let (e, path) =
        load_err(&format!("{SENSOR}\n<shape type=\"sphere\"><float name=\"radius\" value=\"$nope\"/></shape>"));
    assert_error(&e, &path, 4, &["$nope"]);
}

#[test]
fn include_is_relative_to_the_including_file_and_errors_name_the_included_file() {
    let dir = temp_dir();
    write(
        &dir,
        "parts/materials.xml",
        &scene(
            r#"<include filename="more.xml"/><bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.3"/></bsdf>"#,
        ),
    );
    write(
        &dir,
        "parts/more.xml",
        &scene(r#"<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.6, 0.1, 0.1"/></bsdf>"#),
    );
    let main = write(
        &dir,
        "main.xml",
        &scene(&format!(
            r#"<include filename="parts/materials.xml"/>{SENSOR}
            <shape type="sphere"><ref id="red"/></shape><shape type="sphere"><ref id="grey"/></shape>"#
        )),
    );
    let s = load(&main, &[]).unwrap();
    let reflectance = |i: usize| match &s.materials[s.shapes[i].material as usize] {
        Material::Diffuse { reflectance } => reflectance.as_constant().unwrap(),
        m => panic!("{m:?}"),
    };
    assert_rgb(reflectance(0), [0.6, 0.1, 0.1], 0.0);
    assert_rgb(reflectance(1), [0.3; 3], 0.0);

    // A malformed included file: the error names it, with its line.
    let bad = write(&dir, "parts/bad.xml", "<scene version=\"3.0.0\">\n  <bsdf type=\"diffuse\">\n</scene>\n");
    let main = write(&dir, "main2.xml", &scene(r#"<include filename="parts/bad.xml"/>"#));
    let e = load(&main, &[]).unwrap_err();
    assert_eq!(e.file, bad, "{e}");
    assert_eq!(e.line, Some(3), "{e}");

    // A missing included file: the error is at the <include>.
    let main = write(&dir, "main3.xml", &scene(r#"<include filename="parts/absent.xml"/>"#));
    let e = load(&main, &[]).unwrap_err();
    assert_error(&e, &main, 2, &["parts/absent.xml"]);
}

#[test]
fn include_cycles_are_errors() {
    let dir = temp_dir();
    let a = write(&dir, "a.xml", &scene(r#"<include filename="b.xml"/>"#));
    let b = write(&dir, "b.xml", &scene(r#"<include filename="a.xml"/>"#));
    let e = load(&a, &[]).unwrap_err();
    assert_error(&e, &b, 2, &["cycle"]);
}

#[test]
fn references_work_before_and_after_definition_and_unknown_ids_fail() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <texture type="checkerboard" id="tex"><rgb name="color0" value="0.4"/><rgb name="color1" value="0.2"/>
            <transform name="to_uv"><scale x="8" y="8"/></transform></texture>
        <bsdf type="diffuse" id="checks"><ref name="reflectance" id="tex"/></bsdf>
        <shape type="rectangle"><ref id="checks"/><ref id="light"/></shape>
        <shape type="rectangle"><ref id="checks"/></shape>
        <emitter type="area" id="light"><rgb name="radiance" value="1, 2, 3"/></emitter>"#
    ));
    assert_eq!(s.shapes[0].material, s.shapes[1].material, "a referenced bsdf is one material");
    assert_eq!(s.materials.len(), 1);
    match &s.materials[0] {
        Material::Diffuse { reflectance: Texture::Checkerboard { color0, color1, to_uv } } => {
            assert_rgb(*color0, [0.4; 3], 0.0);
            assert_rgb(*color1, [0.2; 3], 0.0);
            assert_eq!(
                *to_uv,
                UvTransform { columns: [Vec2::new(8.0, 0.0), Vec2::new(0.0, 8.0)], translation: Vec2::ZERO }
            );
        }
        m => panic!("{m:?}"),
    }
    assert_eq!(s.shapes[0].emission, Some(Rgb::new(1.0, 2.0, 3.0)));
    assert_eq!(s.shapes[1].emission, None);

    let (e, path) = load_err(&format!("{SENSOR}\n<shape type=\"sphere\">\n<ref id=\"missing\"/></shape>"));
    assert_error(&e, &path, 5, &["unknown id 'missing'"]);
}

// ---------------------------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------------------------

#[test]
fn rectangle_geometry_normals_and_mirroring() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="rectangle"><transform name="to_world"><scale x="2" y="3"/><translate z="5"/></transform></shape>
        <shape type="rectangle"><transform name="to_world"><scale x="-2" y="3"/></transform></shape>
        <shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>"#
    ));
    let m = mesh(&s, 0);
    assert_eq!(m.triangles.len(), 2);
    assert!(close(total_area(m), 4.0 * 2.0 * 3.0, 1e-5));
    for p in &m.positions {
        assert!(close(p.x.abs(), 2.0, 0.0) && close(p.y.abs(), 3.0, 0.0) && close(p.z, 5.0, 0.0), "{p:?}");
    }
    for t in 0..2 {
        assert_vec(face_cross(m, t).normalize(), Vec3::Z, 1e-6);
    }
    // Mirrored in x: Mitsuba's rectangle normal is the inverse transpose of +z, still +z.
    let m = mesh(&s, 1);
    assert!(close(total_area(m), 24.0, 1e-5));
    for t in 0..2 {
        assert_vec(face_cross(m, t).normalize(), Vec3::Z, 1e-6);
    }
    let m = mesh(&s, 2);
    for t in 0..2 {
        assert_vec(face_cross(m, t).normalize(), -Vec3::Z, 1e-6);
    }
    // A shape without a bsdf gets Mitsuba's default diffuse 0.5.
    assert_eq!(
        s.materials[s.shapes[0].material as usize],
        Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }
    );
}

#[test]
fn cube_normals_point_outward_even_when_mirrored() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="cube"/>
        <shape type="cube"><transform name="to_world"><scale x="-1" y="2" z="0.5"/><translate x="4"/></transform></shape>
        <shape type="cube"><boolean name="flip_normals" value="true"/></shape>"#
    ));
    for (i, center, area, sign) in [
        (0, Vec3::ZERO, 24.0, 1.0),
        (1, Vec3::new(4.0, 0.0, 0.0), 8.0 * (1.0 * 2.0 + 2.0 * 0.5 + 1.0 * 0.5), 1.0),
        (2, Vec3::ZERO, 24.0, -1.0),
    ] {
        let m = mesh(&s, i);
        assert_eq!(m.triangles.len(), 12);
        assert!(close(total_area(m), area, 1e-4), "cube {i}: area {}", total_area(m));
        for t in 0..12 {
            let [a, b, c] = m.triangles[t].map(|v| m.positions[v as usize]);
            let centroid = (a + b + c) / 3.0;
            let outward = face_cross(m, t).normalize().dot((centroid - center).normalize());
            assert!(outward * sign > 0.4, "cube {i} triangle {t}: {outward}");
        }
    }
}

#[test]
fn sphere_and_disk_parameters() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/>
            <boolean name="flip_normals" value="true"/></shape>
        <shape type="disk"><transform name="to_world"><scale value="2"/><translate y="1"/></transform></shape>
        <shape type="disk"><transform name="to_world"><scale z="-1"/></transform></shape>"#
    ));
    assert_eq!(
        s.shapes[0].geometry,
        Geometry::Sphere { center: Vec3::new(1.0, 2.0, 3.0), radius: 0.5, flip_normals: true }
    );
    assert_eq!(
        s.shapes[1].geometry,
        Geometry::Disk {
            center: Vec3::Y,
            axis_u: Vec3::new(2.0, 0.0, 0.0),
            axis_v: Vec3::new(0.0, 2.0, 0.0),
            flip_normals: false
        }
    );
    // Mirrored disk: Mitsuba's normal (inverse transpose of +z) is -z while u × v = +z.
    match s.shapes[2].geometry {
        Geometry::Disk { axis_u, axis_v, flip_normals, .. } => {
            assert_vec(axis_u.cross(axis_v), Vec3::Z, 0.0);
            assert!(flip_normals);
        }
        ref g => panic!("{g:?}"),
    }
    let (e, path) = load_err(&format!(
        "{SENSOR}\n<shape type=\"sphere\"><transform name=\"to_world\"><scale x=\"2\"/></transform></shape>"
    ));
    assert_error(&e, &path, 4, &["sphere", "uniform"]);
}

// ---------------------------------------------------------------------------------------------
// BSDFs and textures
// ---------------------------------------------------------------------------------------------

fn one_material(bsdf: &str) -> (Material, Vec<String>) {
    let s = load_body(&format!("{SENSOR}\n<shape type=\"sphere\">{bsdf}</shape>"));
    (s.materials[s.shapes[0].material as usize].clone(), s.warnings)
}

#[test]
fn conductors() {
    assert_eq!(one_material(r#"<bsdf type="conductor"/>"#).0, Material::perfect_mirror());
    let normal_reflectance = |eta: f32, k: f32| ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
    match one_material(r#"<bsdf type="conductor"><string name="material" value="Au"/></bsdf>"#).0 {
        Material::Conductor { eta, k, .. } => {
            let r = [normal_reflectance(eta.r, k.r), normal_reflectance(eta.g, k.g), normal_reflectance(eta.b, k.b)];
            // Gold: high red reflectance falling towards blue (its yellow colour).
            assert!(r[0] > 0.9 && r[0] > r[1] && r[1] > r[2] && r[2] < 0.5, "{r:?}");
        }
        m => panic!("{m:?}"),
    }
    match one_material(r#"<bsdf type="conductor"><string name="material" value="Ag"/></bsdf>"#).0 {
        Material::Conductor { eta, k, .. } => {
            for (e, k) in [(eta.r, k.r), (eta.g, k.g), (eta.b, k.b)] {
                assert!(normal_reflectance(e, k) > 0.9, "silver reflects > 90 %");
            }
        }
        m => panic!("{m:?}"),
    }
    match one_material(
        r#"<bsdf type="roughconductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9 2.4 2.1"/>
           <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/><string name="distribution" value="ggx"/></bsdf>"#,
    ) {
        (Material::RoughConductor { alpha_u, alpha_v, eta, k, .. }, warnings) => {
            assert_eq!((alpha_u, alpha_v), (0.1, 0.3));
            assert_rgb(eta, [0.2, 0.9, 1.1], 0.0);
            assert_rgb(k, [3.9, 2.4, 2.1], 0.0);
            assert!(warnings.is_empty(), "{warnings:?}");
        }
        m => panic!("{m:?}"),
    }
    // Default distribution: Beckmann, as Mitsuba, without a warning.
    let (m, warnings) = one_material(r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#);
    assert!(
        matches!(m, Material::RoughConductor { distribution: Distribution::Beckmann, alpha_u: 0.2, alpha_v: 0.2, .. }),
        "{m:?}"
    );
    assert!(warnings.is_empty(), "{warnings:?}");
    let (e, path) = load_err(&format!(
        "{SENSOR}\n<shape type=\"sphere\">\n<bsdf type=\"conductor\"><string name=\"material\" value=\"Unobtainium\"/></bsdf></shape>"
    ));
    assert_error(&e, &path, 5, &["Unobtainium"]);
}

#[test]
fn dielectrics_and_named_iors() {
    match one_material(r#"<bsdf type="dielectric"/>"#).0 {
        Material::Dielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance, .. } => {
            assert_eq!((int_ior, ext_ior), (1.5046, 1.000277));
            assert_eq!(specular_reflectance, Texture::Constant(Rgb::WHITE));
            assert_eq!(specular_transmittance, Texture::Constant(Rgb::WHITE));
        }
        m => panic!("{m:?}"),
    }
    match one_material(r#"<bsdf type="thindielectric"><string name="int_ior" value="water"/><string name="ext_ior" value="vacuum"/></bsdf>"#).0 {
        Material::ThinDielectric { int_ior, ext_ior, .. } => assert_eq!((int_ior, ext_ior), (1.333, 1.0)),
        m => panic!("{m:?}"),
    }
    match one_material(r#"<bsdf type="roughdielectric"><string name="int_ior" value="diamond"/><float name="alpha" value="0.05"/><string name="distribution" value="ggx"/></bsdf>"#).0 {
        Material::RoughDielectric { int_ior, alpha_u, alpha_v, .. } => assert_eq!((int_ior, alpha_u, alpha_v), (2.419, 0.05, 0.05)),
        m => panic!("{m:?}"),
    }
    let (e, path) = load_err(&format!(
        "{SENSOR}\n<shape type=\"sphere\">\n<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"1\"/><float name=\"ext_ior\" value=\"1\"/></bsdf></shape>"
    ));
    assert_error(&e, &path, 5, &["differ"]);
}

#[test]
fn plastics_blend_and_twosided() {
    match one_material(r#"<bsdf type="plastic"><boolean name="nonlinear" value="true"/></bsdf>"#).0 {
        Material::Plastic { diffuse_reflectance, specular_reflectance, int_ior, ext_ior, nonlinear } => {
            assert_eq!(diffuse_reflectance, Texture::Constant(Rgb::splat(0.5)));
            assert_eq!(specular_reflectance, Texture::Constant(Rgb::WHITE));
            assert_eq!((int_ior, ext_ior, nonlinear), (1.49, 1.000277, true));
        }
        m => panic!("{m:?}"),
    }
    match one_material(
        r#"<bsdf type="roughplastic"><float name="alpha" value="0.3"/><float name="int_ior" value="2"/>
            <rgb name="diffuse_reflectance" value="0.07 0.09 0.13"/></bsdf>"#,
    )
    .0
    {
        Material::RoughPlastic { alpha, int_ior, diffuse_reflectance, .. } => {
            assert_eq!((alpha, int_ior), (0.3, 2.0));
            assert_eq!(diffuse_reflectance, Texture::Constant(Rgb::new(0.07, 0.09, 0.13)));
        }
        m => panic!("{m:?}"),
    }
    match one_material(
        r#"<bsdf type="blendbsdf"><float name="weight" value="0.3"/>
            <bsdf type="diffuse"/><bsdf type="conductor"/></bsdf>"#,
    )
    .0
    {
        Material::Blend { weight, first, second } => {
            assert_eq!(weight, Texture::Constant(Rgb::splat(0.3)));
            assert!(matches!(*first, Material::Diffuse { .. }));
            assert_eq!(*second, Material::perfect_mirror());
        }
        m => panic!("{m:?}"),
    }
    match one_material(
        r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf></bsdf>"#,
    )
    .0
    {
        Material::TwoSided { front, back: None } => {
            assert_eq!(*front, Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.2)) })
        }
        m => panic!("{m:?}"),
    }
    match one_material(r#"<bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="dielectric"/></bsdf>"#).0 {
        Material::TwoSided { back: Some(back), .. } => assert!(matches!(*back, Material::Dielectric { .. })),
        m => panic!("{m:?}"),
    }
    let (e, path) = load_err(&format!("{SENSOR}\n<shape type=\"sphere\">\n<bsdf type=\"measured\"/></shape>"));
    assert_error(&e, &path, 5, &["unsupported bsdf type 'measured'"]);
}

#[test]
fn bitmap_textures_decode_srgb_unless_raw() {
    let dir = temp_dir();
    // Pixels chosen so that the PNG stores the 8-bit codes 0, 64, 128 / 200, 255, 10.
    let codes = [[0u8, 64, 128], [200, 255, 10]];
    let image = Image { width: 2, height: 1, pixels: codes.iter().map(|c| c.map(io::srgb8_to_linear)).collect() };
    write_image(&dir.join("tex.png"), &image, &WriteOptions::default()).unwrap();
    let path = write(
        &dir,
        "scene.xml",
        &scene(&format!(
            r#"{SENSOR}
            <shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                <string name="filename" value="tex.png"/>
                <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></shape>
            <shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                <string name="filename" value="tex.png"/><boolean name="raw" value="true"/></texture></bsdf></shape>"#
        )),
    );
    let s = load(&path, &[]).unwrap();
    // The sRGB EOTF, written out independently of the crate.
    let eotf = |c: u8| {
        let v = f64::from(c) / 255.0;
        if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
    };
    let texels = |i: usize| match &s.materials[s.shapes[i].material as usize] {
        Material::Diffuse { reflectance: Texture::Bitmap { image, to_uv } } => (image.clone(), *to_uv),
        m => panic!("{m:?}"),
    };
    let (decoded, to_uv) = texels(0);
    assert_eq!((decoded.width, decoded.height), (2, 1));
    for (x, c) in codes.iter().enumerate() {
        let p = decoded.pixel(x as u32, 0).to_array();
        for ch in 0..3 {
            assert!((f64::from(p[ch]) - eotf(c[ch])).abs() < 1e-5, "decoded {p:?} vs code {c:?}");
        }
    }
    assert_eq!(
        to_uv,
        UvTransform { columns: [Vec2::new(2.0, 0.0), Vec2::new(0.0, 3.0)], translation: Vec2::new(0.5, 0.0) }
    );
    let (raw, _) = texels(1);
    for (x, c) in codes.iter().enumerate() {
        let p = raw.pixel(x as u32, 0).to_array();
        for ch in 0..3 {
            assert!((f64::from(p[ch]) - f64::from(c[ch]) / 255.0).abs() < 1e-5, "raw {p:?} vs code {c:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Emitters
// ---------------------------------------------------------------------------------------------

#[test]
fn point_spot_directional_constant_lights() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="5, 6, 7"/></emitter>
        <emitter type="spot"><transform name="to_world"><lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
            <rgb name="intensity" value="2"/></emitter>
        <emitter type="spot"><float name="cutoff_angle" value="30"/><float name="beam_width" value="10"/></emitter>
        <emitter type="directional"><vector name="direction" x="0" y="0" z="-2"/><rgb name="irradiance" value="3"/></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#
    ));
    assert_eq!(
        s.lights[0],
        LightDesc::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Rgb::new(5.0, 6.0, 7.0) }
    );
    match s.lights[1] {
        LightDesc::Spot { position, direction, intensity, cutoff_degrees, beam_width_degrees, texture: None } => {
            assert_vec(position, Vec3::new(0.0, 4.0, 0.0), 1e-6);
            assert_vec(direction, Vec3::new(0.0, -1.0, 0.0), 1e-6);
            assert_rgb(intensity, [2.0; 3], 0.0);
            // Mitsuba's defaults: cutoff 20°, beam width 3/4 of it.
            assert_eq!((cutoff_degrees, beam_width_degrees), (20.0, 15.0));
        }
        ref l => panic!("{l:?}"),
    }
    assert!(matches!(s.lights[2], LightDesc::Spot { cutoff_degrees: 30.0, beam_width_degrees: 10.0, .. }));
    assert_eq!(
        s.lights[3],
        LightDesc::Directional { direction: Vec3::new(0.0, 0.0, -1.0), irradiance: Rgb::splat(3.0) }
    );
    assert_eq!(s.lights[4], LightDesc::Constant { radiance: Rgb::splat(0.5) });
    let (e, path) = load_err(&format!("{SENSOR}\n<emitter type=\"constant\"/>\n<emitter type=\"constant\"/>"));
    assert_error(&e, &path, 5, &["one environment"]);
}

#[test]
fn envmap_reads_the_image_with_scale_and_rotation() {
    let dir = temp_dir();
    let image = Image { width: 4, height: 2, pixels: (0..8).map(|i| [i as f32, 1.0, 2.0]).collect() };
    write_image(&dir.join("env.exr"), &image, &WriteOptions::default()).unwrap();
    let path = write(
        &dir,
        "scene.xml",
        &scene(&format!(
            r#"{SENSOR}<emitter type="envmap"><string name="filename" value="env.exr"/><float name="scale" value="3"/>
            <transform name="to_world"><rotate y="1" angle="90"/><translate z="8"/></transform></emitter>"#
        )),
    );
    let s = load(&path, &[]).unwrap();
    match &s.lights[0] {
        LightDesc::EnvMap { image: texture, scale, to_world } => {
            assert_eq!(*scale, 3.0);
            assert_eq!((texture.width, texture.height), (4, 2));
            assert_eq!(texture.pixel(3, 1), Rgb::new(7.0, 1.0, 2.0));
            // Rotation by 90° about +y: x → -z, y → y, z → x.
            assert_vec(to_world[0], Vec3::new(0.0, 0.0, -1.0), 1e-6);
            assert_vec(to_world[1], Vec3::Y, 1e-6);
            assert_vec(to_world[2], Vec3::X, 1e-6);
        }
        l => panic!("{l:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Sensors, films, integrators
// ---------------------------------------------------------------------------------------------

#[test]
fn thinlens_orthographic_and_filters() {
    let s = load_body(
        r#"<sensor type="thinlens"><float name="fov" value="50"/><float name="aperture_radius" value="0.1"/>
            <float name="focus_distance" value="7"/>
            <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="tent"><float name="radius" value="1.5"/></rfilter></film></sensor>"#,
    );
    assert_eq!(
        s.camera.projection,
        Projection::ThinLens { horizontal_fov_degrees: 50.0, aperture_radius: 0.1, focus_distance: 7.0 }
    );
    assert_eq!(s.film.filter, FilterDesc::Tent { radius: 1.5 });
    let s = load_body(
        r#"<sensor type="orthographic"><transform name="to_world"><scale value="3"/>
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><rfilter type="box"/></film></sensor>"#,
    );
    // Mitsuba's orthographic camera spans camera-space x in [-1, 1]: width 2 × scale.
    assert_eq!(s.camera.projection, Projection::Orthographic { width: 6.0 });
    assert_vec(s.camera.forward, -Vec3::Z, 1e-6);
    assert_eq!(s.film.filter, FilterDesc::Box);
    let s = load_body(
        r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="gaussian"><float name="stddev" value="0.25"/></rfilter></film></sensor>"#,
    );
    assert_eq!(s.film.filter, FilterDesc::Gaussian { stddev: 0.25, radius: 1.0 });
    // No fov: Mitsuba's default 50 mm focal length on 35 mm film is a diagonal field of view.
    match s.camera.projection {
        Projection::Perspective { horizontal_fov_degrees } => {
            let diagonal = 2.0 * ((36.0f64.hypot(24.0)) / 100.0).atan();
            let half_width = (diagonal / 2.0).tan() * 768.0 / 768.0f64.hypot(576.0);
            assert!((f64::from(horizontal_fov_degrees) - 2.0 * half_width.atan().to_degrees()).abs() < 1e-4);
        }
        p => panic!("{p:?}"),
    }
}

#[test]
fn integrator_max_depth() {
    let depth = |integrator: &str| {
        let s = load_body(&format!("{SENSOR}{integrator}"));
        (s.max_path_length, s.warnings)
    };
    assert_eq!(depth(r#"<integrator type="path"><integer name="max_depth" value="8"/></integrator>"#).0, Some(8));
    assert_eq!(depth(r#"<integrator type="path"><integer name="max_depth" value="-1"/></integrator>"#).0, None);
    assert_eq!(depth(r#"<integrator type="path"/>"#).0, None);
    assert_eq!(depth(r#"<integrator type="volpath"><integer name="max_depth" value="3"/></integrator>"#).0, Some(3));
    assert_eq!(depth(r#"<integrator type="bdpt"><integer name="max_depth" value="5"/></integrator>"#).0, Some(5));
    assert_eq!(depth("").0, None);
    let (d, warnings) = depth(r#"<integrator type="direct"/>"#);
    assert_eq!(d, Some(2));
    assert!(warnings.iter().any(|w| w.contains("direct")), "{warnings:?}");
    let (d, warnings) = depth(r#"<integrator type="aov"/>"#);
    assert_eq!(d, None);
    assert!(warnings.iter().any(|w| w.contains("'aov'")), "{warnings:?}");
    let (e, path) = load_err(r#"<integrator type="path"><integer name="max_depth" value="-2"/></integrator>"#);
    assert_error(&e, &path, 2, &["max_depth"]);
}

// ---------------------------------------------------------------------------------------------
// Spectra
// ---------------------------------------------------------------------------------------------

#[test]
fn constant_spectra_become_grey_reflectances_and_equal_energy_emission() {
    // D65 is the sRGB white point: a flat reflectance stays grey.
    let grey = tabulated_spectrum_to_rgb(&[(360.0, 0.5), (830.0, 0.5)], false);
    for c in grey {
        assert!((c - 0.5).abs() < 2e-3, "{grey:?}");
    }
    // The CIE matching functions have equal integrals: a flat emission spectrum c has
    // XYZ = (c, c, c) and so RGB = c · M · (1, 1, 1).
    let white = xyz_to_linear_srgb([1.0; 3]);
    let emitted = tabulated_spectrum_to_rgb(&[(360.0, 2.0), (830.0, 2.0)], true);
    for ch in 0..3 {
        assert!((emitted[ch] - 2.0 * white[ch]).abs() < 0.01 * 2.0 * white[ch], "{emitted:?} vs {white:?}");
    }
    // In a scene: tabulated and constant spectra, reflectance and emission.
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="360:0.25, 600:0.25, 830:0.25"/></bsdf>
            <emitter type="area"><spectrum name="radiance" value="3"/></emitter></shape>
        <shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.7"/></bsdf></shape>"#
    ));
    match &s.materials[s.shapes[0].material as usize] {
        Material::Diffuse { reflectance } => assert_rgb(reflectance.as_constant().unwrap(), [0.25; 3], 1e-3),
        m => panic!("{m:?}"),
    }
    let e = s.shapes[0].emission.unwrap();
    assert_rgb(e, white.map(|w| 3.0 * w as f32), 1e-5);
    match &s.materials[s.shapes[1].material as usize] {
        Material::Diffuse { reflectance } => assert_eq!(reflectance.as_constant(), Some(Rgb::splat(0.7))),
        m => panic!("{m:?}"),
    }
}

#[test]
fn a_narrow_band_emission_spectrum_has_the_chromaticity_of_its_wavelength() {
    // A 1 nm-wide triangle at 600 nm: XYZ ∝ (x̄, ȳ, z̄)(600) = (1.0622, 0.631, 0.0008).
    let rgb = tabulated_spectrum_to_rgb(&[(599.0, 0.0), (600.0, 1.0), (601.0, 0.0)], true);
    let expected = xyz_to_linear_srgb([1.0622, 0.631, 0.0008]);
    // Both are scaled by the same (unknown here) factor: compare directions.
    let scale = rgb[0] / expected[0];
    assert!(scale > 0.0);
    // Negative green/blue are clamped to 0, as Mitsuba does.
    for ch in 0..3 {
        assert!((rgb[ch] - (expected[ch] * scale).max(0.0)).abs() < 1e-3 * rgb[0], "{rgb:?} vs {expected:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Errors and warnings
// ---------------------------------------------------------------------------------------------

#[test]
fn error_messages_name_file_line_and_culprit() {
    let cases: [(&str, u32, &[&str]); 10] = [
        ("<shape type=\"sphere\">\n<float name=\"radius\" value=\"1\">\n</shape>", 4, &["malformed XML"]),
        ("<teapot/>", 2, &["unknown element <teapot>"]),
        ("<shape type=\"hyperboloid\"/>", 2, &["unsupported shape type 'hyperboloid'"]),
        ("<shape type=\"obj\"/>", 2, &["missing required", "filename"]),
        ("<shape type=\"sphere\"><string name=\"radius\" value=\"1\"/></shape>", 2, &["radius", "wrong type"]),
        ("<shape type=\"sphere\">\n<float name=\"radius\" value=\"abc\"/></shape>", 3, &["bad number", "abc"]),
        (
            "<shape type=\"obj\"><string name=\"filename\" value=\"nothere.obj\"/></shape>",
            2,
            &["nothere.obj", "not found"],
        ),
        ("<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"a\"/>", 3, &["'a'", "twice"]),
        ("<shape type=\"sphere\"><rgb name=\"radius\" value=\"1, 2\"/></shape>", 2, &["rgb", "three"]),
        ("<emitter type=\"sunsky\"/>", 2, &["unsupported emitter type 'sunsky'"]),
    ];
    for (body, line, needles) in cases {
        let (e, path) = load_err(body);
        assert_error(&e, &path, line, needles);
    }
}

#[test]
fn unknown_optional_properties_are_warnings_and_nothing_is_dropped() {
    let s = load_body(&format!(
        r#"{SENSOR}
        <shape type="rectangle"><float name="wobble" value="3"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.1"/><float name="sheen" value="1"/></bsdf></shape>"#
    ));
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(
        s.materials[s.shapes[0].material as usize],
        Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.1)) }
    );
    for name in ["'wobble'", "'sheen'"] {
        assert!(s.warnings.iter().any(|w| w.contains(name) && w.contains("scene.xml:")), "{:?}", s.warnings);
    }
}

#[test]
fn garbage_input_never_panics() {
    let inputs = [
        "",
        "<",
        "<scene>",
        "<scene version=\"3.0.0\"><shape type=\"sphere\"><transform name=\"to_world\"><scale value=\"0\"/></transform></shape></scene>",
        "<scene version=\"3.0.0\"><shape type=\"rectangle\"><transform name=\"to_world\"><matrix value=\"nan 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\"/></transform></shape></scene>",
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"1e40\"/></sensor></scene>",
        "<scene version=\"3.0.0\"><bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf><shape type=\"sphere\"><ref id=\"a\"/></shape></scene>",
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"-3\"/></film></sensor></scene>",
        "<scene version=\"3.0.0\"><shape type=\"sphere\"><spectrum name=\"radius\" value=\"500:1, 400:2\"/></shape></scene>",
        "<scene version=\"3.0.0\"><default name=\"a\" value=\"$a\"/></scene>",
    ];
    for input in inputs {
        let dir = temp_dir();
        let path = write(&dir, "scene.xml", input);
        if let Ok(s) = load(&path, &[]) {
            assert!(!input.is_empty(), "{s:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The real scenes
// ---------------------------------------------------------------------------------------------

/// Loads a scene of the shared Mitsuba scenes (`../shared` beside the clone). The tests that
/// need them are named `shared_*` and ignored, and `.ci/run` runs them in a step of their own;
/// without the file they fail here instead of passing unchecked.
fn real_scene(relative: &str) -> SceneDescription {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/mitsuba").join(relative);
    assert!(path.exists(), "{} is absent: this test needs ../shared beside the clone", path.display());
    load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_cornell_box_xml() {
    let s = real_scene("cornell-box/cornell_box.xml");
    assert_eq!(s.shapes.len(), 8);
    assert_eq!(s.max_path_length, Some(8));
    assert_eq!((s.film.width, s.film.height), (512, 512));
    assert_eq!(s.film.filter, FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 });
    assert_vec(s.camera.position, Vec3::new(0.0, 0.0, 3.9), 1e-6);
    assert_vec(s.camera.forward, Vec3::new(0.0, 0.0, -1.0), 1e-6);
    assert_vec(s.camera.up, Vec3::Y, 1e-6);
    assert_vec(s.camera.right, Vec3::X, 1e-6);
    // fov_axis "smaller" on a square film is the horizontal axis.
    match s.camera.projection {
        Projection::Perspective { horizontal_fov_degrees } => assert!(close(horizontal_fov_degrees, 39.3077, 1e-4)),
        p => panic!("{p:?}"),
    }
    let light = s.shapes.iter().find(|sh| sh.name == "light").unwrap();
    assert_eq!(light.emission, Some(Rgb::new(18.387, 13.9873, 6.75357)));
    assert_eq!(s.shapes.iter().filter(|sh| sh.emission.is_some()).count(), 1);
    let Geometry::Mesh(m) = &light.geometry else { panic!() };
    // [-1,1]² scaled by 0.23 × 0.19: area 4 · 0.23 · 0.19, facing down into the box at y ≈ 0.99.
    assert!(close(total_area(m), 4.0 * 0.23 * 0.19, 1e-5), "{}", total_area(m));
    for t in 0..m.triangles.len() {
        assert_vec(face_cross(m, t).normalize(), Vec3::new(0.0, -1.0, 0.0), 1e-6);
    }
    for p in &m.positions {
        assert!(close(p.y, 0.99, 1e-6));
    }
    // Walls face into the box: the floor (y = -1) up, the back wall (z = -1) towards +z.
    let normal_of = |name: &str| {
        let Geometry::Mesh(m) = &s.shapes.iter().find(|sh| sh.name == name).unwrap().geometry else { panic!() };
        face_cross(m, 0).normalize()
    };
    assert_vec(normal_of("floor"), Vec3::Y, 1e-6);
    assert_vec(normal_of("ceiling"), -Vec3::Y, 1e-6);
    assert_vec(normal_of("back"), Vec3::Z, 1e-6);
    assert_vec(normal_of("green-wall"), -Vec3::X, 1e-6);
    assert_vec(normal_of("red-wall"), Vec3::X, 1e-6);
    // Three diffuse materials (white, green, red), shared by reference.
    assert_eq!(s.materials.len(), 3);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// Loads a scene that needs the OBJ / serialized mesh readers and checks its shape count.
fn mesh_scene(relative: &str, shapes: usize) -> SceneDescription {
    let s = real_scene(relative);
    assert_eq!(s.shapes.len(), shapes, "{relative}");
    for shape in &s.shapes {
        if let Geometry::Mesh(m) = &shape.geometry {
            assert!(!m.triangles.is_empty(), "{}", shape.name);
            m.validate().unwrap();
        }
    }
    s
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_caustic_cbox_xml() {
    let s = mesh_scene("caustic-cbox/cbox.xml", 8);
    assert_eq!(s.max_path_length, Some(6));
    assert_eq!(s.film.filter, FilterDesc::Tent { radius: 1.0 });
    let glass = s.shapes.iter().find(|sh| sh.name == "glasssphere").unwrap();
    assert_eq!(
        glass.geometry,
        Geometry::Sphere { center: Vec3::new(0.5, -0.75, -0.2), radius: 0.25, flip_normals: false }
    );
    assert!(matches!(s.materials[glass.material as usize], Material::Dielectric { int_ior: 1.5046, .. }));
    let mirror = s.shapes.iter().find(|sh| sh.name == "mirrorsphere").unwrap();
    assert_eq!(s.materials[mirror.material as usize], Material::perfect_mirror());
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_cbox_classic_xml() {
    for file in ["cbox-classic/cbox.xml", "cbox-classic/cbox-rgb.xml", "cbox-classic/cbox-spectral.xml"] {
        let s = mesh_scene(file, 8);
        assert_eq!(s.shapes.iter().filter(|sh| sh.emission.is_some()).count(), 1, "{file}");
        assert_vec(s.camera.position, Vec3::new(278.0, 273.0, -800.0), 1e-3);
    }
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_veach_mis_xml() {
    let s = mesh_scene("veach-mis/veach_mis_path.xml", 10);
    assert_eq!(s.max_path_length, Some(8));
    assert_eq!(s.shapes.iter().filter(|sh| sh.emission.is_some()).count(), 4 + 1);
    let s = mesh_scene("veach-mis/integrator_direct_both.xml", 10);
    assert_eq!(s.max_path_length, Some(2));
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_matpreview_xml() {
    let s = mesh_scene("matpreview/matpreview.xml", 3);
    assert_eq!((s.film.width, s.film.height), (683, 512));
    assert!(matches!(s.lights[0], LightDesc::EnvMap { scale: 3.0, .. }));
}
