//! Mitsuba's and pbrt's `cylinder` shapes, loaded as tessellated meshes: placed where the
//! analytic cylinder is (every vertex on the axis-distance the tessellation promises, between
//! the end caps), with the analytic area 2π·r·h (φ_max·r·h for pbrt's partial cylinders), and
//! facing outwards unless flipped.

use std::fs;
use std::path::{Path, PathBuf};

use math::Vec3;
use scene::desc::{Geometry, MeshData, SceneDescription};

fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-cylinder-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn load(test: &str, name: &str, text: &str) -> SceneDescription {
    let path = scratch_dir(test).join(name);
    fs::write(&path, text).unwrap();
    io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn mesh(s: &SceneDescription) -> &MeshData {
    match &s.shapes[0].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("{g:?}"),
    }
}

/// Total area and, per triangle, whether its geometric normal points away from the axis
/// through `base` along unit `axis`.
fn area_and_outward(m: &MeshData, base: Vec3, axis: Vec3) -> (f64, bool) {
    let mut area = 0.0;
    let mut outward = true;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        area += 0.5 * f64::from(n.length());
        let centre = (a + b + c) / 3.0 - base;
        let radial = centre - axis * centre.dot(axis);
        outward &= n.dot(radial) > 0.0;
    }
    (area, outward)
}

/// The largest relative deviation of a vertex's distance from the axis from `radius`, and
/// whether every vertex lies between the end caps at heights 0 and `height`.
fn placement(m: &MeshData, base: Vec3, axis: Vec3, radius: f32, height: f32) -> (f32, bool) {
    let mut deviation = 0.0f32;
    let mut between = true;
    for &p in &m.positions {
        let d = p - base;
        let h = d.dot(axis);
        between &= (-1e-5..=height + 1e-5).contains(&h);
        deviation = deviation.max(((d - axis * h).length() - radius).abs() / radius);
    }
    (deviation, between)
}

/// 128 strips per turn: vertices lie θ²/24 ≈ 1.0e-4 (relative) outside the true radius.
const VERTEX_OFFSET: f32 = 1.1e-4;

#[test]
fn mitsuba_cylinder_follows_p0_p1_radius_and_to_world() {
    let s = load(
        "mitsuba",
        "scene.xml",
        r#"<scene version="3.0.0"><shape type="cylinder">
            <point name="p0" x="1" y="2" z="3"/><point name="p1" x="1" y="5" z="7"/><float name="radius" value="0.5"/>
            <transform name="to_world"><scale value="2"/><translate x="1"/></transform></shape></scene>"#,
    );
    let m = mesh(&s);
    // Mitsuba composes in document order, to_world = translate(1, 0, 0) · scale(2):
    // p0 ↦ (3, 4, 6), p1 ↦ (3, 10, 14), r ↦ 1, h = 10.
    let (base, top) = (Vec3::new(3.0, 4.0, 6.0), Vec3::new(3.0, 10.0, 14.0));
    let axis = (top - base).normalize();
    let (deviation, between) = placement(m, base, axis, 1.0, 10.0);
    assert!(between);
    assert!(deviation < VERTEX_OFFSET, "{deviation}");
    let (area, outward) = area_and_outward(m, base, axis);
    let exact = 2.0 * std::f64::consts::PI * 1.0 * 10.0;
    assert!((area - exact).abs() < 1e-5 * exact, "{area} vs {exact}");
    assert!(outward);
    // Vertex normals point away from the axis too.
    for (&p, &n) in m.positions.iter().zip(&m.normals) {
        let d = p - base;
        let radial = (d - axis * d.dot(axis)).normalize();
        assert!(n.dot(radial) > 0.999, "{n:?} vs {radial:?}");
    }
}

#[test]
fn mitsuba_cylinder_defaults_and_flip_normals() {
    let s = load(
        "mitsuba_flip",
        "scene.xml",
        r#"<scene version="3.0.0"><shape type="cylinder"><boolean name="flip_normals" value="true"/></shape></scene>"#,
    );
    // Defaults: p0 = 0, p1 = +z, radius 1.
    let m = mesh(&s);
    let (deviation, between) = placement(m, Vec3::ZERO, Vec3::Z, 1.0, 1.0);
    assert!(between && deviation < VERTEX_OFFSET, "{deviation}");
    let (area, outward) = area_and_outward(m, Vec3::ZERO, Vec3::Z);
    assert!((area - 2.0 * std::f64::consts::PI).abs() < 1e-4);
    assert!(!outward);
    let (first, second) = (m.triangles[0][0] as usize, m.triangles[0][1] as usize);
    assert!(m.normals[first].dot(m.positions[first]) < 0.0 && m.normals[second].dot(m.positions[second]) < 0.0);
}

#[test]
fn mitsuba_degenerate_cylinders_are_errors() {
    let dir = scratch_dir("mitsuba_bad");
    for (body, needle) in
        [(r#"<point name="p0" value="0 0 1"/>"#, "coincide"), (r#"<float name="radius" value="-1"/>"#, "radius")]
    {
        let path = dir.join("scene.xml");
        fs::write(&path, format!("<scene version=\"3.0.0\">\n<shape type=\"cylinder\">{body}</shape></scene>"))
            .unwrap();
        let e = io::load_scene(&path, &[]).unwrap_err();
        assert!(e.line == Some(2) && e.message.contains(needle), "{e}");
    }
}

const HEADER: &str = "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n";

#[test]
fn pbrt_cylinder_with_partial_sweep_and_reverse_orientation() {
    let s = load(
        "pbrt",
        "scene.pbrt",
        &format!(
            "{HEADER}Translate 0 0 1\nShape \"cylinder\" \"float radius\" 2 \"float zmin\" -1 \"float zmax\" 3 \"float phimax\" 90\n"
        ),
    );
    let m = mesh(&s);
    let base = Vec3::new(0.0, 0.0, 0.0);
    let (deviation, between) = placement(m, base, Vec3::Z, 2.0, 4.0);
    assert!(between && deviation < VERTEX_OFFSET, "{deviation}");
    // Only the first quadrant is swept.
    assert!(m.positions.iter().all(|p| p.x > -1e-5 && p.y > -1e-5));
    let (area, outward) = area_and_outward(m, base, Vec3::Z);
    let exact = std::f64::consts::FRAC_PI_2 * 2.0 * 4.0;
    assert!((area - exact).abs() < 1e-5 * exact, "{area} vs {exact}");
    assert!(outward);
    let s = load("pbrt_reverse", "scene.pbrt", &format!("{HEADER}ReverseOrientation\nShape \"cylinder\"\n"));
    let (area, outward) = area_and_outward(mesh(&s), Vec3::new(0.0, 0.0, -1.0), Vec3::Z);
    assert!((area - 2.0 * std::f64::consts::PI * 2.0).abs() < 1e-4);
    assert!(!outward);
}
