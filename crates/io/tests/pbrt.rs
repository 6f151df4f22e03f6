//! The pbrt-v4 loader: tokenizer, every supported directive, shape, material, texture and
//! light on small scenes, errors with positions, and the Cornell box twin of the Mitsuba scene.

use scene::microfacet::Distribution;
use std::fs;
use std::path::{Path, PathBuf};

use io::pbrt::tokenizer::{Pos, TokenKind, tokenize};
use io::pbrt::{color, envmap};
use math::{Vec2, Vec3};
use scene::desc::{FilterDesc, Geometry, LightDesc, MeshData, Projection, SceneDescription};
use scene::light::equal_area;
use scene::material::Material;
use scene::texture::Texture;
use spectrum::Rgb;

/// A fresh, empty directory for one test under Cargo's per-target temp dir.
fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-pbrt-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// The camera and film that most tests do not care about.
const HEADER: &str = "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nWorldBegin\n";

/// Writes `text` to `<test dir>/scene.pbrt` and loads it.
fn load_text(test: &str, text: &str) -> Result<SceneDescription, io::SceneError> {
    let dir = scratch_dir(test);
    let path = dir.join("scene.pbrt");
    fs::write(&path, text).unwrap();
    io::pbrt::load(&path)
}

fn load_ok(test: &str, text: &str) -> SceneDescription {
    load_text(test, text).unwrap_or_else(|e| panic!("{e}"))
}

/// Loads a scene that must fail; returns the message (`file:line:column: …`).
fn load_err(test: &str, text: &str) -> String {
    match load_text(test, text) {
        Ok(_) => panic!("{test}: expected an error"),
        Err(e) => e.to_string(),
    }
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

fn assert_close(a: Vec3, b: Vec3, tol: f32) {
    assert!(close(a, b, tol), "{a} vs {b}");
}

fn mesh(d: &SceneDescription, i: usize) -> &MeshData {
    match &d.shapes[i].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("shape {i} is not a mesh: {g:?}"),
    }
}

/// World-space corners of triangle `t`.
fn corners(m: &MeshData, t: usize) -> [Vec3; 3] {
    m.triangles[t].map(|i| m.positions[i as usize])
}

fn normal(m: &MeshData, t: usize) -> Vec3 {
    let [a, b, c] = corners(m, t);
    (b - a).cross(c - a)
}

fn front_material(m: &Material) -> &Material {
    match m {
        Material::TwoSided { front, back: None } => front,
        other => panic!("expected a two-sided material, got {other:?}"),
    }
}

fn constant(t: &Texture) -> Rgb {
    t.as_constant().unwrap_or_else(|| panic!("not constant: {t:?}"))
}

fn rgb_close(a: Rgb, b: Rgb, tol: f32) -> bool {
    (a.r - b.r).abs() <= tol && (a.g - b.g).abs() <= tol && (a.b - b.b).abs() <= tol
}

const TRIANGLE: &str = "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2]\n";

// ----- tokenizer ---------------------------------------------------------------------------

#[test]
fn tokenizer_strings_numbers_comments_and_positions() {
    let text = "Shape \"tri mesh\" # a comment \"not a string\" [9]\n  [1e-3 -.5 +2 3. 7 -1.5E+2] \"a\\\"b\"";
    let tokens = tokenize(Path::new("t.pbrt"), text).unwrap();
    let kinds: Vec<TokenKind> = tokens.iter().map(|t| t.kind.clone()).collect();
    assert_eq!(
        kinds,
        vec![
            TokenKind::Word("Shape".into()),
            TokenKind::Str("tri mesh".into()),
            TokenKind::Open,
            TokenKind::Num(0.001),
            TokenKind::Num(-0.5),
            TokenKind::Num(2.0),
            TokenKind::Num(3.0),
            TokenKind::Num(7.0),
            TokenKind::Num(-150.0),
            TokenKind::Close,
            TokenKind::Str("a\"b".into()),
        ]
    );
    let positions: Vec<Pos> = tokens.iter().map(|t| t.pos).collect();
    assert_eq!(positions[0], Pos { line: 1, column: 1 });
    assert_eq!(positions[1], Pos { line: 1, column: 7 });
    assert_eq!(positions[2], Pos { line: 2, column: 3 });
    assert_eq!(positions[3], Pos { line: 2, column: 4 });
    assert_eq!(positions[4], Pos { line: 2, column: 9 });
    assert_eq!(positions[10], Pos { line: 2, column: 30 });
}

#[test]
fn tokenizer_reports_positions_of_bad_input() {
    let e = tokenize(Path::new("t.pbrt"), "Shape\n  \"open").unwrap_err().to_string();
    assert_eq!(e, "t.pbrt:2:3: unterminated string");
    let e = tokenize(Path::new("t.pbrt"), "Translate 1.2.3 0 0").unwrap_err().to_string();
    assert_eq!(e, "t.pbrt:1:11: bad number '1.2.3'");
    let e = tokenize(Path::new("t.pbrt"), "Translate 1 0 0\n @").unwrap_err().to_string();
    assert_eq!(e, "t.pbrt:2:2: unexpected character '@'");
    let e = tokenize(Path::new("t.pbrt"), "Scale 1 - 2").unwrap_err().to_string();
    assert_eq!(e, "t.pbrt:1:9: bad number '-'");
}

// ----- camera, film, filter, integrator ------------------------------------------------------

#[test]
fn lookat_camera_axes_and_shorter_axis_fov() {
    // 200×100: pbrt's fov spans the vertical axis; tan(h/2) = 2·tan(15°).
    let d = load_ok(
        "camera_landscape",
        "LookAt 1 2 3  1 2 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\nWorldBegin\n",
    );
    let c = d.camera;
    assert_close(c.position, Vec3::new(1.0, 2.0, 3.0), 1e-6);
    assert_close(c.forward, Vec3::new(0.0, 0.0, -1.0), 1e-6);
    assert_close(c.up, Vec3::new(0.0, 1.0, 0.0), 1e-6);
    // pbrt's camera +x is normalize(up × dir) = (0,1,0) × (0,0,−1) = (−1, 0, 0), the image's right.
    assert_close(c.right, Vec3::new(-1.0, 0.0, 0.0), 1e-6);
    let expected = 2.0 * (2.0 * 15f64.to_radians().tan()).atan().to_degrees();
    match c.projection {
        Projection::Perspective { horizontal_fov_degrees } => {
            assert!((f64::from(horizontal_fov_degrees) - expected).abs() < 1e-4, "{horizontal_fov_degrees}")
        }
        p => panic!("{p:?}"),
    }
    assert_eq!((d.film.width, d.film.height), (200, 100));
    // Portrait: the horizontal axis is the shorter one, fov unchanged.
    let d = load_ok(
        "camera_portrait",
        "Camera \"perspective\" \"float fov\" 30\nFilm \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 200\nWorldBegin\n",
    );
    assert_eq!(d.camera.projection, Projection::Perspective { horizontal_fov_degrees: 30.0 });
}

#[test]
fn mirrored_camera_keeps_its_handedness() {
    let d = load_ok(
        "camera_mirror",
        &format!("Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n{HEADER}"),
    );
    assert_close(d.camera.right, Vec3::X, 1e-6);
    assert_close(d.camera.forward, -Vec3::Z, 1e-6);
    // Default fov 90 on a square film.
    assert_eq!(d.camera.projection, Projection::Perspective { horizontal_fov_degrees: 90.0 });
}

#[test]
fn orthographic_and_thin_lens_cameras() {
    let d = load_ok(
        "camera_ortho",
        "Scale 2 2 2\nCamera \"orthographic\"\nFilm \"rgb\" \"integer xresolution\" 300 \"integer yresolution\" 100\nWorldBegin\n",
    );
    // Screen window [-3, 3] × [-1, 1] in camera units; a camera unit is 0.5 world units.
    match d.camera.projection {
        Projection::Orthographic { width } => assert!((width - 3.0).abs() < 1e-5, "{width}"),
        p => panic!("{p:?}"),
    }
    let d = load_ok(
        "camera_lens",
        &format!(
            "Camera \"perspective\" \"float fov\" 40 \"float lensradius\" 0.1 \"float focaldistance\" 7\n{HEADER}"
        ),
    );
    assert_eq!(
        d.camera.projection,
        Projection::ThinLens { horizontal_fov_degrees: 40.0, aperture_radius: 0.1, focus_distance: 7.0 }
    );
}

#[test]
fn filters_and_integrator_depth() {
    let filter = |t: &str| load_ok("filters", &format!("PixelFilter {t}\n{HEADER}")).film.filter;
    assert_eq!(filter("\"box\""), FilterDesc::Box);
    assert_eq!(filter("\"triangle\""), FilterDesc::Tent { radius: 2.0 });
    assert_eq!(filter("\"triangle\" \"float xradius\" 1 \"float yradius\" 1"), FilterDesc::Tent { radius: 1.0 });
    assert_eq!(filter("\"gaussian\""), FilterDesc::Gaussian { stddev: 0.5, radius: 1.5 });
    assert_eq!(
        filter("\"gaussian\" \"float sigma\" 0.25 \"float xradius\" 1 \"float yradius\" 1"),
        FilterDesc::Gaussian { stddev: 0.25, radius: 1.0 }
    );
    let e = load_err("filters_bad", &format!("PixelFilter \"gaussian\" \"float xradius\" 1\n{HEADER}"));
    assert!(e.contains("scene.pbrt:1:") && e.contains("xradius"), "{e}");
    let e = load_err("filters_mitchell", &format!("PixelFilter \"mitchell\"\n{HEADER}"));
    assert!(e.contains("scene.pbrt:1:13:") && e.contains("not supported"), "{e}");
    // maxdepth counts bounces; segments = maxdepth + 1; pbrt's default maxdepth is 5.
    let d = load_ok("integrator", &format!("Integrator \"volpath\" \"integer maxdepth\" 7\n{HEADER}"));
    assert_eq!(d.max_path_length, Some(8));
    assert_eq!(load_ok("integrator_default", HEADER).max_path_length, Some(6));
}

// ----- transformations ---------------------------------------------------------------------

#[test]
fn transform_directives_compose_like_pbrt() {
    let text = format!(
        "{HEADER}\
         AttributeBegin\n Translate 1 2 3\n Rotate 90 0 0 1\n Scale 2 2 2\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n Translate 9 9 9\n ConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 1 1]\n Identity\n Translate 0 0 -1\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n Translate 0 0 4\n CoordinateSystem \"lifted\"\nAttributeEnd\n\
         AttributeBegin\n Scale 3 3 3\n CoordSysTransform \"lifted\"\n {TRIANGLE}AttributeEnd\n\
         {TRIANGLE}"
    );
    let d = load_ok("transforms", &text);
    // T(1,2,3)·Rz(90°)·S(2): x ↦ (1,2,3) + Rz(2x); Rz(90°) maps (1,0,0) to (0,1,0), (0,1,0) to (−1,0,0).
    let m = mesh(&d, 0);
    assert_close(m.positions[0], Vec3::new(1.0, 2.0, 3.0), 1e-6);
    assert_close(m.positions[1], Vec3::new(1.0, 4.0, 3.0), 1e-6);
    assert_close(m.positions[2], Vec3::new(-1.0, 2.0, 3.0), 1e-6);
    // Column-major list: translation in elements 12–14.
    assert_close(mesh(&d, 1).positions[1], Vec3::new(6.0, 6.0, 7.0), 1e-6);
    // Identity discards the earlier Translate and ConcatTransform.
    assert_close(mesh(&d, 2).positions[1], Vec3::new(1.0, 0.0, -1.0), 1e-6);
    assert_close(mesh(&d, 3).positions[2], Vec3::new(0.0, 1.0, 4.0), 1e-6);
    // After the blocks the transformation is the identity again.
    assert_close(mesh(&d, 4).positions[1], Vec3::new(1.0, 0.0, 0.0), 1e-6);
}

#[test]
fn orientation_follows_reverse_orientation_and_handedness() {
    let text = format!(
        "{HEADER}{TRIANGLE}\
         AttributeBegin\n ReverseOrientation\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n Scale 1 1 -1\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n Scale 1 1 -1\n ReverseOrientation\n {TRIANGLE}AttributeEnd\n\
         AttributeBegin\n ReverseOrientation\n Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 -1 0 0 -1 0 0 -1]\nAttributeEnd\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 -1 0 0 -1 0 0 -1]\n"
    );
    let d = load_ok("orientation", &text);
    let z = |i: usize| normal(mesh(&d, i), 0).z.signum();
    // (p1 − p0) × (p2 − p0) = +z for the plain triangle (a Scale 1 1 −1 leaves it in place).
    assert_eq!([z(0), z(1), z(2), z(3)], [1.0, -1.0, -1.0, 1.0]);
    // With normals the triangle faces them; ReverseOrientation negates the normals first.
    assert_eq!(z(5), -1.0);
    assert_eq!(z(4), 1.0);
    assert_close(mesh(&d, 4).normals[0], Vec3::Z, 1e-6);
}

// ----- shapes ------------------------------------------------------------------------------

#[test]
fn trianglemesh_with_normals_and_uvs() {
    let text = format!(
        "{HEADER}Translate 0 0 2\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"integer indices\" [0 1 2 0 2 3]\n\
         \"normal N\" [0 0 2 0 0 2 0 0 2 0 0 2] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
    );
    let d = load_ok("trianglemesh", &text);
    let m = mesh(&d, 0);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_close(m.positions[2], Vec3::new(1.0, 1.0, 2.0), 1e-6);
    assert_close(m.normals[3], Vec3::Z, 1e-6);
    assert_eq!(m.uvs[2], Vec2::new(1.0, 1.0));
    // Three vertices need no indices.
    let d =
        load_ok("trianglemesh_noindex", &format!("{HEADER}Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n"));
    assert_eq!(mesh(&d, 0).triangles, vec![[0, 1, 2]]);
}

#[test]
fn bilinear_patches_become_two_triangles() {
    // p00 p10 p01 p11 = (0,0) (2,0) (0,1) (2,1): boundary p00 p10 p11 p01.
    let d = load_ok("bilinear", &format!("{HEADER}Shape \"bilinearmesh\" \"point3 P\" [0 0 0 2 0 0 0 1 0 2 1 0]\n"));
    let m = mesh(&d, 0);
    assert_eq!(m.triangles, vec![[0, 1, 3], [0, 3, 2]]);
    // pbrt's normal is (p10 − p00) × (p01 − p00) = +z; total area 2.
    let area: f32 = (0..2).map(|t| 0.5 * normal(m, t).length()).sum();
    assert!((area - 2.0).abs() < 1e-6);
    assert!(normal(m, 0).z > 0.0 && normal(m, 1).z > 0.0);
    let e = load_err(
        "bilinear_bad",
        &format!("{HEADER}Shape \"bilinearmesh\" \"point3 P\" [0 0 0 2 0 0 0 1 0 2 1 0] \"integer indices\" [0 1 2]\n"),
    );
    assert!(e.contains("scene.pbrt:3:") && e.contains("multiple of 4"), "{e}");
}

#[test]
fn loop_subdivision_surfaces_are_refined_at_load() {
    // A tetrahedron, translated: levels 2 make 4 · 16 triangles; the limit surface lies inside
    // the control tetrahedron (around its centre, here (5, 0, 0)) and every normal points away
    // from the centre.
    let tetrahedron = "\"point3 P\" [1 1 1 1 -1 -1 -1 1 -1 -1 -1 1] \"integer indices\" [0 1 2 0 3 1 0 2 3 1 3 2]";
    let d = load_ok(
        "loopsubdiv",
        &format!("{HEADER}Translate 5 0 0\nShape \"loopsubdiv\" \"integer levels\" 2 {tetrahedron}\n"),
    );
    let m = mesh(&d, 0);
    assert_eq!(m.triangles.len(), 64);
    assert_eq!(m.normals.len(), m.positions.len());
    let centre = Vec3::new(5.0, 0.0, 0.0);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!((*p - centre).length() < 3f32.sqrt() && n.dot(*p - centre) > 0.0, "{p} {n}");
    }
    // The default is 3 levels.
    let d = load_ok("loopsubdiv_default", &format!("{HEADER}Shape \"loopsubdiv\" {tetrahedron}\n"));
    assert_eq!(mesh(&d, 0).triangles.len(), 256);
    let e = load_err(
        "loopsubdiv_bad",
        &format!("{HEADER}Shape \"loopsubdiv\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2 0 1 2]\n"),
    );
    assert!(e.contains("scene.pbrt:3:") && e.contains("non-manifold edge"), "{e}");
}

#[test]
fn spheres_and_disks() {
    let text = format!(
        "{HEADER}AttributeBegin\n Translate 1 2 3\n Rotate 30 1 1 0\n Scale 2 2 2\n Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n\
         AttributeBegin\n ReverseOrientation\n Shape \"sphere\"\nAttributeEnd\n\
         AttributeBegin\n Translate 0 1 0\n Rotate -90 1 0 0\n Shape \"disk\" \"float radius\" 2 \"float height\" 0.5\nAttributeEnd\n"
    );
    let d = load_ok("spheres", &text);
    match d.shapes[0].geometry {
        Geometry::Sphere { center, radius, flip_normals } => {
            assert_close(center, Vec3::new(1.0, 2.0, 3.0), 1e-6);
            assert!((radius - 1.0).abs() < 1e-6);
            assert!(!flip_normals);
        }
        ref g => panic!("{g:?}"),
    }
    assert!(matches!(d.shapes[1].geometry, Geometry::Sphere { radius: 1.0, flip_normals: true, .. }));
    // Rotate −90° about x maps +z to +y and +y to −z.
    match d.shapes[2].geometry {
        Geometry::Disk { center, axis_u, axis_v, flip_normals } => {
            assert_close(center, Vec3::new(0.0, 1.5, 0.0), 1e-6);
            assert_close(axis_u, Vec3::new(2.0, 0.0, 0.0), 1e-6);
            assert_close(axis_v, Vec3::new(0.0, 0.0, -2.0), 1e-6);
            assert_close(axis_u.cross(axis_v).normalize(), Vec3::Y, 1e-6);
            assert!(!flip_normals);
        }
        ref g => panic!("{g:?}"),
    }
    let e = load_err("sphere_skew", &format!("{HEADER}Scale 1 2 1\nShape \"sphere\"\n"));
    assert!(e.contains("scene.pbrt:4:1:") && e.contains("non-uniform"), "{e}");
    let e = load_err("sphere_partial", &format!("{HEADER}Shape \"sphere\" \"float zmax\" 0.5\n"));
    assert!(e.contains("scene.pbrt:3:16:") && e.contains("partial"), "{e}");
}

#[test]
fn plymesh_is_read_and_transformed() {
    let dir = scratch_dir("plymesh");
    fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    fs::write(
        dir.join("scene.pbrt"),
        format!("{HEADER}Translate 0 0 5\nShape \"plymesh\" \"string filename\" \"tri.ply\"\n"),
    )
    .unwrap();
    let d = io::pbrt::load(&dir.join("scene.pbrt")).unwrap();
    let m = mesh(&d, 0);
    assert_eq!(m.triangles.len(), 1);
    assert_close(m.positions[1], Vec3::new(1.0, 0.0, 5.0), 1e-6);
}

#[test]
fn plymesh_missing_file_is_an_error() {
    let e = load_err("plymesh_missing", &format!("{HEADER}Shape \"plymesh\" \"string filename\" \"nope.ply\"\n"));
    assert!(e.contains("scene.pbrt:3:17:") && e.contains("nope.ply"), "{e}");
}

// ----- materials ---------------------------------------------------------------------------

#[test]
fn diffuse_default_and_named_materials() {
    let text = format!(
        "{HEADER}{TRIANGLE}\
         Material \"diffuse\" \"rgb reflectance\" [0.1 0.2 0.3]\n{TRIANGLE}\
         MakeNamedMaterial \"grey\" \"string type\" \"diffuse\" \"float reflectance\" 0.25\n\
         AttributeBegin\n NamedMaterial \"grey\"\n {TRIANGLE} {TRIANGLE}AttributeEnd\n{TRIANGLE}"
    );
    let d = load_ok("diffuse", &text);
    let reflectance = |i: usize| match front_material(&d.materials[d.shapes[i].material as usize]) {
        Material::Diffuse { reflectance } => constant(reflectance),
        m => panic!("{m:?}"),
    };
    assert_eq!(reflectance(0), Rgb::splat(0.5));
    assert_eq!(reflectance(1), Rgb::new(0.1, 0.2, 0.3));
    assert_eq!(reflectance(2), Rgb::splat(0.25));
    // A named material is stored once however often it is used.
    assert_eq!(d.shapes[2].material, d.shapes[3].material);
    // AttributeEnd restores the material of the enclosing block.
    assert_eq!(d.shapes[4].material, d.shapes[1].material);
    let e = load_err("diffuse_bad", &format!("{HEADER}Material \"diffuse\" \"rgb reflectance\" [1.5 0 0]\n"));
    assert!(e.contains("scene.pbrt:3:20:") && e.contains("reflectance = (1.5, 0, 0) is outside [0, 1]"), "{e}");
}

#[test]
fn conductors() {
    let text = format!(
        "{HEADER}Material \"conductor\"\n{TRIANGLE}\
         Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\" \"float roughness\" 0.04\n{TRIANGLE}\
         Material \"conductor\" \"rgb eta\" [0.2 0.3 0.4] \"rgb k\" [3 2 1] \"float uroughness\" 0.09 \"float vroughness\" 0.01 \"bool remaproughness\" false\n{TRIANGLE}\
         Material \"conductor\" \"rgb reflectance\" [0.9 0.5 0.1]\n{TRIANGLE}"
    );
    let d = load_ok("conductor", &text);
    let m = |i: usize| front_material(&d.materials[d.shapes[i].material as usize]).clone();
    // pbrt-v4's default is copper; red η is interpolated in pbrt's Cu table at 611.3 nm between
    // (604.800842 nm, 0.351250) and (619.920898 nm, 0.272000).
    let cu_eta_red = 0.351250 + (0.272000 - 0.351250) * (611.3 - 604.800842) / (619.920898 - 604.800842);
    match m(0) {
        Material::Conductor { eta, k, .. } => {
            assert!((f64::from(eta.r) - cu_eta_red).abs() < 1e-6, "{eta:?}");
            // Green k between (539.061646, 2.583) and (551.040771, 2.5765) at 549.1 nm.
            let k_green = 2.583 + (2.5765 - 2.583) * (549.1 - 539.061646) / (551.040771 - 539.061646);
            assert!((f64::from(k.g) - k_green).abs() < 1e-6, "{k:?}");
        }
        other => panic!("{other:?}"),
    }
    // remaproughness (default): α = √roughness.
    match m(1) {
        Material::RoughConductor { distribution: Distribution::Ggx, alpha_u, alpha_v, eta, .. } => {
            assert!((alpha_u - 0.2).abs() < 1e-6 && (alpha_v - 0.2).abs() < 1e-6);
            assert!(
                (eta.b - (1.426000 + (1.345875 - 1.426000) * (464.3 - 459.200653) / (467.864838 - 459.200653)) as f32)
                    .abs()
                    < 1e-6
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        m(2),
        Material::RoughConductor {
            distribution: Distribution::Ggx,
            alpha_u: 0.09,
            alpha_v: 0.01,
            eta: Rgb::new(0.2, 0.3, 0.4),
            k: Rgb::new(3.0, 2.0, 1.0),
            specular_reflectance: Texture::Constant(Rgb::WHITE)
        }
    );
    // "reflectance": the Fresnel reflectance at normal incidence, ((η−1)² + k²)/((η+1)² + k²),
    // equals the given value.
    match m(3) {
        Material::Conductor { eta, k, .. } => {
            for (e, k, r) in [(eta.r, k.r, 0.9), (eta.g, k.g, 0.5), (eta.b, k.b, 0.1)] {
                let f = ((e - 1.0).powi(2) + k * k) / ((e + 1.0).powi(2) + k * k);
                assert!((f - r).abs() < 1e-5, "{f} vs {r}");
            }
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn dielectrics_mix_and_unsupported_materials() {
    let text = format!(
        "{HEADER}Material \"dielectric\" \"float eta\" 1.33\n{TRIANGLE}\
         Material \"dielectric\" \"spectrum eta\" \"glass-BK7\" \"float roughness\" 0.01\n{TRIANGLE}\
         Material \"thindielectric\"\n{TRIANGLE}\
         MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\
         MakeNamedMaterial \"b\" \"string type\" \"dielectric\"\n\
         Material \"mix\" \"string materials\" [\"a\" \"b\"] \"float amount\" 0.3\n{TRIANGLE}"
    );
    let d = load_ok("dielectric", &text);
    let m = |i: usize| d.materials[d.shapes[i].material as usize].clone();
    let white = Texture::Constant(Rgb::WHITE);
    assert_eq!(
        m(0),
        Material::Dielectric {
            int_ior: 1.33,
            ext_ior: 1.0,
            specular_reflectance: white.clone(),
            specular_transmittance: white.clone(),
            dispersion: None
        }
    );
    match m(1) {
        Material::RoughDielectric { distribution: Distribution::Ggx, alpha_u, int_ior, .. } => {
            assert!((alpha_u - 0.1).abs() < 1e-6);
            assert!((int_ior - 1.5168).abs() < 1e-4);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(m(2), Material::ThinDielectric { int_ior: 1.5, ext_ior: 1.0, .. }));
    match m(3) {
        Material::Blend { weight, first, second } => {
            assert_eq!(constant(&weight), Rgb::splat(0.3));
            assert!(matches!(front_material(&first), Material::Diffuse { .. }));
            assert!(matches!(*second, Material::Dielectric { int_ior: 1.5, .. }));
        }
        other => panic!("{other:?}"),
    }
    let e = load_err("measured", &format!("{HEADER}Material \"measured\"\n"));
    assert_eq!(e.rsplit_once("scene.pbrt:").unwrap().1, "3:1: material \"measured\" is not supported");
    // An index-matched boundary (see tests/media.rs).
    let d = load_ok("interface", &format!("{HEADER}Material \"interface\"\n"));
    assert_eq!(d.media.null_materials, vec![0]);
    let e = load_err("unknown_material", &format!("{HEADER}\nMaterial \"velvet\"\n"));
    assert!(e.contains("scene.pbrt:4:1:") && e.contains("unknown material type \"velvet\""), "{e}");
}

// ----- textures ----------------------------------------------------------------------------

#[test]
fn checkerboard_matches_pbrts_rule() {
    let text = format!(
        "{HEADER}Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 3 \"float udelta\" 0.3\n\
         \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n\
         Material \"diffuse\" \"texture reflectance\" \"c\"\n{TRIANGLE}"
    );
    let d = load_ok("checkerboard", &text);
    let Material::Diffuse { reflectance } = front_material(&d.materials[d.shapes[0].material as usize]) else {
        panic!()
    };
    // pbrt: tex1 where floor(4u + 0.3) + floor(3v) is even.
    let mut checked = 0;
    for i in 0..37 {
        for j in 0..41 {
            let (u, v) = (i as f32 / 37.0 + 0.013, j as f32 / 41.0 + 0.007);
            let (s, t) = (4.0 * u + 0.3, 3.0 * v);
            if (s - s.round()).abs() < 1e-3 || (t - t.round()).abs() < 1e-3 {
                continue; // on a square's edge
            }
            let even = (s.floor() as i32 + t.floor() as i32).rem_euclid(2) == 0;
            let expected = if even { Rgb::new(1.0, 0.0, 0.0) } else { Rgb::new(0.0, 0.0, 1.0) };
            assert_eq!(reflectance.eval(Vec2::new(u, v)), expected, "u {u} v {v}");
            checked += 1;
        }
    }
    assert!(checked > 1400);
}

#[test]
fn imagemap_orientation_scale_and_errors() {
    let dir = scratch_dir("imagemap");
    // 2×2 linear image: top row (1, 2), bottom row (3, 4) in the red channel.
    let image = io::Image::from_fn(2, 2, |x, y| [(1 + x + 2 * y) as f32, 0.0, 0.0]);
    io::write_image(&dir.join("tex.pfm"), &image, &io::WriteOptions::default()).unwrap();
    fs::write(
        dir.join("scene.pbrt"),
        format!(
            "{HEADER}Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex.pfm\" \"float scale\" 0.1\n\
             Material \"conductor\" \"texture reflectance\" \"t\"\n{TRIANGLE}"
        ),
    )
    .unwrap();
    let d = io::pbrt::load(&dir.join("scene.pbrt")).unwrap();
    let Material::Conductor { specular_reflectance, .. } = front_material(&d.materials[d.shapes[0].material as usize])
    else {
        panic!()
    };
    // pbrt looks up t = 0 at the image's bottom row: (u, v) = (0.25, 0.25) is the bottom-left texel.
    let at = |u: f32, v: f32| specular_reflectance.eval(Vec2::new(u, v)).r;
    assert!((at(0.25, 0.25) - 0.3).abs() < 1e-6);
    assert!((at(0.75, 0.25) - 0.4).abs() < 1e-6);
    assert!((at(0.25, 0.75) - 0.1).abs() < 1e-6);
    assert!((at(0.75, 0.75) - 0.2).abs() < 1e-6);
    let e = load_err(
        "imagemap_missing",
        &format!("{HEADER}Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"no.png\"\n"),
    );
    assert!(e.contains("scene.pbrt:3:35:") && e.contains("no.png"), "{e}");
    let e = load_err("texture_fbm", &format!("{HEADER}Texture \"t\" \"float\" \"fbm\"\n"));
    assert!(e.contains("scene.pbrt:3:21:") && e.contains("\"fbm\" is not supported"), "{e}");
}

// ----- lights ------------------------------------------------------------------------------

#[test]
fn projection_light_follows_pbrt_v4() {
    let dir = scratch_dir("projection");
    // A wide 4×2 image: red 1 + column + 4·row (row 0 at the top).
    let image = io::Image::from_fn(4, 2, |x, y| [(1 + x + 4 * y) as f32, 0.5, 0.0]);
    io::write_image(&dir.join("proj.pfm"), &image, &io::WriteOptions::default()).unwrap();
    let scene = |extra: &str| {
        fs::write(
            dir.join("scene.pbrt"),
            format!(
                "{HEADER}AttributeBegin\nTranslate 0 1 0\nRotate 90 0 1 0\n\
                 LightSource \"projection\" \"string filename\" \"proj.pfm\" {extra}\nAttributeEnd\n"
            ),
        )
        .unwrap();
        io::pbrt::load(&dir.join("scene.pbrt"))
    };
    let d = scene("\"float fov\" 60 \"float scale\" 2").unwrap();
    let light = scene::Light::from_desc(&d.lights[0]).unwrap();
    let sphere = scene::BoundingSphere { center: Vec3::ZERO, radius: 10.0 };
    // Light space: +z is world +x (Rotate 90 about y), +y is world +y, +x is world −z. pbrt's
    // screen window for a wide image is [−2, 2]×[−1, 1] times tan(30°) (fov on the short axis);
    // the image's left column is light −x, its top row light +y.
    let tan = 30f32.to_radians().tan();
    for (column, row) in [(0, 0), (3, 0), (1, 1), (2, 1)] {
        let sx = -2.0 + (column as f32 + 0.5) * 1.0;
        let sy = -1.0 + (row as f32 + 0.5) * 1.0;
        // Light-space direction through the texel centre (y flipped: row 0 is up).
        let (lx, ly) = (sx * tan, -sy * tan);
        let world = Vec3::new(1.0, ly, -lx).normalize();
        let distance = 3.0;
        let receiver = Vec3::new(0.0, 1.0, 0.0) + world * distance;
        let sample = light.sample_direct(receiver, [0.5, 0.5], &sphere).unwrap();
        let expected = 2.0 * (1 + column + 4 * row) as f32;
        // I = scale·E (no cos³ falloff); the direct pdf carries the 1/d².
        assert!((sample.radiance.r - expected).abs() < 1e-4 * expected, "texel ({column}, {row}): {sample:?}");
        assert!((sample.radiance.g - 1.0).abs() < 1e-4 && (sample.direct_pdf.0 - distance * distance).abs() < 1e-3);
    }
    // Beyond the short axis' field of view: nothing.
    let above = Vec3::new(0.0, 1.0, 0.0) + Vec3::new(1.0, 0.7, 0.0).normalize() * 3.0;
    assert!(light.sample_direct(above, [0.5, 0.5], &sphere).is_none());
    // "power": the flux Σ luminance·cos³θ·A / texels (pbrt's normalisation) becomes 10 W.
    let d = scene("\"float fov\" 60 \"float power\" 10").unwrap();
    let power = scene::Light::from_desc(&d.lights[0]).unwrap().power(&sphere);
    assert!((power - 10.0).abs() < 1e-3 * 10.0, "power {power}");
    let e = scene("\"float fov\" 190").unwrap_err().to_string();
    assert!(e.contains("fov 190"), "{e}");
    fs::write(dir.join("scene.pbrt"), format!("{HEADER}LightSource \"projection\"\n")).unwrap();
    let e = io::pbrt::load(&dir.join("scene.pbrt")).unwrap_err().to_string();
    assert!(e.contains("scene.pbrt:3:") && e.contains("\"filename\" is required"), "{e}");
}

#[test]
fn goniometric_light_follows_pbrt_v4() {
    let dir = scratch_dir("goniometric");
    // A 4×4 image whose texel (x, y) has channel mean (1.5 + x + 4·y)/3 (row 0 at the top).
    let image = io::Image::from_fn(4, 4, |x, y| [(1 + x + 4 * y) as f32, 0.5, 0.0]);
    io::write_image(&dir.join("gonio.pfm"), &image, &io::WriteOptions::default()).unwrap();
    let scene = |extra: &str| {
        fs::write(
            dir.join("scene.pbrt"),
            format!(
                "{HEADER}AttributeBegin\nTranslate 0 1 0\nRotate 90 0 1 0\n\
                 LightSource \"goniometric\" \"string filename\" \"gonio.pfm\" {extra}\nAttributeEnd\n"
            ),
        )
        .unwrap();
        io::pbrt::load(&dir.join("scene.pbrt"))
    };
    let d = scene("\"rgb I\" [1 0.5 0.25] \"float scale\" 2").unwrap();
    let light = scene::Light::from_desc(&d.lights[0]).unwrap();
    let sphere = scene::BoundingSphere { center: Vec3::ZERO, radius: 10.0 };
    // Light space: x is world −z, y world +y, z world +x (Rotate 90 about y). pbrt-v4 swaps the
    // light's y and z: the map's (x, y, z) is light (x, z, y) = world (−z, +x, +y). The map's
    // centre (+z) is world +y, the middle of its right edge (+x) world −z, of its far edge
    // (+y, v = 1) world +x, its corners (−z) world −y.
    let map_to_world = |m: Vec3| Vec3::new(m.y, m.z, -m.x).normalize();
    let cases = [
        (Vec3::new(0.01, 0.01, 1.0), (2, 2)),
        (Vec3::new(-0.01, -0.01, 1.0), (1, 1)),
        (Vec3::new(1.0, 0.01, 0.0), (3, 2)),
        (Vec3::new(0.01, 1.0, 0.0), (2, 3)),
        (Vec3::new(0.01, -0.01, -1.0), (3, 0)),
    ];
    for (m, (x, y)) in cases {
        let distance = 3.0;
        let receiver = Vec3::new(0.0, 1.0, 0.0) + map_to_world(m) * distance;
        let sample = light.sample_direct(receiver, [0.5, 0.5], &sphere).unwrap();
        let mean = (1.5 + (x + 4 * y) as f32) / 3.0;
        let expected = Rgb::new(2.0, 1.0, 0.5) * mean;
        assert!((sample.radiance.r - expected.r).abs() < 1e-4 * expected.r, "{m}, texel ({x}, {y}): {sample:?}");
        assert!((sample.radiance.b - expected.b).abs() < 1e-4 * expected.b, "{m}: {sample:?}");
        assert!((sample.direct_pdf.0 - distance * distance).abs() < 1e-3);
    }
    // "power": 4π · mean(image) becomes 10 W (the white I has luminance 1).
    let d = scene("\"float power\" 10").unwrap();
    let power = scene::Light::from_desc(&d.lights[0]).unwrap().power(&sphere);
    assert!((power - 10.0).abs() < 1e-3 * 10.0, "power {power}");
    // A non-square image and a missing filename are errors with file:line.
    let wide = io::Image::from_fn(4, 2, |_, _| [1.0, 1.0, 1.0]);
    io::write_image(&dir.join("wide.pfm"), &wide, &io::WriteOptions::default()).unwrap();
    fs::write(
        dir.join("scene.pbrt"),
        format!("{HEADER}LightSource \"goniometric\" \"string filename\" \"wide.pfm\"\n"),
    )
    .unwrap();
    let e = io::pbrt::load(&dir.join("scene.pbrt")).unwrap_err().to_string();
    assert!(e.contains("scene.pbrt:3:") && e.contains("4×2") && e.contains("square"), "{e}");
    fs::write(dir.join("scene.pbrt"), format!("{HEADER}LightSource \"goniometric\"\n")).unwrap();
    let e = io::pbrt::load(&dir.join("scene.pbrt")).unwrap_err().to_string();
    assert!(e.contains("scene.pbrt:3:") && e.contains("\"filename\" is required"), "{e}");
}

#[test]
fn point_spot_and_distant_lights() {
    let text = format!(
        "{HEADER}Translate 1 0 0\n\
         LightSource \"point\" \"point3 from\" [0 2 0] \"rgb I\" [1 2 3] \"float scale\" 2\n\
         LightSource \"spot\" \"point3 from\" [0 0 0] \"point3 to\" [0 -3 0] \"float coneangle\" 40 \"float conedeltaangle\" 10 \"rgb I\" [5 5 5]\n\
         Rotate 90 0 0 1\n\
         LightSource \"distant\" \"point3 from\" [0 0 0] \"point3 to\" [1 0 0] \"rgb L\" [0.5 0.5 0.5]\n"
    );
    let d = load_ok("lights", &text);
    assert_eq!(
        d.lights[0],
        LightDesc::Point { position: Vec3::new(1.0, 2.0, 0.0), intensity: Rgb::new(2.0, 4.0, 6.0) }
    );
    match d.lights[1] {
        LightDesc::Spot { position, direction, intensity, cutoff_degrees, beam_width_degrees, texture: None } => {
            assert_close(position, Vec3::new(1.0, 0.0, 0.0), 1e-6);
            assert_close(direction, -Vec3::Y, 1e-6);
            assert_eq!(intensity, Rgb::splat(5.0));
            assert_eq!((cutoff_degrees, beam_width_degrees), (40.0, 30.0));
        }
        ref l => panic!("{l:?}"),
    }
    match d.lights[2] {
        // Light travels from 'from' to 'to'; Rz(90°) turns +x into +y.
        LightDesc::Directional { direction, irradiance } => {
            assert_close(direction, Vec3::Y, 1e-6);
            assert_eq!(irradiance, Rgb::splat(0.5));
        }
        ref l => panic!("{l:?}"),
    }
}

#[test]
fn light_spectra_are_normalised_to_unit_luminance() {
    // Planckian chromaticities (CIE 1931): illuminant A (2856 K) is (0.44757, 0.40745); 6504 K
    // lies at about (0.3135, 0.3237).
    let (x, y) = color::blackbody_chromaticity(2856.0);
    assert!((x - 0.44757).abs() < 2e-3 && (y - 0.40745).abs() < 2e-3, "{x} {y}");
    let (x, y) = color::blackbody_chromaticity(6504.0);
    assert!((x - 0.3135).abs() < 2e-3 && (y - 0.3237).abs() < 2e-3, "{x} {y}");
    let text = format!(
        "{HEADER}LightSource \"point\" \"blackbody I\" [3000] \"float scale\" 5\n\
         LightSource \"point\" \"spectrum I\" \"stdillum-D65\" \"float scale\" 2\n\
         LightSource \"point\" \"spectrum I\" [400 1 700 1]\n\
         AreaLightSource \"diffuse\" \"blackbody L\" [6500]\n{TRIANGLE}"
    );
    let d = load_ok("light_spectra", &text);
    let intensity = |i: usize| match d.lights[i] {
        LightDesc::Point { intensity, .. } => intensity,
        ref l => panic!("{l:?}"),
    };
    // Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B.
    let lum = |c: Rgb| 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    let warm = intensity(0);
    assert!((lum(warm) - 5.0).abs() < 2e-3 * 5.0, "{warm:?}");
    assert!(warm.r > warm.g && warm.g > warm.b, "3000 K is reddish: {warm:?}");
    assert_eq!(intensity(1), Rgb::splat(2.0));
    assert!((lum(intensity(2)) - 1.0).abs() < 2e-3);
    let e = d.shapes[0].emission.unwrap();
    assert!((lum(e) - 1.0).abs() < 2e-3 && rgb_close(e, Rgb::WHITE, 0.05), "{e:?}");
}

#[test]
fn area_lights_apply_to_the_block() {
    let text = format!(
        "{HEADER}AttributeBegin\n AreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"float scale\" 4\n {TRIANGLE}AttributeEnd\n{TRIANGLE}"
    );
    let d = load_ok("area", &text);
    assert_eq!(d.shapes[0].emission, Some(Rgb::new(4.0, 8.0, 12.0)));
    assert_eq!(d.shapes[1].emission, None);
    let e = load_err("area_twosided", &format!("{HEADER}AreaLightSource \"diffuse\" \"bool twosided\" true\n"));
    assert!(e.contains("scene.pbrt:3:27:") && e.contains("two-sided"), "{e}");
}

#[test]
fn infinite_lights_constant_and_resampled_image() {
    let d = load_ok("infinite_constant", &format!("{HEADER}LightSource \"infinite\" \"rgb L\" [0.1 0.2 0.3]\n"));
    assert_eq!(d.lights[0], LightDesc::Constant { radiance: Rgb::new(0.1, 0.2, 0.3) });

    // A square image whose red channel is the z of each texel's direction (pbrt's mapping) and
    // whose green channel is its x: after resampling, each lat-long texel holds the z and x of
    // its own direction in the light's frame, up to interpolation error.
    let side = 64;
    let dir = scratch_dir("infinite_image");
    let image = io::Image::from_fn(side, side, |x, y| {
        let w = equal_area::square_to_sphere(Vec2::new((x as f32 + 0.5) / side as f32, (y as f32 + 0.5) / side as f32));
        [w.z, w.x, 0.5]
    });
    io::write_image(&dir.join("env.pfm"), &image, &io::WriteOptions::default()).unwrap();
    fs::write(
        dir.join("scene.pbrt"),
        format!(
            "{HEADER}Rotate 90 1 0 0\nLightSource \"infinite\" \"string filename\" \"env.pfm\" \"float scale\" 2\n"
        ),
    )
    .unwrap();
    let d = io::pbrt::load(&dir.join("scene.pbrt")).unwrap();
    let LightDesc::EnvMap { image, scale, to_world } = &d.lights[0] else { panic!("{:?}", d.lights[0]) };
    assert_eq!(*scale, 2.0);
    assert_eq!((image.width, image.height), (128, 64));
    // Rx(90°): local y ↦ +z, local z ↦ −y.
    assert_close(to_world[1], Vec3::Z, 1e-6);
    assert_close(to_world[2], -Vec3::Y, 1e-6);
    let mut worst = 0.0f64;
    for j in 0..64 {
        for i in 0..128 {
            let w = envmap::latlong_direction(i, j, 128, 64);
            let px = image.pixel(i as u32, j as u32);
            worst = worst.max((f64::from(px.r) - w[2]).abs()).max((f64::from(px.g) - w[0]).abs());
            assert_eq!(px.b, 0.5);
        }
    }
    // Texels are ~π/64 wide: interpolating a unit vector's component across one errs by
    // at most about (π/64)²/8·(stretch of the mapping) ≈ 0.01.
    assert!(worst < 0.03, "{worst}");
}

// ----- files, errors, warnings --------------------------------------------------------------

#[test]
fn include_and_import_are_relative_to_the_including_file() {
    let dir = scratch_dir("include");
    fs::create_dir_all(dir.join("sub")).unwrap();
    fs::write(dir.join("sub/geometry.pbrt"), format!("{TRIANGLE}Import \"more.pbrt\"\n")).unwrap();
    fs::write(dir.join("sub/more.pbrt"), "Translate 0 0 1\nShape \"sphere\"\n").unwrap();
    fs::write(
        dir.join("scene.pbrt"),
        format!("{HEADER}AttributeBegin\nInclude \"sub/geometry.pbrt\"\nAttributeEnd\n{TRIANGLE}"),
    )
    .unwrap();
    let d = io::pbrt::load(&dir.join("scene.pbrt")).unwrap();
    assert_eq!(d.shapes.len(), 3);
    assert!(matches!(d.shapes[1].geometry, Geometry::Sphere { center, .. } if center == Vec3::Z));
    // The included Translate stays inside the block.
    assert_close(mesh(&d, 2).positions[1], Vec3::X, 0.0);
    // Errors inside an included file name that file.
    fs::write(dir.join("sub/more.pbrt"), "Shape \"cone\"\n").unwrap();
    let e = io::pbrt::load(&dir.join("scene.pbrt")).unwrap_err().to_string();
    assert!(e.contains("more.pbrt:1:7:") && e.contains("\"cone\" is not supported"), "{e}");
    let e = load_err("include_missing", &format!("{HEADER}\nInclude \"missing.pbrt\"\n"));
    assert!(e.contains("scene.pbrt:4:9:") && e.contains("missing.pbrt"), "{e}");
}

#[test]
fn errors_name_file_line_and_column() {
    let cases: &[(&str, &str, &str)] = &[
        ("unknown_directive", "WorldBegin\n  Sphere 1\n", "scene.pbrt:2:3: unknown directive 'Sphere'"),
        ("unknown_shape", "WorldBegin\nShape \"blob\"\n", "scene.pbrt:2:7: unknown shape type \"blob\""),
        ("unknown_light", "WorldBegin\nLightSource \"laser\"\n", "scene.pbrt:2:13: unknown light type \"laser\""),
        (
            "bad_param_type",
            "WorldBegin\nShape \"sphere\" \"string radius\" \"one\"\n",
            "scene.pbrt:2:16: Shape \"sphere\": parameter 'radius' has type 'string', expected float",
        ),
        (
            "bad_value",
            "WorldBegin\nShape \"sphere\" \"float radius\" \"one\"\n",
            "scene.pbrt:2:31: parameter \"float radius\": value \"one\" does not fit type 'float'",
        ),
        (
            "unbalanced_end",
            "WorldBegin\nAttributeEnd\n",
            "scene.pbrt:2:1: AttributeEnd without a matching AttributeBegin",
        ),
        (
            "unclosed_begin",
            "WorldBegin\nAttributeBegin\nShape \"sphere\"\n",
            "scene.pbrt:2:1: AttributeBegin is never closed (missing AttributeEnd)",
        ),
        ("bad_number", "Translate 1 2e 3\n", "scene.pbrt:1:13: bad number '2e'"),
        (
            "too_few_numbers",
            "Translate 1 2\nWorldBegin\n",
            "scene.pbrt:2:1: Translate expects 3 numbers, found 'WorldBegin' after 2",
        ),
        (
            "instancing",
            "WorldBegin\nObjectBegin \"x\"\n",
            "scene.pbrt:2:1: ObjectBegin \"x\" without a matching ObjectEnd",
        ),
        ("shape_before_world", "Shape \"sphere\"\n", "scene.pbrt:1:1: Shape is only allowed after WorldBegin"),
        (
            "camera_after_world",
            "WorldBegin\nCamera \"perspective\"\n",
            "scene.pbrt:2:1: Camera is only allowed before WorldBegin",
        ),
        (
            "unknown_namedmaterial",
            "WorldBegin\nNamedMaterial \"gold\"\n",
            "scene.pbrt:2:15: unknown named material \"gold\"",
        ),
        (
            "unknown_param_type",
            "WorldBegin\nShape \"sphere\" \"real radius\" 1\n",
            "scene.pbrt:2:16: unknown parameter type 'real' in \"real radius\"",
        ),
        (
            "stray_value",
            "WorldBegin\nShape \"sphere\" 3\n",
            "scene.pbrt:2:16: Shape: unexpected number 3, expected a parameter declaration",
        ),
        (
            "odd_spectrum",
            "WorldBegin\nLightSource \"point\" \"spectrum I\" [400 1 700]\n",
            "scene.pbrt:2:21: LightSource \"point\": parameter 'I': expected wavelength/value pairs with increasing wavelengths",
        ),
        (
            "mixed_spectrum",
            "WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" [\"glass-BK7\" 1]\n",
            "scene.pbrt:2:23: Material \"dielectric\": eta: expected wavelength/value pairs with increasing wavelengths",
        ),
        (
            "index_range",
            "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n",
            "scene.pbrt:2:53: Shape \"trianglemesh\": index 3 is out of range (there are 3 vertices)",
        ),
    ];
    for (test, text, expected) in cases {
        let e = load_err(test, text);
        let tail = e.rsplit_once("/scene.pbrt").map_or(e.as_str(), |(_, t)| t);
        assert_eq!(format!("scene.pbrt{tail}"), *expected, "{test}");
    }
    let missing = io::pbrt::load(Path::new("/nonexistent/scene.pbrt")).unwrap_err();
    assert_eq!(missing.file, Path::new("/nonexistent/scene.pbrt"));
}

#[test]
fn unknown_optional_parameters_are_warnings() {
    let d = load_ok("warnings", &format!("{HEADER}Shape \"sphere\" \"float radius\" 2 \"float sparkle\" 3\n"));
    assert_eq!(d.warnings.len(), 1);
    assert!(
        d.warnings[0].ends_with(
            "scene.pbrt:3:33: Shape \"sphere\": parameter \"float sparkle\" is not supported and was ignored"
        ),
        "{}",
        d.warnings[0]
    );
    assert!(matches!(d.shapes[0].geometry, Geometry::Sphere { radius: 2.0, .. }));
}

// ----- the Cornell box twin ----------------------------------------------------------------

/// The `to_world` matrices of shared/scenes/mitsuba/cornell-box/cornell_box.xml, row-major, in
/// the file's order (light, floor, ceiling, back, green wall, red wall, small box, large box).
const MITSUBA_MATRICES: [&str; 8] = [
    "0.229999989 0 0 0 0 -8.30516367e-09 -0.189999998 0.99000001 0 0.189999998 -8.30516367e-09 0.00999999978 0 0 0 1",
    "0.99999994 0 0 0 0 -4.37113883e-08 1 -1 0 -1 -4.37113883e-08 0 0 0 0 1",
    "0.99999994 0 0 0 0 -4.37113883e-08 -1 1 0 1 -4.37113883e-08 0 0 0 0 1",
    "1 0 0 0 0 1 0 0 0 0 1 -1 0 0 0 1",
    "-4.37113883e-08 0 -1 1 0 0.99999994 0 0 1 0 -4.37113883e-08 0 0 0 0 1",
    "-4.37113883e-08 0 1 -1 0 0.99999994 0 0 -1 0 -4.37113883e-08 0 0 0 0 1",
    "0.28689146 0 -0.087711513 0.335000008 0 0.300000012 0 -0.699999988 0.087711513 0 0.28689146 0.379999995 0 0 0 1",
    "0.284909755 0 0.0939491391 -0.330000013 0 0.610000014 0 -0.400000006 -0.0939491391 0 0.284909755 -0.280000001 0 0 0 1",
];

fn apply(matrix: &str, p: [f64; 3]) -> Vec3 {
    let m: Vec<f64> = matrix.split_whitespace().map(|x| x.parse().unwrap()).collect();
    let row = |r: usize| m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
    Vec3::new(row(0) as f32, row(1) as f32, row(2) as f32)
}

/// The triangle `t` as a vertex cycle starting at its smallest vertex (lexicographically), so
/// that equal oriented triangles compare equal.
fn canonical(t: [Vec3; 3]) -> [Vec3; 3] {
    let key = |v: Vec3| (v.x, v.y, v.z);
    let start = (0..3).min_by(|&a, &b| key(t[a]).partial_cmp(&key(t[b])).unwrap()).unwrap();
    [t[start], t[(start + 1) % 3], t[(start + 2) % 3]]
}

#[test]
fn cornell_box_twin_matches_the_mitsuba_scene() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.pbrt");
    let d = io::pbrt::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);

    // Camera: Mitsuba's lookat origin (0,0,3.9), target 0, up y. Mitsuba's camera x axis is
    // up × dir = (−1,0,0), the image's *left*, so the image's right is +x.
    let c = d.camera;
    assert_close(c.position, Vec3::new(0.0, 0.0, 3.9), 1e-6);
    assert_close(c.forward, -Vec3::Z, 1e-6);
    assert_close(c.up, Vec3::Y, 1e-6);
    assert_close(c.right, Vec3::X, 1e-6);
    // fov_axis "smaller" on a square film: the horizontal fov is the given one.
    match c.projection {
        Projection::Perspective { horizontal_fov_degrees } => assert!((horizontal_fov_degrees - 39.3077).abs() < 1e-4),
        p => panic!("{p:?}"),
    }
    assert_eq!((d.film.width, d.film.height), (512, 512));
    // Mitsuba's default gaussian rfilter: stddev 0.5, radius 4·stddev.
    assert_eq!(d.film.filter, FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 });
    assert_eq!(d.max_path_length, Some(8));
    assert!(d.lights.is_empty());
    assert_eq!(d.shapes.len(), 8);

    let white = Rgb::new(0.885809, 0.698859, 0.666422);
    let green = Rgb::new(0.105421, 0.37798, 0.076425);
    let red = Rgb::new(0.570068, 0.0430135, 0.0443706);
    let colours = [white, white, white, white, green, red, white, white];
    for (i, shape) in d.shapes.iter().enumerate() {
        let Material::Diffuse { reflectance } = front_material(&d.materials[shape.material as usize]) else {
            panic!("shape {i}: {:?}", d.materials[shape.material as usize])
        };
        assert_eq!(constant(reflectance), colours[i], "shape {i}");
        let expected_emission = (i == 0).then_some(Rgb::new(18.387, 13.9873, 6.75357));
        assert_eq!(shape.emission, expected_emission, "shape {i}");
    }

    // Rectangles: Mitsuba's mesh has vertices (−1,−1,0), (1,−1,0), (1,1,0), (−1,1,0) and
    // triangles (0,1,2), (2,3,0), both facing +z.
    let square = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];
    for (i, matrix) in MITSUBA_MATRICES.iter().enumerate().take(6) {
        let v = square.map(|p| apply(matrix, p));
        let mut expected = vec![canonical([v[0], v[1], v[2]]), canonical([v[2], v[3], v[0]])];
        let m = mesh(&d, i);
        let mut got: Vec<[Vec3; 3]> = (0..m.triangles.len()).map(|t| canonical(corners(m, t))).collect();
        let key = |t: &[Vec3; 3]| t.iter().flat_map(|v| [v.x, v.y, v.z]).collect::<Vec<f32>>();
        expected.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
        got.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
        assert_eq!(got.len(), 2);
        for (g, e) in got.iter().zip(&expected) {
            for k in 0..3 {
                assert_close(g[k], e[k], 2e-6);
            }
        }
    }

    // Cubes: the images of the 8 corners of [−1,1]³, 12 triangles facing away from the centre,
    // total area 8·(|a×b| + |b×c| + |c×a|) for the matrix columns a, b, c.
    for (i, matrix) in MITSUBA_MATRICES.iter().enumerate().skip(6) {
        let m = mesh(&d, i);
        assert_eq!(m.triangles.len(), 12);
        let centre = apply(matrix, [0.0; 3]);
        let mut expected_corners = Vec::new();
        for x in [-1.0, 1.0] {
            for y in [-1.0, 1.0] {
                for z in [-1.0, 1.0] {
                    expected_corners.push(apply(matrix, [x, y, z]));
                }
            }
        }
        for p in &m.positions {
            assert!(expected_corners.iter().any(|q| close(*p, *q, 2e-6)), "{p} is not a corner");
        }
        for q in &expected_corners {
            assert!(m.positions.iter().any(|p| close(*p, *q, 2e-6)), "corner {q} missing");
        }
        let mut area = 0.0;
        for t in 0..12 {
            let [a, b, c] = corners(m, t);
            let n = normal(m, t);
            assert!(n.dot((a + b + c) / 3.0 - centre) > 0.0, "cube {i} triangle {t} faces inward");
            area += 0.5 * n.length();
        }
        let [a, b, c] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| apply(matrix, e) - centre);
        let expected_area = 8.0 * (a.cross(b).length() + b.cross(c).length() + c.cross(a).length());
        assert!((area - expected_area).abs() < 1e-5 * expected_area, "{area} vs {expected_area}");
    }
}

#[test]
fn truncated_files_error_with_a_position_and_never_panic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.pbrt");
    let text = fs::read_to_string(path).unwrap();
    let dir = scratch_dir("truncated");
    let file = dir.join("cut.pbrt");
    let (mut ok, mut errors) = (0, 0);
    for cut in (0..text.len()).step_by(13).filter(|&i| text.is_char_boundary(i)) {
        fs::write(&file, &text[..cut]).unwrap();
        match io::pbrt::load(&file) {
            Ok(_) => ok += 1,
            Err(e) => {
                errors += 1;
                assert_eq!(e.file, file);
                assert!(e.line.is_some(), "cut at {cut}: {e}");
            }
        }
    }
    // Cutting inside an attribute block (most of the file) leaves it unclosed.
    assert!(errors > ok, "{errors} errors, {ok} loads");
}

// ----- coated materials --------------------------------------------------------------------

/// The coated parameters of a loaded material (pbrt's coated materials are two-sided).
fn coated_parameters(m: &Material) -> &scene::material::CoatedParameters {
    match front_material(m) {
        Material::Coated(p) => p,
        other => panic!("{other:?}"),
    }
}

#[test]
fn coated_materials_take_pbrts_parameters_and_defaults() {
    use scene::material::{CoatedBase, ConductorIor};
    let text = format!(
        "{HEADER}Material \"coateddiffuse\"\n{TRIANGLE}\
         Material \"coateddiffuse\" \"rgb reflectance\" [0.2 0.4 0.6] \"float roughness\" 0.04 \
         \"float vroughness\" 0.09 \"float eta\" 1.3 \"float thickness\" 0.2 \"rgb albedo\" [0.5 0.5 0.5] \
         \"float g\" 0.3 \"integer maxdepth\" 7 \"integer nsamples\" 2\n{TRIANGLE}\
         Material \"coatedconductor\"\n{TRIANGLE}\
         Material \"coatedconductor\" \"float interface.roughness\" 0.01 \"float conductor.uroughness\" 0.25 \
         \"spectrum conductor.eta\" \"metal-Au-eta\" \"spectrum conductor.k\" \"metal-Au-k\" \
         \"float interface.eta\" 1.7 \"bool remaproughness\" false\n{TRIANGLE}\
         Material \"coatedconductor\" \"rgb reflectance\" [0.9 0.5 0.1]\n{TRIANGLE}"
    );
    let d = load_ok("coated", &text);
    let m = |i: usize| d.materials[d.shapes[i].material as usize].clone();
    // Defaults: η 1.5, smooth, thickness 0.01, no scattering, maxdepth 10, one sample.
    let defaults = m(0);
    let p = coated_parameters(&defaults);
    assert_eq!((p.interface().eta, p.interface().alpha_u, p.interface().alpha_v), (1.5, 0.0, 0.0));
    assert_eq!((p.layer().thickness, p.layer().g, p.layer().max_depth, p.layer().samples), (0.01, 0.0, 10, 1));
    assert_eq!(constant(&p.layer().albedo), Rgb::BLACK);
    let CoatedBase::Diffuse { reflectance } = p.base() else { panic!("{:?}", p.base()) };
    assert_eq!(constant(reflectance), Rgb::splat(0.5));
    // Given values; α = √roughness, vroughness overrides roughness.
    let given = m(1);
    let p = coated_parameters(&given);
    assert!((p.interface().alpha_u - 0.2).abs() < 1e-6 && (p.interface().alpha_v - 0.3).abs() < 1e-6);
    assert_eq!((p.interface().eta, p.layer().thickness, p.layer().g), (1.3, 0.2, 0.3));
    assert_eq!((p.layer().max_depth, p.layer().samples), (7, 2));
    assert_eq!(constant(&p.layer().albedo), Rgb::splat(0.5));
    let CoatedBase::Diffuse { reflectance } = p.base() else { panic!() };
    assert_eq!(constant(reflectance), Rgb::new(0.2, 0.4, 0.6));
    // The conductor: copper by default, smooth.
    let copper = m(2);
    let p = coated_parameters(&copper);
    let cu =
        (io::pbrt::color::named_metal("metal-Cu-eta").unwrap(), io::pbrt::color::named_metal("metal-Cu-k").unwrap());
    assert_eq!(
        p.base(),
        &CoatedBase::Conductor { ior: ConductorIor::Complex { eta: cu.0, k: cu.1 }, alpha_u: 0.0, alpha_v: 0.0 }
    );
    // Named spectra, prefixed roughness without remapping.
    let gold = m(3);
    let p = coated_parameters(&gold);
    assert_eq!((p.interface().eta, p.interface().alpha_u), (1.7, 0.01));
    let CoatedBase::Conductor { ior: ConductorIor::Complex { eta, .. }, alpha_u, alpha_v } = p.base() else { panic!() };
    assert_eq!((*alpha_u, *alpha_v), (0.25, 0.0));
    assert_eq!(*eta, io::pbrt::color::named_metal("metal-Au-eta").unwrap());
    // Reflectance instead of η and k.
    let reflectance = m(4);
    let CoatedBase::Conductor { ior: ConductorIor::Reflectance(r), .. } = coated_parameters(&reflectance).base() else {
        panic!()
    };
    assert_eq!(constant(r), Rgb::new(0.9, 0.5, 0.1));
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn coated_materials_reject_bad_parameters_with_positions() {
    let cases = [
        ("\"rgb reflectance\" [1.5 0 0]", "outside [0, 1]"),
        ("\"float eta\" -1", "must be positive"),
        ("\"float thickness\" -0.1", "thickness"),
        ("\"float g\" 1", "g = 1"),
        ("\"integer maxdepth\" 0", "maxdepth = 0"),
        ("\"integer nsamples\" -2", "nsamples = -2"),
        ("\"float roughness\" -0.5", "roughness must be"),
        ("\"rgb albedo\" [0.5 2 0.5]", "outside [0, 1]"),
        ("\"string eta\" \"x\"", "eta needs one float"),
    ];
    for (k, (params, expected)) in cases.into_iter().enumerate() {
        let e = load_err(&format!("coated_bad_{k}"), &format!("{HEADER}Material \"coateddiffuse\" {params}\n"));
        assert!(e.contains("scene.pbrt:3:") && e.contains(expected), "{params}: {e}");
    }
    let e = load_err(
        "coated_both",
        &format!("{HEADER}Material \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5] \"float conductor.k\" 2\n"),
    );
    assert!(e.contains("scene.pbrt:3:") && e.contains("exclude each other"), "{e}");
    let e = load_err(
        "coated_texture",
        &format!(
            "{HEADER}Texture \"t\" \"float\" \"checkerboard\"\n\
             Material \"coatedconductor\" \"texture interface.roughness\" \"t\"\n"
        ),
    );
    assert!(e.contains("scene.pbrt:4:") && e.contains("only constant textures"), "{e}");
}

#[test]
fn the_coated_spheres_scene_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/coated-spheres.pbrt");
    let d = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let coated = d.materials.iter().filter(|m| matches!(front_material(m), Material::Coated(_))).count();
    assert_eq!(coated, 5, "{:?}", d.materials);
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}
