//! Loader tests of instancing: Mitsuba 3's `shapegroup` + `instance` and pbrt-v4's
//! `ObjectBegin`/`ObjectEnd`/`ObjectInstance` produce objects in their own space and instances
//! with the right transforms; emitters in objects, unknown names and nesting are errors.

use std::path::PathBuf;

use math::Vec3;
use scene::desc::{Geometry, SceneDescription};
use testkit::TempDir;

/// Writes `text` to a scene file in a fresh directory; returns the directory's guard (keep it
/// while the file is used) and the file's path.
fn write(name: &str, text: &str) -> (TempDir, PathBuf) {
    let dir = TempDir::new(&format!("instancing-test-{name}"));
    let file = dir.join(if text.contains("WorldBegin") { "scene.pbrt" } else { "scene.xml" });
    std::fs::write(&file, text).unwrap();
    (dir, file)
}

fn mitsuba(name: &str, body: &str) -> Result<SceneDescription, String> {
    let text = format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n");
    let (_dir, path) = write(name, &text);
    io::mitsuba::load(&path, &[]).map_err(|e| e.to_string())
}

fn pbrt(name: &str, body: &str) -> Result<SceneDescription, String> {
    let text = format!("Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n{body}\n");
    let (_dir, path) = write(name, &text);
    io::pbrt::load(&path).map_err(|e| e.to_string())
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

const GROUP: &str = r#"
<shape type="shapegroup" id="group">
    <shape type="sphere"><float name="radius" value="0.5"/></shape>
    <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform></shape>
</shape>"#;

#[test]
fn mitsuba_shapegroup_and_instances() {
    // The first instance refers to the group before it is declared.
    let body = format!(
        r#"<shape type="instance"><ref id="group"/><transform name="to_world"><scale value="2"/><translate x="3"/></transform></shape>
{GROUP}
<shape type="instance"><ref id="group"/></shape>
<shape type="sphere"/>"#
    );
    let d = mitsuba("mitsuba_ok", &body).unwrap();
    assert_eq!((d.objects.len(), d.instances.len(), d.shapes.len()), (1, 2, 1));
    let object = &d.objects[0];
    assert_eq!(object.name, "group");
    assert!(matches!(object.shapes[0].geometry, Geometry::Sphere { radius: 0.5, .. }));
    let Geometry::Mesh(rectangle) = &object.shapes[1].geometry else { panic!("{:?}", object.shapes[1]) };
    assert!(rectangle.positions.iter().all(|p| p.z == -1.0), "the shape's own transform is kept");
    // scale 2, then translate by 3 along x: the object's origin goes to (3, 0, 0), (1, 0, 0) to (5, 0, 0).
    let to_world = d.instances[0].to_world;
    assert!(close(to_world.transform_point3(Vec3::ZERO), Vec3::new(3.0, 0.0, 0.0)));
    assert!(close(to_world.transform_point3(Vec3::X), Vec3::new(5.0, 0.0, 0.0)));
    assert!(close(d.instances[1].to_world.transform_point3(Vec3::ONE), Vec3::ONE));
    assert_eq!((d.instances[0].object, d.instances[1].object), (0, 0));
}

#[test]
fn mitsuba_instancing_errors() {
    let emitter = r#"<shape type="shapegroup" id="g"><shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></shape>"#;
    let e = mitsuba("emitter", emitter).unwrap_err();
    assert!(e.contains("scene.xml:2:") && e.contains("emitter") && e.contains("'g'"), "{e}");
    let e = mitsuba("not_a_group", r#"<bsdf type="diffuse" id="b"/><shape type="instance"><ref id="b"/></shape>"#)
        .unwrap_err();
    assert!(e.contains("'b' is not a shapegroup"), "{e}");
    let e = mitsuba("no_ref", r#"<shape type="instance"/>"#).unwrap_err();
    assert!(e.contains("needs a <ref>"), "{e}");
    let nested = r#"<shape type="shapegroup" id="a"><shape type="shapegroup" id="b"/></shape>"#;
    assert!(mitsuba("nested", nested).unwrap_err().contains("nested instancing"));
    let singular = format!(
        r#"{GROUP}<shape type="instance"><ref id="group"/><transform name="to_world"><scale x="0"/></transform></shape>"#
    );
    assert!(mitsuba("singular", &singular).unwrap_err().contains("singular"));
}

#[test]
fn pbrt_objects_and_instances() {
    let body = r#"AttributeBegin
Translate 0 0 5
ObjectBegin "thing"
Translate 1 0 0
Shape "sphere" "float radius" 0.5
ObjectEnd
Shape "sphere" "float radius" 2
AttributeEnd
Translate 10 0 0
ObjectInstance "thing"
Scale 2 2 2
ObjectInstance "thing"
Shape "sphere""#;
    let d = pbrt("pbrt_ok", body).unwrap();
    assert_eq!((d.objects.len(), d.instances.len(), d.shapes.len()), (1, 2, 2));
    // The definition's shapes keep the transformation current at their declaration.
    let Geometry::Sphere { center, radius, .. } = d.objects[0].shapes[0].geometry else { panic!() };
    assert!(close(center, Vec3::new(1.0, 0.0, 5.0)) && radius == 0.5, "{center}");
    // ObjectBegin's attribute block ended at ObjectEnd: the world sphere after it is at z = 5.
    let Geometry::Sphere { center, radius, .. } = d.shapes[0].geometry else { panic!() };
    assert!(close(center, Vec3::new(0.0, 0.0, 5.0)) && radius == 2.0, "{center}");
    assert!(close(d.instances[0].to_world.transform_point3(Vec3::ZERO), Vec3::new(10.0, 0.0, 0.0)));
    assert!(close(d.instances[1].to_world.transform_point3(Vec3::X), Vec3::new(12.0, 0.0, 0.0)));
}

#[test]
fn pbrt_instancing_errors() {
    let cases = [
        ("area", "ObjectBegin \"a\"\nAreaLightSource \"diffuse\"\nShape \"sphere\"\nObjectEnd\n", "area light"),
        ("unknown", "ObjectInstance \"nope\"\n", "unknown object \"nope\""),
        ("nested", "ObjectBegin \"a\"\nObjectBegin \"b\"\n", "cannot be nested"),
        ("end", "ObjectEnd\n", "ObjectEnd without a matching ObjectBegin"),
        ("twice", "ObjectBegin \"a\"\nObjectEnd\nObjectBegin \"a\"\nObjectEnd\n", "defined twice"),
        ("inside", "ObjectBegin \"a\"\nObjectEnd\nObjectBegin \"b\"\nObjectInstance \"a\"\n", "inside the definition"),
    ];
    for (name, body, expected) in cases {
        let e = pbrt(name, body).unwrap_err();
        assert!(e.contains("scene.pbrt:") && e.contains(expected), "{name}: {e}");
    }
}
