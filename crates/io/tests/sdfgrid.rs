//! Loader tests of Mitsuba 3's `sdfgrid` shape: a `.vol` file written here (Mitsuba's own unit
//! test grid, the plane y + z = 1 on 2×2×2 points), placed by an instance, answers rays as
//! Mitsuba's `test04_ray_intersect` / `test05_ray_intersect_instancing` expect; bad parameters
//! and bad files are errors naming the file and the position.

use std::path::Path;

use math::{Ray, Vec3};
use scene::Scene;
use scene::desc::SceneDescription;
use testkit::TempDir;

fn dir(name: &str) -> TempDir {
    TempDir::new(&format!("sdfgrid-test-{name}"))
}

/// A single-channel `.vol` file: magic, version 3, encoding 1, sizes, channels, bounds, values.
fn vol(dims: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], channels] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes
}

fn plane() -> Vec<u8> {
    let s = 0.5f32.sqrt();
    vol([2, 2, 2], 1, &[-s, -s, 0.0, 0.0, 0.0, 0.0, s, s])
}

fn load(dir: &Path, shape: &str, translate: Vec3) -> Result<SceneDescription, String> {
    let text = format!(
        r#"<scene version="3.0.0">
<shape type="shapegroup" id="group">
    {shape}
</shape>
<shape type="instance"><ref id="group"/>
    <transform name="to_world"><translate x="{}" y="{}" z="{}"/></transform>
</shape>
</scene>
"#,
        translate.x, translate.y, translate.z
    );
    let file = dir.join("scene.xml");
    std::fs::write(&file, text).unwrap();
    io::mitsuba::load(&file, &[]).map_err(|e| e.to_string())
}

#[test]
fn the_plane_answers_rays_as_in_mitsubas_unit_test() {
    let dir = dir("plane");
    std::fs::write(dir.join("plane.vol"), plane()).unwrap();
    for normals in ["smooth", "analytic"] {
        for translate in [Vec3::ZERO, Vec3::new(-0.5, 0.5, 0.2)] {
            let shape = format!(
                r#"<shape type="sdfgrid"><string name="filename" value="plane.vol"/><string name="normals" value="{normals}"/></shape>"#
            );
            let description = load(&dir, &shape, translate).unwrap();
            let (scene, _) = Scene::from_description(&description, Some((4, 4))).unwrap();
            let n = 10;
            for i in 0..n {
                for j in 0..n {
                    let x = -2.0 + 4.0 * i as f32 / (n - 1) as f32;
                    let y = -2.0 + 4.0 * j as f32 / (n - 1) as f32;
                    let origin = translate + Vec3::new(x, y, 3.0);
                    let hit = scene.intersect(&Ray::new(origin, Vec3::new(0.0, 0.0, -1.0)));
                    let inside = (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y);
                    assert_eq!(hit.is_some(), inside, "{normals}, {translate}: ray at ({x}, {y})");
                    if let Some(hit) = hit {
                        // The plane is exact in the mesh: f32 rounding only.
                        assert!((hit.distance - (2.0 + y)).abs() < 1e-5, "t = {} at y = {y}", hit.distance);
                        let expected = Vec3::new(0.0, 1.0, 1.0).normalize();
                        assert!((hit.normal - expected).length() < 1e-5, "normal {}", hit.normal);
                        assert_eq!(hit.uv, math::Vec2::ZERO, "Mitsuba's sdfgrid has no uv");
                    }
                }
            }
        }
    }
}

#[test]
fn bad_parameters_and_files_are_errors() {
    let dir = dir("errors");
    std::fs::write(dir.join("plane.vol"), plane()).unwrap();
    let bytes = plane();
    std::fs::write(dir.join("short.vol"), &bytes[..bytes.len() - 3]).unwrap();
    std::fs::write(dir.join("rgb.vol"), vol([2, 2, 2], 3, &[0.5; 24])).unwrap();
    std::fs::write(dir.join("empty.vol"), vol([2, 2, 2], 1, &[1.0; 8])).unwrap();
    let shape = |inner: &str| format!(r#"<shape type="sdfgrid" id="sdf">{inner}</shape>"#);
    let file = |name: &str| format!(r#"<string name="filename" value="{name}"/>"#);
    let cases = [
        (shape(&format!(r#"{}<string name="normals" value="falloff"/>"#, file("plane.vol"))), "'falloff'"),
        (shape(&format!(r#"{}<boolean name="flip_normals" value="true"/>"#, file("plane.vol"))), "flip_normals"),
        (shape(""), "filename"),
        (shape(&file("missing.vol")), "missing.vol"),
        (shape(&file("short.vol")), "short.vol: truncated"),
        (shape(&file("rgb.vol")), "rgb.vol: 3 channels"),
        (shape(&file("empty.vol")), "no surface"),
    ];
    for (xml, expected) in cases {
        let e = load(&dir, &xml, Vec3::ZERO).unwrap_err();
        assert!(e.contains(expected) && e.contains("scene.xml:3:"), "{xml}: {e}");
    }
    // Not an area emitter (nor in Mitsuba); tested outside a shapegroup, which refuses emitters anyway.
    let text = format!(
        r#"<scene version="3.0.0"><shape type="sdfgrid">{}<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>"#,
        file("plane.vol")
    );
    std::fs::write(dir.join("emitter.xml"), text).unwrap();
    let e = io::mitsuba::load(&dir.join("emitter.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("cannot be an area emitter"), "{e}");
}
