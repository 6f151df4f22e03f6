//! Where the loaders find the files a scene names: Mitsuba's `<path>` search path (in Mitsuba
//! 3's order: the latest `<path>` first, the scene file's directory last; relative to the file
//! that declares it), pbrt's includes relative to the including file, and gzip-compressed
//! `.pbrt.gz` / `.ply.gz` files.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use flate2::Compression;
use flate2::write::GzEncoder;
use io::SceneError;
use scene::desc::{Geometry, MeshData, SceneDescription};
use scene::material::Material;
use spectrum::Rgb;

/// A fresh empty directory for one test.
fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-search-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, contents: &[u8]) -> PathBuf {
    let path = dir.join(name);
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    fs::write(&path, contents).unwrap();
    path
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = GzEncoder::new(Vec::new(), Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// An OBJ triangle whose first vertex is at `(x, 0, 0)`, so tests can tell files apart.
fn triangle_obj(x: f32) -> Vec<u8> {
    format!("v {x} 0 0\nv {} 0 0\nv {x} 1 0\nf 1 2 3\n", x + 1.0).into_bytes()
}

fn mitsuba(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

fn obj_shape(filename: &str) -> String {
    format!(r#"<shape type="obj"><string name="filename" value="{filename}"/></shape>"#)
}

fn mesh(s: &SceneDescription, i: usize) -> &MeshData {
    match &s.shapes[i].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("{g:?}"),
    }
}

fn first_x(s: &SceneDescription) -> f32 {
    mesh(s, 0).positions[0].x
}

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

#[test]
fn mitsuba_test_suite_layout_loads_through_path() {
    // tests/data/search mirrors mitsuba-data: scenes/<name>/<name>.xml with
    // <path value="../../common"/>, the mesh and an included file only in common/.
    let path = data_dir().join("search/scenes/quad/quad.xml");
    let loaded = io::load_scene_with(&path, &[], &io::LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.description;
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(mesh(s, 0).positions.len(), 3);
    assert_eq!(mesh(s, 0).positions[1].x, 2.0);
    match &s.materials[s.shapes[0].material as usize] {
        Material::Diffuse { reflectance } => assert_eq!(reflectance.as_constant(), Some(Rgb::splat(0.25))),
        m => panic!("{m:?}"),
    }
    assert_eq!(loaded.settings.samples_per_pixel, Some(32));
    assert!(s.warnings.iter().all(|w| !w.contains("<path")), "{:?}", s.warnings);
}

#[test]
fn latest_path_wins_and_the_scene_directory_comes_last() {
    let dir = scratch_dir("order");
    write(&dir, "first/m.obj", &triangle_obj(10.0));
    write(&dir, "second/m.obj", &triangle_obj(20.0));
    write(&dir, "scene/m.obj", &triangle_obj(30.0));
    write(&dir, "scene/only_here.obj", &triangle_obj(40.0));
    let load = |name: &str, body: &str| {
        let path = write(&dir, &format!("scene/{name}"), mitsuba(body).as_bytes());
        io::mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
    };
    // Mitsuba prepends every <path>: the last one declared is searched first …
    let s = load("a.xml", &format!(r#"<path value="../first"/><path value="../second"/>{}"#, obj_shape("m.obj")));
    assert_eq!(first_x(&s), 20.0);
    let s = load("b.xml", &format!(r#"<path value="../second"/><path value="../first"/>{}"#, obj_shape("m.obj")));
    assert_eq!(first_x(&s), 10.0);
    // … before the scene file's own directory, which still serves files found nowhere else.
    let s = load("c.xml", &format!(r#"<path value="../first"/>{}"#, obj_shape("only_here.obj")));
    assert_eq!(first_x(&s), 40.0);
    // Without <path> the scene directory is used.
    let s = load("d.xml", &obj_shape("m.obj"));
    assert_eq!(first_x(&s), 30.0);
}

#[test]
fn path_is_relative_to_the_file_that_declares_it_and_applies_to_includes_after_it() {
    let dir = scratch_dir("declaring_file");
    write(&dir, "assets/m.obj", &triangle_obj(5.0));
    write(&dir, "assets/part.xml", mitsuba(&obj_shape("m.obj")).as_bytes());
    // parts/paths.xml declares "../assets" — relative to parts/, i.e. <dir>/assets.
    write(&dir, "parts/paths.xml", mitsuba(r#"<path value="../assets"/>"#).as_bytes());
    let main = write(
        &dir,
        "deep/down/main.xml",
        mitsuba(r#"<include filename="../../parts/paths.xml"/><include filename="part.xml"/>"#).as_bytes(),
    );
    let s = io::mitsuba::load(&main, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first_x(&s), 5.0);
    // An <include> before the <path> that would find it is not found (Mitsuba resolves
    // includes while reading).
    let early = write(
        &dir,
        "deep/down/early.xml",
        mitsuba(r#"<include filename="part.xml"/><include filename="../../parts/paths.xml"/>"#).as_bytes(),
    );
    let e = io::mitsuba::load(&early, &[]).unwrap_err();
    assert_eq!((e.file.as_path(), e.line), (early.as_path(), Some(2)), "{e}");
    assert!(e.message.contains("part.xml") && e.message.contains("not found"), "{e}");
}

#[test]
fn a_missing_file_lists_every_path_searched() {
    let dir = scratch_dir("missing");
    fs::create_dir_all(dir.join("a")).unwrap();
    fs::create_dir_all(dir.join("b")).unwrap();
    let main = write(
        &dir,
        "scene/scene.xml",
        mitsuba(&format!(
            "<path value=\"../a\"/>\n<path value=\"../b\"/>\n{}",
            r#"<shape type="ply"><string name="filename" value="meshes/absent.ply"/></shape>"#
        ))
        .as_bytes(),
    );
    let e: SceneError = io::mitsuba::load(&main, &[]).unwrap_err();
    assert_eq!((e.file.as_path(), e.line), (main.as_path(), Some(4)), "{e}");
    let searched = [
        dir.join("scene/../b/meshes/absent.ply"),
        dir.join("scene/../a/meshes/absent.ply"),
        dir.join("scene/meshes/absent.ply"),
    ];
    let mut at = 0;
    for path in &searched {
        let needle = format!("'{}'", path.display());
        let found = e.message[at..].find(&needle).unwrap_or_else(|| panic!("{needle} not (in order) in: {e}"));
        at += found + needle.len();
    }
    // The same for an <include>.
    let main =
        write(&dir, "scene/inc.xml", mitsuba("<path value=\"../a\"/>\n<include filename=\"x.xml\"/>").as_bytes());
    let e = io::mitsuba::load(&main, &[]).unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    for path in [dir.join("scene/../a/x.xml"), dir.join("scene/x.xml")] {
        assert!(e.message.contains(&format!("'{}'", path.display())), "{e}");
    }
}

#[test]
fn a_missing_path_directory_is_a_warning_and_named_when_a_file_is_then_not_found() {
    let dir = scratch_dir("bad_path");
    write(&dir, "m.obj", &triangle_obj(3.0));
    // A scene copied without its shared directory still loads what it has.
    let main = write(&dir, "s.xml", mitsuba(&format!("<path value=\"nowhere\"/>\n{}", obj_shape("m.obj"))).as_bytes());
    let s = io::mitsuba::load(&main, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first_x(&s), 3.0);
    assert!(s.warnings.iter().any(|w| w.contains("s.xml:2:") && w.contains("nowhere")), "{:?}", s.warnings);
    // When a file is then missing, the error says that the <path> did not exist.
    let main =
        write(&dir, "t.xml", mitsuba(&format!("<path value=\"nowhere\"/>\n{}", obj_shape("absent.obj"))).as_bytes());
    let e = io::mitsuba::load(&main, &[]).unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("absent.obj") && e.message.contains("t.xml:2:") && e.message.contains("nowhere"), "{e}");
    // <path> only at the top level.
    let main = write(&dir, "u.xml", mitsuba("<shape type=\"sphere\">\n<path value=\".\"/></shape>").as_bytes());
    let e = io::mitsuba::load(&main, &[]).unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("<scene>"), "{e}");
}

#[test]
fn pbrt_includes_are_relative_to_each_including_file() {
    let dir = scratch_dir("pbrt_include");
    write(
        &dir,
        "geometry/mesh/inner.pbrt",
        b"Shape \"trianglemesh\" \"point3 P\" [7 0 0 8 0 0 7 1 0] \"integer indices\" [0 1 2]\n",
    );
    write(&dir, "geometry/outer.pbrt", b"Include \"mesh/inner.pbrt\"\n");
    let main = write(
        &dir,
        "scene.pbrt",
        b"Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nImport \"geometry/outer.pbrt\"\n",
    );
    let s = io::pbrt::load(&main).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first_x(&s), 7.0);
}

#[test]
fn gzip_compressed_pbrt_and_ply_files_load_like_the_plain_ones() {
    let dir = scratch_dir("gzip");
    let ply = fs::read(data_dir().join("pyramid.ply")).unwrap();
    write(&dir, "pyramid.ply.gz", &gzip(&ply));
    write(&dir, "pyramid.ply", &ply);
    let scene = |mesh: &str, include: &str| {
        format!(
            "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
             Shape \"plymesh\" \"string filename\" \"{mesh}\"\nInclude \"{include}\"\n"
        )
    };
    let sphere = b"Shape \"sphere\" \"float radius\" 3\n";
    write(&dir, "part.pbrt.gz", &gzip(sphere));
    write(&dir, "part.pbrt", sphere);
    let plain = write(&dir, "plain.pbrt", scene("pyramid.ply", "part.pbrt").as_bytes());
    let packed = write(&dir, "packed.pbrt.gz", &gzip(scene("pyramid.ply.gz", "part.pbrt.gz").as_bytes()));
    let a = io::load_scene(&plain, &[]).unwrap_or_else(|e| panic!("{e}"));
    let b = io::load_scene(&packed, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.shapes.len(), 2);
    // Identical but for the names, which give the file each shape came from.
    for (x, y) in a.shapes.iter().zip(&b.shapes) {
        assert_eq!((&x.geometry, x.material, x.emission), (&y.geometry, y.material, y.emission));
    }
    assert!(b.shapes[1].name.contains("part.pbrt.gz:1"), "{}", b.shapes[1].name);
    assert!(!mesh(&a, 0).positions.is_empty());
    // The mesh reader decompresses by content, for any caller.
    assert_eq!(
        io::mesh::read_ply(&dir.join("pyramid.ply.gz")).unwrap(),
        io::mesh::read_ply(&dir.join("pyramid.ply")).unwrap()
    );
    // A truncated gzip file is an error naming it, not a panic.
    let gz = gzip(sphere);
    let broken = write(&dir, "broken.pbrt.gz", &gz[..gz.len() / 2]);
    let e = io::load_scene(&broken, &[]).unwrap_err();
    assert_eq!(e.file, broken);
    assert!(e.message.contains("gzip"), "{e}");
}
