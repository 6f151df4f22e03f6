//! The initial merging radius at medium vertices (`render::vcm::radius::base_volume_radius`):
//! the volume scale is the merging scale or the smallest bounded medium, whichever is smaller,
//! and the global mode shrinks it with the cube root of the pixel count above 512².

use std::path::Path;

use render::vcm::radius::{MergingScale, smallest_medium_radius};
use render::vcm::{RadiusMode, VcmAlgorithm, VcmSettings, base_radius, base_volume_radius};
use scene::Scene;
use testkit::TempDir;

fn settings(mode: RadiusMode) -> VcmSettings {
    VcmSettings { radius_mode: mode, ..VcmSettings::new(VcmAlgorithm::VertexConnectionMerging) }
}

fn load(path: &Path, resolution: u32) -> Scene {
    let desc = io::load_scene(path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, Some((resolution, resolution))).unwrap().0
}

/// Writes a Mitsuba scene to a temporary file: a diffuse floor of half-size 5 seen from above
/// and `media` (XML of shapes and media) around the origin.
fn scene_with(name: &str, media: &str, resolution: u32) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0, 0, 8" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5"/><translate z="-1"/></transform>
        <bsdf type="diffuse"/>
    </shape>
    <emitter type="constant"/>
    {media}
</scene>"#
    );
    let dir = TempDir::new("volume-radius");
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    load(&path, resolution)
}

const FOG: &str = r#"<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="1, 1, 1"/><rgb name="albedo" value="0.5, 0.5, 0.5"/></medium>"#;

/// The fog and a sphere of radius 0.4 with BSDF `bsdf` that names the fog on its `side`
/// (`interior` or `exterior`).
fn fog_sphere(bsdf: &str, side: &str) -> String {
    format!(
        r#"{FOG}
    <shape type="sphere"><float name="radius" value="0.4"/><bsdf type="{bsdf}"/><ref id="fog" name="{side}"/></shape>"#
    )
}

#[test]
fn the_fog_box_is_the_volume_scale_of_cornell_fog() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-fog.xml");
    let scene = load(&path, 128);
    // The fog fills a cube of half-edge 0.995 (its interior); the glass sphere names it only
    // as its exterior and does not bound it.
    let fog = smallest_medium_radius(&scene).expect("the fog is bounded");
    assert!((fog - 0.995 * 3f32.sqrt()).abs() < 1e-5, "fog radius {fog}");
    let view = MergingScale::of(&scene).scale;
    let expected = 0.025 * fog.min(view);
    let global = base_volume_radius(&scene, &settings(RadiusMode::Global));
    assert!((global - expected).abs() <= 1e-6 * expected, "{global} vs {expected}");
    // The surface radius is unchanged by the media.
    assert_eq!(base_radius(&scene, &settings(RadiusMode::Global)), 0.003 * view);
}

#[test]
fn a_small_medium_sets_the_volume_scale() {
    // A null sphere of radius 0.4 filled with fog in a scene seen over ±5 units: the ball must
    // be small against the sphere, not against the view.
    let scene = scene_with("small", &fog_sphere("null", "interior"), 64);
    let small = smallest_medium_radius(&scene).unwrap();
    assert!((small - 0.4 * 3f32.sqrt()).abs() < 1e-5, "{small}");
    assert!(MergingScale::of(&scene).scale > 4.0 * small);
    let radius = base_volume_radius(&scene, &settings(RadiusMode::Global));
    assert!((radius - 0.025 * small).abs() < 1e-7, "{radius}");
}

#[test]
fn a_medium_named_only_outside_objects_is_unbounded() {
    // A glass sphere names the fog as its exterior: the fog around it has no bound.
    let scene = scene_with("outside", &fog_sphere("dielectric", "exterior"), 64);
    assert_eq!(smallest_medium_radius(&scene), None);
    let radius = base_volume_radius(&scene, &settings(RadiusMode::Global));
    assert_eq!(radius, 0.025 * MergingScale::of(&scene).scale);
}

#[test]
fn global_volume_radius_keeps_the_expected_vertices_per_query_above_512_squared() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-fog.xml");
    let radius = |resolution: u32, mode| base_volume_radius(&load(&path, resolution), &settings(mode));
    let unscaled = radius(512, RadiusMode::Global);
    assert_eq!(radius(128, RadiusMode::Global), unscaled);
    assert_eq!(radius(1024, RadiusMode::Fixed), unscaled);
    // N_L r_V³ constant: 4× the pixels, the radius × 4^(−1/3).
    let scaled = radius(1024, RadiusMode::Global);
    assert!((scaled / unscaled - 0.25f32.cbrt()).abs() < 1e-6, "{}", scaled / unscaled);
}
