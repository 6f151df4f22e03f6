//! Heterogeneous media in both loaders: Mitsuba 3's `heterogeneous` medium with `gridvolume`
//! (`.vol`, 1 or 3 channels, `to_world`, `filter_type`, `use_grid_bbox`) and `constvolume`
//! volumes, pbrt-v4's `uniformgrid`; the `.vol` → world mapping checked by evaluating the
//! loaded medium at world points; errors naming the file and line.

use std::path::Path;

use scene::desc::SceneDescription;
use scene::medium::Medium;
use spectrum::Rgb;
use testkit::TempDir;

fn dir(test: &str) -> TempDir {
    TempDir::new(&format!("hetero-test-{test}"))
}

/// A `.vol` file of `channels` values per point on `dims` points with the given bounds.
fn write_vol(path: &Path, dims: [i32; 3], channels: i32, bounds: [f32; 6], values: &[f32]) {
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], channels] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in bounds.iter().chain(values) {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

fn mitsuba(test: &str, body: &str) -> Result<SceneDescription, String> {
    let dir = dir(test);
    // density.vol: 2×1×1 points, values 1 and 3; colour.vol: 1×1×2 points of RGB.
    write_vol(&dir.join("density.vol"), [2, 1, 1], 1, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &[1.0, 3.0]);
    write_vol(&dir.join("colour.vol"), [1, 1, 2], 3, [0.0, 0.0, 0.0, 2.0, 2.0, 2.0], &[0.2, 0.4, 0.6, 0.6, 0.4, 0.2]);
    let path = dir.join("scene.xml");
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    io::mitsuba::load(&path, &[]).map_err(|e| e.to_string())
}

/// σ_t and σ_s of `medium` at world point `p` (RGB).
fn at(medium: &Medium, p: [f32; 3]) -> (Rgb, Rgb) {
    let h = medium.heterogeneous().expect("a heterogeneous medium");
    h.tracker::<Rgb>(medium.scale, &()).coefficients(math::Vec3::from(p), &())
}

fn close(a: Rgb, b: [f32; 3]) -> bool {
    a.to_array().iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn mitsuba_grid_volume_maps_the_unit_cube_through_to_world() {
    let body = r#"<medium type="heterogeneous" id="smoke">
    <float name="scale" value="2"/>
    <volume name="sigma_t" type="gridvolume">
        <string name="filename" value="density.vol"/>
        <transform name="to_world"><scale value="2"/><translate x="-1"/></transform>
    </volume>
    <volume name="albedo" type="gridvolume">
        <string name="filename" value="colour.vol"/>
        <string name="filter_type" value="nearest"/>
        <boolean name="use_grid_bbox" value="true"/>
    </volume>
    <phase type="hg"><float name="g" value="0.3"/></phase>
</medium>
<shape type="sphere"><bsdf type="null"/><ref name="interior" id="smoke"/></shape>"#;
    let desc = mitsuba("mitsuba_ok", body).unwrap();
    let medium = &desc.media.media[0];
    // to_world = translate(−1, 0, 0) · scale(2): the grid covers [−1, 1] × [0, 2] × [0, 2], the
    // voxel centres are at x = −0.5 (value 1) and x = 0.5 (value 3); trilinear in between,
    // clamped outside; σ_t = 2 × the value.
    let (t, s) = at(medium, [-0.5, 1.0, 1.0]);
    assert!(close(t, [2.0; 3]), "{t:?}");
    let (t, _) = at(medium, [0.0, 1.0, 1.0]);
    assert!(close(t, [4.0; 3]), "{t:?}");
    let (t, _) = at(medium, [0.9, 0.1, 1.9]);
    assert!(close(t, [6.0; 3]), "{t:?}");
    // Outside the sigma_t volume's box the medium is empty.
    assert!(close(at(medium, [1.1, 1.0, 1.0]).0, [0.0; 3]));
    assert!(close(at(medium, [0.0, -0.1, 1.0]).0, [0.0; 3]));
    // The albedo grid with use_grid_bbox: its file bounds [0, 2]³ are its grid space; nearest
    // lookup, world z ≥ 1 reads the second voxel (0.6, 0.4, 0.2), z < 1 the first.
    assert!(close(s, [2.0 * 0.6, 2.0 * 0.4, 2.0 * 0.2]), "{s:?}");
    let (t, s) = at(medium, [-0.5, 1.0, 0.5]);
    assert!(close(t, [2.0; 3]) && close(s, [2.0 * 0.2, 2.0 * 0.4, 2.0 * 0.6]), "{t:?} {s:?}");
    assert_eq!(desc.media.shapes.len(), 1);
}

#[test]
fn mitsuba_constant_volumes_and_colours() {
    let body = r#"<medium type="heterogeneous" id="m">
    <rgb name="albedo" value="0.5, 0.25, 1"/>
    <volume type="constvolume" name="sigma_t">
        <rgb name="value" value="0.5, 0.4, 0.3"/>
        <transform name="to_world"><translate x="-0.5" y="-0.5" z="-0.5"/></transform>
    </volume>
</medium>"#;
    let desc = mitsuba("mitsuba_const", body).unwrap();
    let m = &desc.media.media[0];
    let (t, s) = at(m, [0.4, -0.4, 0.0]);
    assert!(close(t, [0.5, 0.4, 0.3]) && close(s, [0.25, 0.1, 0.3]), "{t:?} {s:?}");
    // constvolume's box is [−0.5, 0.5]³.
    assert!(close(at(m, [0.6, 0.0, 0.0]).0, [0.0; 3]));
    // A plain sigma_t is a constant volume on the unit cube (Mitsuba's default volume box).
    let desc =
        mitsuba("mitsuba_plain", r#"<medium type="heterogeneous" id="m"><float name="sigma_t" value="3"/></medium>"#)
            .unwrap();
    let m = &desc.media.media[0];
    assert!(close(at(m, [0.5, 0.5, 0.5]).0, [3.0; 3]) && close(at(m, [-0.5, 0.5, 0.5]).0, [0.0; 3]));
    assert!(close(at(m, [0.5, 0.5, 0.5]).1, [2.25; 3]), "default albedo 0.75");
}

#[test]
fn mitsuba_grid_errors_name_file_and_line() {
    let cases = [
        (
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="nothing.vol"/></volume>"#,
            "nothing.vol",
        ),
        (
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="density.vol"/><string name="filter_type" value="cubic"/></volume>"#,
            "cubic",
        ),
        (
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="density.vol"/><string name="wrap_mode" value="repeat"/></volume>"#,
            "repeat",
        ),
        (r#"<volume name="sigma_t" type="gridvolume"/>"#, "filename"),
        (r#"<texture name="sigma_t" type="bitmap"/>"#, "expected a <volume>"),
        (r#"<volume name="albedo" type="constvolume"><float name="value" value="2"/></volume>"#, "albedo"),
    ];
    for (index, (inner, needle)) in cases.iter().enumerate() {
        let body = format!("<medium type=\"heterogeneous\" id=\"m\">\n    {inner}\n</medium>");
        let error = mitsuba(&format!("mitsuba_err{index}"), &body).err().unwrap_or_else(|| panic!("{inner} loads"));
        assert!(error.contains("scene.xml:") && error.contains(needle), "{needle}: {error}");
    }
    // A malformed .vol file: the message names it and what is wrong.
    let dir = dir("mitsuba_badvol");
    std::fs::write(dir.join("bad.vol"), b"VOL\x03").unwrap();
    std::fs::write(
        dir.join("scene.xml"),
        r#"<scene version="3.0.0"><medium type="heterogeneous" id="m"><volume name="sigma_t" type="gridvolume"><string name="filename" value="bad.vol"/></volume></medium></scene>"#,
    )
    .unwrap();
    let error = io::mitsuba::load(&dir.join("scene.xml"), &[]).unwrap_err().to_string();
    assert!(
        error.contains("scene.xml:1:") && error.contains("bad.vol") && error.contains("truncated header"),
        "{error}"
    );
}

fn pbrt(test: &str, text: &str) -> Result<SceneDescription, String> {
    let dir = dir(test);
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, text).unwrap();
    io::pbrt::load(&path).map_err(|e| e.to_string())
}

#[test]
fn pbrt_uniform_grid() {
    let text = r#"WorldBegin
AttributeBegin
  Translate 1 0 0
  MakeNamedMedium "smoke" "string type" "uniformgrid" "integer nx" 2 "integer ny" 1 "integer nz" 1
      "float density" [1 3] "point3 p0" [0 0 0] "point3 p1" [2 1 1]
      "rgb sigma_a" [1 1 1] "rgb sigma_s" [1 2 3] "float scale" 0.5 "float g" 0.2
AttributeEnd
MediumInterface "smoke" ""
Material "interface"
Shape "sphere"
"#;
    let desc = pbrt("pbrt_ok", text).unwrap();
    let m = &desc.media.media[0];
    // Medium space is world shifted by +1 in x: the box is x ∈ [1, 3]; voxel centres at
    // x = 1.5 (density 1) and 2.5 (density 3); pbrt reads zero outside the grid, so at x = 1.0
    // the density is ½·0 + ½·1.
    let (t, s) = at(m, [2.0, 0.5, 0.5]);
    assert!(close(t, [0.5 * 2.0 * 2.0, 0.5 * 2.0 * 3.0, 0.5 * 2.0 * 4.0]), "{t:?}");
    assert!(close(s, [0.5 * 2.0, 0.5 * 2.0 * 2.0, 0.5 * 2.0 * 3.0]), "{s:?}");
    let (t, _) = at(m, [1.0, 0.5, 0.5]);
    assert!(close(t, [0.5 * 0.5 * 2.0, 0.5 * 0.5 * 3.0, 0.5 * 0.5 * 4.0]), "{t:?}");
    assert!(close(at(m, [0.9, 0.5, 0.5]).0, [0.0; 3]));
    assert_eq!(desc.media.shapes.len(), 1);
}

#[test]
fn pbrt_rgb_grid() {
    let text = r#"WorldBegin
MakeNamedMedium "fire" "string type" "rgbgrid" "integer nx" 2 "float scale" 2
    "rgb sigma_a" [0 0 0  1 2 3] "rgb sigma_s" [1 1 1  3 2 1]
MakeNamedMedium "default" "string type" "rgbgrid" "rgb sigma_s" [0.5 0.25 0]
"#;
    let desc = pbrt("pbrt_rgb", text).unwrap();
    let m = &desc.media.media[0];
    // Voxel centres at x = 0.25 and 0.75; the midpoint averages them: σ_a = (½, 1, 3/2),
    // σ_s = (2, 3/2, 1), times scale 2.
    let (t, s) = at(m, [0.5, 0.5, 0.5]);
    assert!(close(t, [5.0, 5.0, 5.0]) && close(s, [4.0, 3.0, 2.0]), "{t:?} {s:?}");
    let (t, s) = at(m, [0.25, 0.5, 0.5]);
    assert!(close(t, [2.0; 3]) && close(s, [2.0; 3]), "{t:?} {s:?}");
    // An absent grid is 1 everywhere (pbrt-v4).
    let (t, s) = at(&desc.media.media[1], [0.5, 0.5, 0.5]);
    assert!(close(t, [1.5, 1.25, 1.0]) && close(s, [0.5, 0.25, 0.0]), "{t:?} {s:?}");
}

#[test]
fn pbrt_grid_errors_name_file_and_line() {
    let cases = [
        (r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2 "float density" [1]"#, "density values"),
        (r#"MakeNamedMedium "m" "string type" "uniformgrid""#, "density"),
        (r#"MakeNamedMedium "m" "string type" "uniformgrid" "float density" [1] "rgb Le" [1 1 1]"#, "Le"),
        (r#"MakeNamedMedium "m" "string type" "uniformgrid" "float density" [-1]"#, "non-negative"),
        (r#"MakeNamedMedium "m" "string type" "uniformgrid" "float density" [1] "point3 p1" [0 1 1]"#, "empty"),
        (r#"MakeNamedMedium "m" "string type" "rgbgrid" "integer nx" 2 "rgb sigma_s" [1 1 1]"#, "rgb values"),
        (r#"MakeNamedMedium "m" "string type" "nanovdb""#, "needs a \"string filename\""),
    ];
    for (index, (line, needle)) in cases.iter().enumerate() {
        let error = pbrt(&format!("pbrt_err{index}"), &format!("WorldBegin\n{line}\n"))
            .err()
            .unwrap_or_else(|| panic!("{line} loads"));
        assert!(error.contains("scene.pbrt:2:") && error.contains(needle), "{needle}: {error}");
    }
}
