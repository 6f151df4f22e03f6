//! Tests of the triangle mesh readers (OBJ, PLY, Mitsuba `.serialized`).
//!
//! Truths used: hand-computed geometry of the test files (areas, orientations, the signed
//! volume of a closed pyramid), the files' own normals, and for `matpreview.serialized` the
//! counts, bounding boxes and areas obtained with an independent decoder (Python's `zlib` and
//! `struct`, run once while writing this test).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use io::mesh::{parse_obj, parse_ply, parse_serialized, read_obj, read_ply, read_serialized};
use math::{Vec2, Vec3};
use scene::desc::MeshData;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// A directory of the shared Mitsuba scenes (`../shared` beside the clone). The tests that
/// need it are named `shared_*` and ignored, and `.ci/run` runs them in a step of their own;
/// without the directory they fail here instead of passing unchecked.
fn shared(dir: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/mitsuba").join(dir);
    assert!(path.is_dir(), "{} is absent: this test needs ../shared beside the clone", path.display());
    path
}

fn area(mesh: &MeshData) -> f64 {
    mesh.triangles.iter().map(|t| 0.5 * f64::from(face_cross(mesh, t).length())).sum()
}

fn face_cross(mesh: &MeshData, t: &[u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    (b - a).cross(c - a)
}

/// Signed volume enclosed by a closed mesh (divergence theorem); positive when faces point out.
fn signed_volume(mesh: &MeshData) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Area of a planar polygon given by its corners (shoelace formula on two coordinates).
fn shoelace(corners: &[(f64, f64)]) -> f64 {
    let n = corners.len();
    (0..n)
        .map(|i| {
            let (x0, y0) = corners[i];
            let (x1, y1) = corners[(i + 1) % n];
            x0 * y1 - x1 * y0
        })
        .sum::<f64>()
        .abs()
        / 2.0
}

fn obj(text: &str) -> Result<MeshData, String> {
    parse_obj(text.as_bytes(), Path::new("t.obj")).map_err(|e| e.to_string())
}

fn ply(bytes: &[u8]) -> Result<MeshData, String> {
    parse_ply(bytes, Path::new("t.ply")).map_err(|e| e.to_string())
}

/// Asserts that `result` is an error whose text starts with `prefix` and contains `needle`.
#[track_caller]
fn assert_error(result: Result<MeshData, String>, prefix: &str, needle: &str) {
    match result {
        Ok(mesh) => {
            panic!("expected an error `{prefix}…{needle}…`, got a mesh with {} triangles", mesh.triangles.len())
        }
        Err(message) => assert!(
            message.starts_with(prefix) && message.contains(needle),
            "error `{message}` should start with `{prefix}` and contain `{needle}`"
        ),
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
#[ignore = "needs ../shared: the Mitsuba caustic-cbox meshes"]
fn shared_obj_caustic_cbox_walls_are_unit_box_faces_pointing_inward() {
    let dir = shared("caustic-cbox/meshes");
    for (name, expected_area) in [
        ("cbox_back.obj", 4.0),
        ("cbox_ceiling.obj", 4.0),
        ("cbox_floor.obj", 4.0),
        ("cbox_greenwall.obj", 4.0),
        ("cbox_redwall.obj", 4.0),
        ("cbox_luminaire.obj", 0.25),
    ] {
        let mesh = read_obj(&dir.join(name)).unwrap();
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (4, 2), "{name}");
        assert!(mesh.normals.is_empty() && mesh.uvs.is_empty(), "{name}");
        assert!((area(&mesh) - expected_area).abs() < 1e-6, "{name}: area {}", area(&mesh));
        for t in &mesh.triangles {
            // The box is [-1, 1]³: the inside is towards the origin.
            let centre = t.iter().map(|&i| mesh.positions[i as usize]).sum::<Vec3>() / 3.0;
            let inward = face_cross(&mesh, t).normalize().dot(-centre.normalize());
            assert!(inward > 0.5, "{name}: triangle {t:?} faces away from the box's inside ({inward})");
        }
    }
}

#[test]
#[ignore = "needs ../shared: the Mitsuba cbox-classic meshes"]
fn shared_obj_cbox_classic_boxes_match_their_file_normals_and_areas() {
    let dir = shared("cbox-classic/meshes");
    // Corners of the boxes' top faces (x, z) and their heights, from the files.
    type BoxSpec = (&'static str, [(f64, f64); 4], f64);
    let boxes: [BoxSpec; 2] = [
        ("cbox_largebox.obj", [(423.0, 247.0), (265.0, 296.0), (314.0, 456.0), (472.0, 406.0)], 330.0),
        ("cbox_smallbox.obj", [(130.0, 65.0), (82.0, 225.0), (240.0, 272.0), (290.0, 114.0)], 165.0),
    ];
    for (name, top, height) in boxes {
        let mesh = read_obj(&dir.join(name)).unwrap();
        // 24 `v`, each used with one normal: 24 distinct corners.
        assert_eq!((mesh.positions.len(), mesh.triangles.len(), mesh.normals.len()), (24, 12, 24), "{name}");
        let perimeter: f64 = (0..4)
            .map(|i| {
                let (a, b) = (top[i], top[(i + 1) % 4]);
                ((a.0 - b.0) * (a.0 - b.0) + (a.1 - b.1) * (a.1 - b.1)).sqrt()
            })
            .sum();
        let expected = 2.0 * shoelace(&top) + perimeter * height;
        assert!((area(&mesh) / expected - 1.0).abs() < 1e-5, "{name}: area {} vs {expected}", area(&mesh));
        assert!((signed_volume(&mesh) / (shoelace(&top) * height) - 1.0).abs() < 1e-4, "{name}: faces point outward");
        for t in &mesh.triangles {
            let geometric = face_cross(&mesh, t).normalize();
            for &v in t {
                let shading = mesh.normals[v as usize];
                assert!((shading.length() - 1.0).abs() < 1e-6);
                assert!(shading.dot(geometric) > 0.999, "{name}: vn {shading} vs face {geometric}");
            }
        }
    }
    // The floor lists 12 vertices but its one face uses the first 4: only those are kept.
    let floor = read_obj(&dir.join("cbox_floor.obj")).unwrap();
    assert_eq!((floor.positions.len(), floor.triangles.len()), (4, 2));
    let expected = shoelace(&[(552.8, 0.0), (0.0, 0.0), (0.0, 559.2), (549.6, 559.2)]);
    assert!((area(&floor) / expected - 1.0).abs() < 1e-5);
    let ceiling = read_obj(&dir.join("cbox_ceiling.obj")).unwrap();
    assert_eq!((ceiling.positions.len(), ceiling.triangles.len()), (8, 4));
    let expected = shoelace(&[(556.0, 0.0), (556.0, 559.2), (0.0, 559.2), (0.0, 0.0)]) + 130.0 * 105.0;
    assert!((area(&ceiling) / expected - 1.0).abs() < 1e-5);
}

#[test]
fn obj_deindexes_corners_flips_v_and_resolves_negative_indices() {
    let mesh = read_obj(&data("quad.obj")).unwrap();
    // Quad: 4 corners (v/vt/1); second face: 3 new combinations; third face: none.
    assert_eq!(mesh.positions.len(), 7);
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [1, 2, 3]]);
    let expect_positions =
        [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [0., 0., 0.], [1., 1., 0.], [0., 1., 0.]];
    assert_eq!(mesh.positions, expect_positions.map(Vec3::from_array).to_vec());
    // v' = 1 − v: (0,0) → (0,1), (1,1) → (1,0), (0.25,0.75) → (0.25,0.25).
    let expect_uvs = [[0., 1.], [1., 1.], [1., 0.], [0., 0.], [0.25, 0.25], [1., 0.], [0., 0.]];
    assert_eq!(mesh.uvs, expect_uvs.map(Vec2::from_array).to_vec());
    // `vn 0 0 2` is normalised; the second face uses `vn -1` = (0, 0, −1).
    let z = Vec3::Z;
    assert_eq!(mesh.normals, vec![z, z, z, z, -z, -z, -z]);
}

#[test]
fn obj_corners_without_normals_get_the_face_normal_and_missing_uvs_are_zero() {
    let text = "v 0 0 0\nv 0 1 0\nv 0 0 1\nv 5 0 0\nvn 1 1 1\nvt 0.5 0.5\n\
                f 1/1/1 4/1/1 2/1/1\n\
                f 1 2 3\n";
    let mesh = obj(text).unwrap();
    assert_eq!(mesh.positions.len(), 6);
    let n = Vec3::ONE.normalize();
    // Second face (x = 0 plane, corners 1 2 3): (0,1,0) × (0,0,1) = +x.
    assert_eq!(&mesh.normals[..3], &[n, n, n]);
    for v in 3..6 {
        assert!((mesh.normals[v] - Vec3::X).length() < 1e-6, "{}", mesh.normals[v]);
    }
    assert_eq!(
        mesh.uvs,
        vec![Vec2::splat(0.5), Vec2::splat(0.5), Vec2::splat(0.5), Vec2::ZERO, Vec2::ZERO, Vec2::ZERO]
    );
}

#[test]
fn obj_line_continuation_comments_and_ignored_statements() {
    let text = "# comment\nv 0 0 0 1\nv 1 0 0 # trailing\nv 0 1 0 0.5 0.5 0.5\n\
                cstype bspline\nl 1 2\np 1\ng a b\ns 1\n\nf 1 \\\n 2 3\n";
    let mesh = obj(text).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    // A backslash at the end of a comment does not continue it.
    let mesh = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n# C:\\models\\\nf 1 2 3\n").unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], Vec3::new(0.0, 1.0, 0.0));
    // A `vt` with only u has v = 0, which flips to 1.
    let mesh = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nf 1/1 2/1 3/1\n").unwrap();
    assert_eq!(mesh.uvs[0], Vec2::new(0.5, 1.0));
}

#[test]
fn obj_errors_name_line_and_column() {
    let eight = "v 0 0 0\n".repeat(8);
    // Lines 1–8 vertices, 9–11 comments, 12 the face.
    let text = format!("{eight}#\n#\n#\nf 1 2 40\n");
    assert_error(obj(&text), "t.obj:12:7: ", "face refers to vertex 40 but only 8 vertices are defined");
    assert_error(obj(&format!("{eight}f 1 2 -9\n")), "t.obj:9:7: ", "vertex -9 (counting back");
    assert_error(obj(&format!("{eight}f 0 1 2\n")), "t.obj:9:3: ", "index 0 is invalid");
    assert_error(obj(&format!("{eight}vt 0 0\nf 1/1 2/2 3/1\n")), "t.obj:10:7: ", "texture coordinate 2 but only 1");
    assert_error(obj(&format!("{eight}f 1//1 2//1 3//1\n")), "t.obj:9:3: ", "normal 1 but no normal is defined");
    assert_error(obj(&format!("{eight}f 1 2\n")), "t.obj:9:1: ", "at least 3 vertices");
    assert_error(obj(&format!("{eight}f 1/2/3/4 1 2\n")), "t.obj:9:3: ", "not a face corner");
    assert_error(obj(&format!("{eight}f 1 2 x\n")), "t.obj:9:7: ", "expected a vertex index, found `x`");
    assert_error(obj("v 0 0 0\nv 1 abc 3\n"), "t.obj:2:5: ", "expected a number, found `abc`");
    assert_error(obj("v 1 inf 3\n"), "t.obj:1:5: ", "not a finite number");
    assert_error(obj("v 1 2\n"), "t.obj:1:6: ", "takes 3 to 7 numbers, found 2");
    assert_error(obj("vn 1 2 3 4\n"), "t.obj:1:10: ", "takes 3 numbers, found 4");
    assert_error(obj("v 0 0 0\n  frob 1 2\n"), "t.obj:2:3: ", "unknown OBJ statement `frob`");
    // A continued line reports its first line, without a column.
    assert_error(obj(&format!("{eight}f 1 \\\n 2 99\n")), "t.obj:9: ", "vertex 99");
    // Invalid UTF-8 inside a number.
    let mut bytes = b"v 0 0 0\nv 1 ".to_vec();
    bytes.extend_from_slice(&[0xff, b'\n']);
    let error = parse_obj(&bytes, Path::new("t.obj")).unwrap_err().to_string();
    assert!(error.starts_with("t.obj:2:5: ") && error.contains("UTF-8"), "{error}");
}

#[test]
#[ignore = "needs ../shared: the Mitsuba cbox-classic meshes"]
fn shared_obj_truncated_files_are_errors() {
    let dir = shared("cbox-classic/meshes");
    let path = dir.join("cbox_largebox.obj");
    let text = std::fs::read_to_string(&path).unwrap();
    // Cut inside the face `f 5//2 6//2 7//2`: the last corner reads `6/`.
    let cut = text.find("f 5//2 6/").unwrap() + "f 5//2 6/".len();
    let line = text[..cut].lines().count();
    assert_error(obj(&text[..cut]), &format!("t.obj:{line}:8: "), "`6/` is not a face corner");
    // Cut before the faces: vertices only.
    let cut = text.find("\nf ").unwrap();
    assert_error(obj(&text[..cut]), "t.obj:", "no faces");
    assert_error(obj(""), "t.obj:1: ", "no vertices and no faces");
    let missing = read_obj(Path::new("/nonexistent/x.obj")).unwrap_err().to_string();
    assert!(missing.starts_with("/nonexistent/x.obj: cannot read the file"), "{missing}");
}

// ---------------------------------------------------------------------------------------------
// PLY

/// The pyramid of `tests/data/pyramid.ply`, checked against hand-computed values.
fn check_pyramid(mesh: &MeshData) {
    assert_eq!(mesh.positions.len(), 5);
    // Quad base as a fan, then four side triangles.
    assert_eq!(mesh.triangles, vec![[0, 3, 2], [0, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]);
    // Base 1, four sides of base 1 and slant height √(0.5² + 1²).
    let expected_area = 1.0 + 2.0 * 1.25f64.sqrt();
    assert!((area(mesh) - expected_area).abs() < 1e-6, "area {}", area(mesh));
    // Volume base · height / 3 = 1/3, positive: every face points outward.
    assert!((signed_volume(mesh) - 1.0 / 3.0).abs() < 1e-6, "volume {}", signed_volume(mesh));
    assert_eq!(mesh.positions[4], Vec3::new(0.5, 0.5, 1.0));
    assert_eq!(mesh.uvs, [[0., 0.], [1., 0.], [1., 1.], [0., 1.], [0.5, 0.5]].map(Vec2::from_array).to_vec());
    // (−3, 0, 0) normalised; vertex 3's zero normal becomes the area-weighted face normal sum:
    // base (0, 0, −1) + side 2-3-4 (0, 1, ½) + side 3-0-4 (−1, 0, ½) = (−1, 1, 0).
    assert_eq!(mesh.normals[0], -Vec3::X);
    assert_eq!(mesh.normals[1], -Vec3::Z);
    assert!((mesh.normals[3] - Vec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-6, "{}", mesh.normals[3]);
}

#[test]
fn ply_ascii_pyramid() {
    check_pyramid(&read_ply(&data("pyramid.ply")).unwrap());
}

/// Appends `value` as PLY type `ty`.
fn put(out: &mut Vec<u8>, ty: &str, value: f64, big: bool) {
    macro_rules! bytes {
        ($t:ty) => {{
            let v = value as $t;
            if big { v.to_be_bytes().to_vec() } else { v.to_le_bytes().to_vec() }
        }};
    }
    let b = match ty {
        "char" | "int8" => bytes!(i8),
        "uchar" | "uint8" => bytes!(u8),
        "short" | "int16" => bytes!(i16),
        "ushort" | "uint16" => bytes!(u16),
        "int" | "int32" => bytes!(i32),
        "uint" | "uint32" => bytes!(u32),
        "float" | "float32" => bytes!(f32),
        "double" | "float64" => bytes!(f64),
        _ => panic!("{ty}"),
    };
    out.extend_from_slice(&b);
}

const PYRAMID_VERTICES: [[f64; 8]; 5] = [
    [0., 0., 0., -3., 0., 0., 0., 0.],
    [1., 0., 0., 0., 0., -1., 1., 0.],
    [1., 1., 0., 0., 0., -1., 1., 1.],
    [0., 1., 0., 0., 0., 0., 0., 1.],
    [0.5, 0.5, 1., 0., 0., 1., 0.5, 0.5],
];
const PYRAMID_FACES: [&[u32]; 5] = [&[0, 3, 2, 1], &[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[3, 0, 4]];

/// The pyramid in a binary PLY with the given list types, other names and extra data to skip.
fn binary_pyramid(big: bool, count_type: &str, index_type: &str) -> Vec<u8> {
    let format = if big { "binary_big_endian" } else { "binary_little_endian" };
    let header = format!(
        "ply\r\nformat {format} 1.0\r\nelement vertex 5\r\nproperty double x\r\nproperty double y\r\n\
         property double z\r\nproperty short extra\r\nproperty float nx\r\nproperty float ny\r\n\
         property float nz\r\nproperty float s\r\nproperty float t\r\nelement edge 2\r\n\
         property int a\r\nproperty list ushort short b\r\nelement face 5\r\n\
         property list {count_type} {index_type} vertex_index\r\nproperty list uchar int flags\r\nend_header\r\n"
    );
    let mut out = header.into_bytes();
    for v in PYRAMID_VERTICES {
        for (i, x) in v.iter().enumerate() {
            let ty = match i {
                0..3 => "double",
                _ => "float",
            };
            put(&mut out, ty, *x, big);
            if i == 2 {
                put(&mut out, "short", -7.0, big);
            }
        }
    }
    for edge in [0.0, 3.0] {
        put(&mut out, "int", edge, big);
        put(&mut out, "ushort", edge, big);
        for k in 0..edge as usize {
            put(&mut out, "short", k as f64, big);
        }
    }
    for face in PYRAMID_FACES {
        put(&mut out, count_type, face.len() as f64, big);
        for &i in face {
            put(&mut out, index_type, i.into(), big);
        }
        put(&mut out, "uchar", 1.0, big);
        put(&mut out, "int", 99.0, big);
    }
    out
}

#[test]
fn ply_binary_both_byte_orders_and_all_index_types_give_the_ascii_mesh() {
    let ascii = read_ply(&data("pyramid.ply")).unwrap();
    for big in [false, true] {
        for (count_type, index_type) in [
            ("uchar", "int"),
            ("uint8", "uint32"),
            ("char", "ushort"),
            ("ushort", "short"),
            ("uint", "int8"),
            ("int", "uchar"),
        ] {
            let bytes = binary_pyramid(big, count_type, index_type);
            let mesh =
                parse_ply(&bytes, Path::new("b.ply")).unwrap_or_else(|e| panic!("{count_type} {index_type}: {e}"));
            assert_eq!(mesh, ascii, "big endian {big}, {count_type} {index_type}");
        }
    }
}

#[test]
fn ply_binary_errors() {
    let good = binary_pyramid(false, "uchar", "int");
    let header_len = good.windows(12).position(|w| w == b"end_header\r\n").unwrap() + 12;
    // Truncated inside the last face: 5 vertices × 48 B, 2 edges, then faces of 22 and 18 B.
    let cut = &good[..good.len() - 10];
    assert_error(ply(cut), "t.ply: ", "the file ends inside face 4 of the 5 faces");
    // The header's counts must fit in the data before anything is reserved.
    let hostile = String::from_utf8_lossy(&good[..header_len]).replace("element vertex 5", "element vertex 4000000000");
    let mut bytes = hostile.into_bytes();
    bytes.extend_from_slice(&good[header_len..]);
    assert_error(ply(&bytes), "t.ply:3: ", "declares 4000000000 `vertex` elements but only");
    // An index beyond the vertices: the first index of face 2 (vertex 1).
    let mut bad = good.clone();
    let face2 = good.len() - 3 * 18 + 1;
    bad[face2..face2 + 4].copy_from_slice(&17i32.to_le_bytes());
    assert_error(
        ply(&bad),
        "t.ply: ",
        &format!("face 2 refers to vertex 17 but the header declares 5 vertices (at byte {face2})"),
    );
    bad[face2..face2 + 4].copy_from_slice(&(-1i32).to_le_bytes());
    assert_error(ply(&bad), "t.ply: ", "face 2 refers to vertex -1");
    // A two-vertex face.
    let mut bad = good.clone();
    bad[face2 - 1] = 2;
    assert_error(ply(&bad), "t.ply: ", "face 2 has 2 vertices");
}

fn ascii_pyramid() -> String {
    std::fs::read_to_string(data("pyramid.ply")).unwrap()
}

#[test]
fn ply_ascii_errors_name_line_and_column() {
    let good = ascii_pyramid();
    // Line 25 is vertex 3: `0 1 0 0 0 0 0 0 1`; its y is at column 3.
    assert_error(
        ply(good.replace("0 1 0 0 0 0 0 0 1", "0 x 0 0 0 0 0 0 1").as_bytes()),
        "t.ply:25:3: ",
        "expected a number (float), found `x` in vertex 3",
    );
    // Line 28 is face 1 `3 0 1 4 2 0.5 0.5`; an index beyond the 5 vertices.
    assert_error(
        ply(good.replace("3 0 1 4 2", "3 0 9 4 2").as_bytes()),
        "t.ply:28:5: ",
        "face 1 refers to vertex 9 but the header declares 5 vertices",
    );
    assert_error(
        ply(good.replace("3 0 1 4 2", "3 0 1.5 4 2").as_bytes()),
        "t.ply:28:5: ",
        "expected an integer (int), found `1.5`",
    );
    assert_error(
        ply(good.replace("3 0 1 4 2", "300 0 1 4 2").as_bytes()),
        "t.ply:28:1: ",
        "300 does not fit in the declared type uchar",
    );
    // Wrong counts: one vertex too many declared, or one face too few.
    // With 6 declared vertices the first face line is read as vertex 5, and face 0 starts in the
    // middle of the next line, running into the texture coordinate 0.5.
    assert_error(
        ply(good.replace("element vertex 5", "element vertex 6").as_bytes()),
        "t.ply:28:11: ",
        "found `0.5` in face 0",
    );
    assert_error(
        ply(good.replace("element face 5", "element face 4").as_bytes()),
        "t.ply:31:1: ",
        "unexpected data after the last element",
    );
    assert_error(
        ply(good.replace("element vertex 5", "element vertex 50").as_bytes()),
        "t.ply:7: ",
        "declares 50 `vertex` elements but only",
    );
    // Truncated in the last face.
    let cut = &good[..good.len() - 6];
    assert_error(ply(cut.as_bytes()), "t.ply:31: ", "the file ends inside face 4 of the 5 faces");
    // Header problems.
    assert_error(ply(b"plx\n"), "t.ply:1: ", "not a PLY file");
    assert_error(ply(b""), "t.ply:1: ", "empty");
    assert_error(ply(good.replace("end_header\n", "").as_bytes()), "t.ply:", "unknown header statement `7`");
    assert_error(ply(good.replace("ascii 1.0", "ascii 2.0").as_bytes()), "t.ply:2:14: ", "version `1.0`");
    assert_error(ply(good.replace("ascii", "binary").as_bytes()), "t.ply:2:8: ", "expected `ascii`");
    assert_error(ply(good.replace("float nx", "half nx").as_bytes()), "t.ply:12:10: ", "unknown property type `half`");
    assert_error(ply(good.replace("property float z\n", "").as_bytes()), "t.ply:7: ", "no `z` property");
    assert_error(ply(good.replace("property float nz\n", "").as_bytes()), "t.ply:7: ", "some of `nx`, `ny`, `nz`");
    assert_error(
        ply(good.replace("uchar int vertex_indices", "uchar float vertex_indices").as_bytes()),
        "t.ply:17: ",
        "integer type",
    );
    assert_error(ply(good.replace("vertex_indices", "corners").as_bytes()), "t.ply:17: ", "no `vertex_indices`");
    assert_error(
        ply(good.replace("list uchar int tags", "list float int tags").as_bytes()),
        "t.ply:6:15: ",
        "list count must have an integer type",
    );
    assert_error(
        ply(good.replace("property float shininess", "property float x\nproperty float x").as_bytes()),
        "t.ply:6:16: ",
        "a second property `x`",
    );
}

// ---------------------------------------------------------------------------------------------
// Mitsuba .serialized

/// Counts, bounding boxes (min, max) and total areas of the three meshes of
/// `matpreview.serialized`, from an independent decoder (Python `zlib` + `struct`).
/// Vertices, triangles, bounding box minimum and maximum, total area.
type MeshFacts = (usize, usize, [f64; 3], [f64; 3], f64);

const MATPREVIEW: [MeshFacts; 3] = [
    (
        289,
        512,
        [-1.0024269819259644, -1.0, 0.0],
        [1.1313550472259521, 0.622808575630188, 1.2964400053024292],
        4.960818722090654,
    ),
    (
        2078,
        3936,
        [-0.9272717833518982, -0.927271842956543, -0.031111598014831543],
        [0.9272717833518982, 0.927271842956543, 1.6868669986724854],
        8.681537285403339,
    ),
    (
        29439,
        57152,
        [-1.2199430465698242, -1.2199430465698242, -1.1764949560165405],
        [1.003021001815796, 1.2199430465698242, 1.0131640434265137],
        32.16646091369628,
    ),
];

#[test]
#[ignore = "needs ../shared: the Mitsuba matpreview.serialized"]
fn shared_serialized_matpreview_meshes_match_an_independent_decoder() {
    let dir = shared("matpreview");
    let path = dir.join("matpreview.serialized");
    for (index, &(vertices, triangles, min, max, expected_area)) in MATPREVIEW.iter().enumerate() {
        let start = Instant::now();
        let mesh = read_serialized(&path, index as u32).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        let lo = mesh.positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = mesh.positions.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        eprintln!(
            "matpreview shape {index}: {} vertices, {} triangles, bounds {lo} – {hi}, area {:.6}, loaded in {:.2} ms",
            mesh.positions.len(),
            mesh.triangles.len(),
            area(&mesh),
            seconds * 1e3
        );
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (vertices, triangles));
        assert_eq!((mesh.normals.len(), mesh.uvs.len()), (vertices, vertices));
        // f32 → f64 is exact, and the table holds the f32 values exactly.
        assert_eq!((lo.as_dvec3().to_array(), hi.as_dvec3().to_array()), (min, max));
        assert!((area(&mesh) / expected_area - 1.0).abs() < 1e-5, "area {} vs {expected_area}", area(&mesh));
        assert!(mesh.validate().is_ok());
        // Every vertex is used, as in the file.
        let mut used = vec![false; vertices];
        mesh.triangles.iter().flatten().for_each(|&i| used[i as usize] = true);
        assert!(used.iter().all(|&u| u));
        for n in &mesh.normals {
            assert!((n.length() - 1.0).abs() < 1e-6, "normal {n}");
        }
        assert!(mesh.uvs.iter().all(|uv| uv.is_finite() && uv.x > -0.2 && uv.x < 1.2 && uv.y > -0.2 && uv.y < 1.2));
    }
}

#[test]
#[ignore = "needs ../shared: the Mitsuba matpreview.serialized"]
fn shared_serialized_damaged_copies_of_matpreview_are_errors() {
    let dir = shared("matpreview");
    let bytes = std::fs::read(dir.join("matpreview.serialized")).unwrap();
    let parse = |b: &[u8], i: u32| parse_serialized(b, i, Path::new("m.serialized")).map_err(|e| e.to_string());
    // Mesh offsets from the file's dictionary (version 3: u32 offsets, then the count 3).
    let offsets = [0usize, 5167, 52916];
    // Truncated inside mesh 0's compressed stream.
    assert_error(parse(&bytes[..3000], 0), "m.serialized: ", "mesh 0: the compressed data ends");
    // Truncated: the dictionary is gone, so mesh 1 cannot be found.
    assert_error(parse(&bytes[..bytes.len() - 2], 1), "m.serialized: ", "dictionary");
    assert_error(parse(&bytes[..3], 0), "m.serialized: ", "ends inside the header of mesh 0");
    // A corrupted byte in the middle of mesh 1's stream: a deflate error or a checksum mismatch.
    let mut corrupt = bytes.clone();
    corrupt[(offsets[1] + offsets[2]) / 2] ^= 0x55;
    assert_error(parse(&corrupt, 1), "m.serialized: ", "mesh 1: corrupt compressed data");
    // Wrong identifier, version, index, dictionary entry.
    let mut wrong = bytes.clone();
    wrong[0] = 0x1d;
    assert_error(parse(&wrong, 0), "m.serialized: ", "not the serialized-mesh identifier");
    let mut wrong = bytes.clone();
    wrong[offsets[2] + 2] = 5;
    assert_error(parse(&wrong, 2), "m.serialized: ", "unsupported serialized-mesh version 5");
    assert_error(parse(&bytes, 3), "m.serialized: ", "shape_index 3 is out of range: the file holds 3 meshes");
    let mut wrong = bytes.clone();
    let entry = bytes.len() - 4 - 4;
    wrong[entry..entry + 4].copy_from_slice(&(offsets[2] as u32 + 1).to_le_bytes());
    assert_error(parse(&wrong, 2), "m.serialized: ", "mesh 2 (at byte 52917) starts with");
    let mut wrong = bytes.clone();
    let count = bytes.len() - 4;
    wrong[count..].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_error(
        parse(&wrong, 1),
        "m.serialized: ",
        "the mesh dictionary at the end of the file is missing or damaged",
    );
    // Shape 0 is found without the dictionary, as in Mitsuba.
    assert!(parse(&bytes[..offsets[1]], 0).is_ok());
}

/// A one-mesh `.serialized` file: header, zlib stream, dictionary.
fn serialized_file(version: u16, flags: u32, counts: (u64, u64), payload: &[u8]) -> Vec<u8> {
    let mut stream = flags.to_le_bytes().to_vec();
    if version == 4 {
        stream.extend_from_slice(b"a name\0");
    }
    stream.extend_from_slice(&counts.0.to_le_bytes());
    stream.extend_from_slice(&counts.1.to_le_bytes());
    stream.extend_from_slice(payload);
    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(&stream).unwrap();
    let mut file = 0x041Cu16.to_le_bytes().to_vec();
    file.extend_from_slice(&version.to_le_bytes());
    file.extend_from_slice(&encoder.finish().unwrap());
    if version == 4 {
        file.extend_from_slice(&0u64.to_le_bytes());
    } else {
        file.extend_from_slice(&0u32.to_le_bytes());
    }
    file.extend_from_slice(&1u32.to_le_bytes());
    file
}

/// The payload of one triangle in double precision with normals, uvs and colours.
fn triangle_payload(indices: [u32; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    let floats: [f64; 33] = [
        0., 0., 0., 2., 0., 0., 0., 2., 0., // positions
        0., 0., 3., 0., 0., 0., 0., 0., 1., // normals (the second is zero)
        0., 0., 1., 0., 0., 1., // uvs
        1., 0., 0., 0., 1., 0., 0., 0., 1., // colours
    ];
    floats.iter().for_each(|f| out.extend_from_slice(&f.to_le_bytes()));
    indices.iter().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
    out
}

#[test]
fn serialized_version_4_double_precision_colours_and_face_normals() {
    let flags = 0x1 | 0x2 | 0x8 | 0x2000;
    let parse = |b: &[u8]| parse_serialized(b, 0, Path::new("s.serialized")).map_err(|e| e.to_string());
    for version in [3, 4] {
        let mesh = parse(&serialized_file(version, flags, (3, 1), &triangle_payload([0, 1, 2]))).unwrap();
        assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)]);
        // Normalised; the zero normal becomes the face normal +z. No v flip for this format.
        assert_eq!(mesh.normals, vec![Vec3::Z; 3]);
        assert_eq!(mesh.uvs, vec![Vec2::ZERO, Vec2::X, Vec2::Y]);
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }
    // Face normals: the file's normals are dropped.
    let mesh = parse(&serialized_file(4, flags | 0x10, (3, 1), &triangle_payload([0, 1, 2]))).unwrap();
    assert!(mesh.normals.is_empty() && mesh.uvs.len() == 3);
    // Wrong counts and indices.
    let payload = triangle_payload([0, 1, 2]);
    assert_error(
        parse(&serialized_file(4, flags, (3, 2), &payload)),
        "s.serialized: ",
        "ends after 276 of the 288 bytes",
    );
    assert_error(parse(&serialized_file(4, flags, (2, 1), &payload)), "s.serialized: ", "longer than its counts say");
    assert_error(
        parse(&serialized_file(4, flags, (3, 1), &triangle_payload([0, 3, 2]))),
        "s.serialized: ",
        "triangle 0 refers to vertex 3 but the mesh has 3 vertices",
    );
    assert_error(parse(&serialized_file(4, flags, (3, 0), &payload)), "s.serialized: ", "no triangles");
    assert_error(
        parse(&serialized_file(4, flags | 0x1000, (3, 1), &payload)),
        "s.serialized: ",
        "both single and double",
    );
    // A hostile header is refused before anything is reserved.
    assert_error(parse(&serialized_file(4, flags, (1 << 31, 1), &payload)), "s.serialized: ", "more than the");
    assert_error(
        parse(&serialized_file(4, flags, (1 << 33, 1 << 20), &payload)),
        "s.serialized: ",
        "more than 2³² − 1",
    );
    // Non-finite positions.
    let mut payload = triangle_payload([0, 1, 2]);
    payload[8..16].copy_from_slice(&f64::NAN.to_le_bytes());
    assert_error(
        parse(&serialized_file(4, flags, (3, 1), &payload)),
        "s.serialized: ",
        "vertex 0 has a non-finite position",
    );
}

// ---------------------------------------------------------------------------------------------
// Robustness

/// Checks what the readers promise about any mesh they return.
#[track_caller]
fn assert_sound(mesh: &MeshData, what: &str) {
    assert!(mesh.validate().is_ok(), "{what}: {:?}", mesh.validate());
    assert!(!mesh.triangles.is_empty(), "{what}: no triangles");
    assert!(mesh.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5), "{what}: normals not unit length");
    assert!(mesh.uvs.iter().all(|uv| uv.is_finite()), "{what}: non-finite uvs");
}

/// Random edits (fixed seed) of valid files: every result is an error or a sound mesh, and
/// nothing panics.
#[test]
fn mutated_files_give_errors_or_sound_meshes() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move |bound: usize| {
        // xorshift64*
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % bound.max(1)
    };
    let flags = 0x1 | 0x2 | 0x8 | 0x2000;
    let inputs: [(&str, Vec<u8>); 5] = [
        ("obj", std::fs::read(data("quad.obj")).unwrap()),
        ("ply", std::fs::read(data("pyramid.ply")).unwrap()),
        ("ply", binary_pyramid(false, "uchar", "int")),
        ("ply", binary_pyramid(true, "ushort", "uint")),
        ("serialized", serialized_file(4, flags, (3, 1), &triangle_payload([0, 1, 2]))),
    ];
    const INTERESTING: &[u8] = b"-09/ \n\\#.eE\xff\x00\x7f";
    let mut outcomes = [0usize; 2];
    for (kind, original) in &inputs {
        for iteration in 0..2000 {
            let mut bytes = original.clone();
            for _ in 0..1 + next(3) {
                let at = next(bytes.len());
                match next(5) {
                    0 => bytes[at] = next(256) as u8,
                    1 => bytes[at] = INTERESTING[next(INTERESTING.len())],
                    2 => bytes.insert(at, INTERESTING[next(INTERESTING.len())]),
                    3 => _ = bytes.remove(at),
                    _ => bytes.truncate(at),
                }
                if bytes.is_empty() {
                    break;
                }
            }
            let path = Path::new("fuzz");
            let result = match *kind {
                "obj" => parse_obj(&bytes, path),
                "ply" => parse_ply(&bytes, path),
                _ => parse_serialized(&bytes, 0, path),
            };
            match result {
                Ok(mesh) => {
                    assert_sound(&mesh, &format!("{kind} mutation {iteration}"));
                    outcomes[0] += 1;
                }
                Err(error) => {
                    assert!(error.to_string().starts_with("fuzz"), "{error}");
                    outcomes[1] += 1;
                }
            }
        }
    }
    eprintln!("mutated files: {} parsed, {} rejected", outcomes[0], outcomes[1]);
    // Both outcomes occur: the edits neither always break nor never touch the parsers.
    assert!(outcomes[0] > 100 && outcomes[1] > 100, "{outcomes:?}");
}
