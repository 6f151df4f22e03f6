//! Light selection of scenes loaded from files: the defensive uniform half of the selection
//! mixture is shared per emitter of the file, so a point light's pick probability does not
//! depend on how finely an emitting mesh beside it is tessellated (it did when every triangle
//! counted as an emitter: Mitsuba's `various_emitters` scene, whose flower sphere has 32 512
//! triangles, left its spot lights 3 % of the next-event samples).

use std::path::PathBuf;

use io::mitsuba::load;
use math::PI;
use scene::Scene;
use testkit::TempDir;

/// A z = 0 unit square, split into `n × n` quads (2 n² triangles) facing +z, as OBJ text.
fn grid_obj(n: usize) -> String {
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            text += &format!("v {} {} 0\n", i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5);
        }
    }
    let vertex = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1));
            text += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    text
}

/// A scene with an emitting square of `n × n` quads (radiance 1, area 1, 2 m above the floor)
/// and a point light of intensity 1; returns the scene and the point light's index.
fn scene_with_grid(n: usize) -> (Scene, u32) {
    let dir = TempDir::new("light-selection");
    std::fs::write(dir.join("grid.obj"), grid_obj(n)).unwrap();
    let path: PathBuf = dir.join("scene.xml");
    std::fs::write(
        &path,
        r#"<scene version="3.0.0">
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    <shape type="obj">
        <string name="filename" value="grid.obj"/>
        <transform name="to_world"><rotate x="1" angle="180"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
    <shape type="rectangle"/>
    <emitter type="point"><point name="position" x="0" y="1" z="0"/><rgb name="intensity" value="1"/></emitter>
</scene>
"#,
    )
    .unwrap();
    let desc = load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let (scene, _) = Scene::from_description(&desc, None).unwrap();
    let point = scene.lights.len() as u32 - 1;
    assert!(matches!(scene.lights[point as usize], scene::Light::Point(_)));
    (scene, point)
}

#[test]
fn a_point_lights_pick_probability_does_not_depend_on_the_tessellation_of_a_mesh_emitter() {
    // Independent truth: two emitters, powers π·A·L = π (the square) and 4π·I = 4π (the
    // point): ½ · 4π/5π + ½ · ½ = 0.65 for the point, whatever the square's triangle count.
    let expected = 0.5 * (4.0 * PI) / (5.0 * PI) + 0.25;
    for n in [1, 4, 40] {
        let (scene, point) = scene_with_grid(n);
        // One quad (two triangles tiling a square) is one parallelogram light.
        let square_lights = if n == 1 { 1 } else { 2 * n * n };
        assert_eq!(scene.lights.len(), square_lights + 1);
        let p = scene.light_pick_probability(point);
        assert!((p - expected).abs() < 1e-5, "{n}×{n} quads: the point light is picked with {p}, expected {expected}");
        // The square's lights share the rest in proportion to their area (equal here).
        let triangle = scene.light_pick_probability(0);
        let share = (1.0 - expected) / square_lights as f32;
        assert!((triangle - share).abs() < 1e-4 * share, "{n}×{n} quads: a triangle gets {triangle}, expected {share}");
    }
}
