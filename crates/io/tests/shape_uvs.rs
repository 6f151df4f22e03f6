//! Texture coordinates of Mitsuba 3's analytic shapes as the loader builds them: the cube's
//! per-face layout, and a turned sphere's uv in its own axes (placed as an instance of a unit
//! sphere), as Mitsuba computes them.

use math::{Ray, Vec2, Vec3};
use scene::Scene;
use scene::desc::{Geometry, SceneDescription};
use testkit::TempDir;

fn load(name: &str, body: &str) -> SceneDescription {
    let dir = TempDir::new(&format!("shape-uvs-test-{name}"));
    let file = dir.join("scene.xml");
    std::fs::write(&file, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    io::mitsuba::load(&file, &[]).unwrap()
}

#[test]
fn cube_faces_have_mitsubas_uv_layout_and_face_outwards() {
    let d = load("cube", r#"<shape type="cube"/>"#);
    let Geometry::Mesh(mesh) = &d.shapes[0].geometry else { panic!("{:?}", d.shapes[0]) };
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), (24, 12));
    // Mitsuba's cube: the first face (normal −y) has corners (1,−1,−1), (1,−1,1), (−1,−1,1),
    // (−1,−1,−1) with uv (0,1), (1,1), (1,0), (0,0); every face repeats that uv pattern.
    let first: Vec<(Vec3, Vec2)> = (0..4).map(|i| (mesh.positions[i], mesh.uvs[i])).collect();
    assert_eq!(
        first,
        [
            (Vec3::new(1.0, -1.0, -1.0), Vec2::new(0.0, 1.0)),
            (Vec3::new(1.0, -1.0, 1.0), Vec2::new(1.0, 1.0)),
            (Vec3::new(-1.0, -1.0, 1.0), Vec2::new(1.0, 0.0)),
            (Vec3::new(-1.0, -1.0, -1.0), Vec2::new(0.0, 0.0)),
        ]
    );
    let normals = [Vec3::NEG_Y, Vec3::Y, Vec3::X, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Z];
    for (face, normal) in normals.iter().enumerate() {
        for t in &mesh.triangles[2 * face..2 * face + 2] {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            assert_eq!((b - a).cross(c - a).normalize(), *normal, "face {face}");
        }
        let uvs: Vec<Vec2> = (4 * face..4 * face + 4).map(|i| mesh.uvs[i]).collect();
        assert_eq!(uvs, [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO]);
    }
}

#[test]
fn a_turned_sphere_takes_uv_in_its_own_axes() {
    // Rotating 90° about x takes the sphere's +z pole to world −y: Mitsuba's v = θ/π is 0 there.
    let turned =
        r#"<transform name="to_world"><rotate x="1" angle="90"/><scale value="2"/><translate x="1"/></transform>"#;
    let d = load("turned", &format!(r#"<shape type="sphere">{turned}</shape>"#));
    assert_eq!((d.shapes.len(), d.objects.len(), d.instances.len()), (0, 1, 1));
    let (scene, _) = Scene::from_description(&d, Some((4, 4))).unwrap();
    let hit = scene.intersect(&Ray::new(Vec3::new(1.0, -5.0, 0.01), Vec3::Y)).unwrap();
    assert!((hit.position - Vec3::new(1.0, -2.0, 0.01)).length() < 1e-3, "{}", hit.position);
    assert!(hit.uv.y < 0.01, "v = {} at the pole", hit.uv.y);
    assert!((hit.normal - Vec3::NEG_Y).length() < 1e-2, "{}", hit.normal);
    // Only scaled and moved: a world sphere, whose world axes are its own.
    let d = load("plain", r#"<shape type="sphere"><transform name="to_world"><scale value="2"/></transform></shape>"#);
    assert_eq!((d.shapes.len(), d.objects.len()), (1, 0));
    // An emitter keeps the world sphere (instanced emitters are not supported).
    let emitter = r#"<emitter type="area"><rgb name="radiance" value="1"/></emitter>"#;
    let d = load("emitter", &format!(r#"<shape type="sphere">{turned}{emitter}</shape>"#));
    assert_eq!((d.shapes.len(), d.objects.len()), (1, 0));
}
