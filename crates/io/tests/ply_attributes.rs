//! PLY mesh attributes (Mitsuba's `vertex_<name>` and `face_<name>`): which properties are
//! grouped into which attribute, how integer values are converted, face values replicated
//! over a polygon's fan, and errors with the line of the bad value.
//!
//! Truths: the values written into the test files, and the sRGB decoding formula
//! `((v + 0.055)/1.055)^2.4` evaluated by hand for uchar 128 (0.2158605).

use std::path::Path;

use io::mesh::parse_ply;
use scene::desc::{MeshAttribute, MeshData};
use spectrum::Rgb;

fn parse(text: &str) -> MeshData {
    parse_ply(text.as_bytes(), Path::new("test.ply")).unwrap_or_else(|e| panic!("{e}"))
}

fn attribute<'m>(mesh: &'m MeshData, name: &str) -> &'m MeshAttribute {
    mesh.attributes.iter().find(|a| a.name == name).unwrap_or_else(|| {
        panic!("no `{name}` among {:?}", mesh.attributes.iter().map(|a| &a.name).collect::<Vec<_>>())
    })
}

/// A square as one quad face (two fan triangles).
fn square(vertex_properties: &str, vertex_values: [&str; 4], face_properties: &str, face_values: &str) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         {vertex_properties}element face 1\nproperty list uchar int vertex_indices\n{face_properties}end_header\n"
    );
    for (i, (x, y)) in [(0, 0), (1, 0), (1, 1), (0, 1)].into_iter().enumerate() {
        s += &format!("{x} {y} 0 {}\n", vertex_values[i]);
    }
    s += &format!("4 0 1 2 3 {face_values}\n");
    s
}

#[test]
fn float_and_integer_colours() {
    let mesh = parse(&square(
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
        ["255 0 128 7", "0 0 0 0", "0 0 0 0", "0 0 0 0"],
        "property float color_0\nproperty float color_1\nproperty float color_2\nproperty float weight_0\n",
        "0.25 0.5 0.75 0.125",
    ));
    // uchar: divided by 255 and sRGB-decoded, as Mitsuba's PLY loader reads integer fields.
    let colour = attribute(&mesh, "vertex_color");
    assert_eq!(colour.components, 3);
    assert_eq!(colour.values.len(), 4);
    let v = colour.values[0];
    assert_eq!((v.r, v.g), (1.0, 0.0));
    assert!((v.b - 0.215_860_5).abs() < 1e-6, "{}", v.b);
    // Face values: one per fan triangle, a one-component attribute in all channels.
    assert_eq!(mesh.triangles.len(), 2);
    assert_eq!(attribute(&mesh, "face_color").values, vec![Rgb::new(0.25, 0.5, 0.75); 2]);
    let weight = attribute(&mesh, "face_weight");
    assert_eq!((weight.components, weight.values.clone()), (1, vec![Rgb::splat(0.125); 2]));
    // The alpha channel is not an attribute of its own.
    assert_eq!(mesh.attributes.len(), 3);
}

#[test]
fn suffix_groups() {
    let mesh = parse(&square(
        "property float r\nproperty float g\nproperty float b\nproperty float albedo_x\nproperty float albedo_y\n\
         property float albedo_z\nproperty float tint_r\nproperty float tint_g\nproperty float tint_b\n\
         property float pair_0\nproperty float pair_1\nproperty float bad_1\nproperty float bad_3\n\
         property float bad_2\nproperty float nosuffix\nproperty float one_1\n",
        ["0.1 0.2 0.3 1 2 3 0.4 0.5 0.6 7 8 9 9 9 5 0.75"; 4],
        "",
        "",
    ));
    let names: Vec<&str> = mesh.attributes.iter().map(|a| a.name.as_str()).collect();
    // `pair` has 2 components, `bad` is out of order, `nosuffix` has none: not attributes.
    assert_eq!(names, ["vertex_color", "vertex_albedo", "vertex_tint_color", "vertex_one"]);
    assert_eq!(attribute(&mesh, "vertex_color").values[3], Rgb::new(0.1, 0.2, 0.3));
    assert_eq!(attribute(&mesh, "vertex_albedo").values[0], Rgb::new(1.0, 2.0, 3.0));
    assert_eq!(attribute(&mesh, "vertex_tint_color").values[0], Rgb::new(0.4, 0.5, 0.6));
    assert_eq!(attribute(&mesh, "vertex_one").values[0], Rgb::splat(0.75));
}

#[test]
fn bad_attribute_values_name_their_line() {
    let text = square(
        "property float red\nproperty float green\nproperty float blue\n",
        ["1 1 1", "1 1 1", "1 oops 1", "1 1 1"],
        "",
        "",
    );
    let error = parse_ply(text.as_bytes(), Path::new("test.ply")).unwrap_err().to_string();
    // The header has 12 lines; the third vertex is on line 15.
    assert!(error.contains(":15:") && error.contains("oops"), "{error}");
    let text = square("property float red\nproperty float green\nproperty float blue\n", ["1 1 1"; 4], "", "")
        .replace("1 1 0 1 1 1", "1 1 0 1 inf 1");
    let error = parse_ply(text.as_bytes(), Path::new("test.ply")).unwrap_err().to_string();
    assert!(error.contains(":15:") && error.contains("non-finite `green`"), "{error}");
}
