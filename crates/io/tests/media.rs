//! Participating media in both loaders: Mitsuba 3's `<medium type="homogeneous">` with its
//! `<phase>`, `interior`/`exterior` references, the sensor's medium and the `null` BSDF; pbrt-v4's
//! `MakeNamedMedium`, `MediumInterface`, the camera's medium and the `interface` material; and
//! the errors for what is not supported (file, line and feature).

use std::path::PathBuf;

use scene::desc::SceneDescription;
use scene::medium::{Coefficients, MediumInterface, PhaseFunction};
use spectrum::Rgb;
use testkit::TempDir;

/// Writes `text` to `name` in a fresh directory; returns the directory's guard (keep it while
/// the file is used) and the file's path.
fn write(test: &str, name: &str, text: &str) -> (TempDir, PathBuf) {
    let dir = TempDir::new(&format!("media-test-{test}"));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

fn mitsuba(test: &str, body: &str) -> Result<SceneDescription, String> {
    let (_dir, path) = write(test, "scene.xml", &format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n"));
    io::mitsuba::load(&path, &[]).map_err(|e| e.to_string())
}

fn pbrt(test: &str, text: &str) -> Result<SceneDescription, String> {
    let (_dir, path) = write(test, "scene.pbrt", text);
    io::pbrt::load(&path).map_err(|e| e.to_string())
}

const MITSUBA_SCENE: &str = r#"<medium type="homogeneous" id="fog">
    <rgb name="sigma_t" value="1, 2, 3"/>
    <rgb name="albedo" value="0.9, 0.8, 0.7"/>
    <float name="scale" value="0.5"/>
    <phase type="hg"><float name="g" value="0.4"/></phase>
</medium>
<sensor type="perspective">
    <ref id="fog"/>
</sensor>
<shape type="sphere">
    <bsdf type="null"/>
    <ref name="interior" id="fog"/>
</shape>
<shape type="rectangle">
    <bsdf type="diffuse"/>
    <medium type="homogeneous" name="exterior"><float name="sigma_t" value="2"/></medium>
</shape>
<shape type="sphere"><float name="radius" value="0.1"/></shape>"#;

#[test]
fn mitsuba_media_interfaces_sensor_and_null() {
    let desc = mitsuba("mitsuba_ok", MITSUBA_SCENE).unwrap();
    let media = &desc.media;
    assert_eq!(media.media.len(), 2);
    assert_eq!(media.camera, Some(0));
    let fog = &media.media[0];
    assert_eq!(fog.scale, 0.5);
    assert_eq!(fog.phase, PhaseFunction::HenyeyGreenstein { g: 0.4 });
    match &fog.coefficients {
        Coefficients::ExtinctionAlbedo { sigma_t, albedo } => {
            assert_eq!((sigma_t.rgb, albedo.rgb), (Rgb::new(1.0, 2.0, 3.0), Rgb::new(0.9, 0.8, 0.7)));
        }
        other => panic!("{other:?}"),
    }
    // Mitsuba's defaults: albedo 0.75, isotropic phase.
    let c = media.media[1].coefficients::<Rgb>(&());
    assert!((c.sigma_t.g - 2.0).abs() < 1e-6 && (c.sigma_s.g - 1.5).abs() < 1e-6, "{c:?}");
    assert_eq!(media.media[1].phase, PhaseFunction::Isotropic);
    assert_eq!(media.shapes.get(&0), Some(&MediumInterface { interior: Some(0), exterior: None }));
    assert_eq!(media.shapes.get(&1), Some(&MediumInterface { interior: None, exterior: Some(1) }));
    assert_eq!(media.shapes.get(&2), None);
    assert_eq!(media.null_materials, vec![desc.shapes[0].material]);
    // The scene builds, and its primitives carry the interfaces.
    let (scene, _) = scene::Scene::from_description(&desc, Some((4, 4))).unwrap();
    assert!(scene.media.is_active() && scene.media.is_null(scene.primitives[0].material));
    assert_eq!(scene.media.interface(0), media.shapes.get(&0).copied());
    assert_eq!(scene.media.interface(scene.primitives.len() as u32 - 1), None);
}

#[test]
fn mitsuba_unsupported_media_are_errors() {
    let cases = [
        (r#"<medium type="heterogeneous" id="m"><volume type="procedural" name="sigma_t"/></medium>"#, "procedural"),
        (
            r#"<medium type="heterogeneous" id="m"><volume type="gridvolume" name="albedo"><string name="filename" value="none.vol"/></volume></medium>"#,
            "none.vol",
        ),
        (r#"<medium type="checkerboard" id="m"/>"#, "checkerboard"),
        (r#"<medium type="homogeneous" id="m"><phase type="rayleigh"/></medium>"#, "rayleigh"),
        (r#"<medium type="homogeneous" id="m"><volume type="gridvolume" name="sigma_t"/></medium>"#, "volume data"),
        (r#"<medium type="homogeneous" id="m"><rgb name="albedo" value="1.5"/></medium>"#, "albedo"),
        (r#"<shape type="sphere"><bsdf type="twosided"><bsdf type="null"/></bsdf></shape>"#, "null bsdf"),
        (r#"<medium type="homogeneous" id="m"/><shape type="sphere"><ref name="inside" id="m"/></shape>"#, "interior"),
    ];
    for (index, (body, needle)) in cases.iter().enumerate() {
        let error = mitsuba(&format!("mitsuba_err{index}"), body).err().unwrap_or_else(|| panic!("{body} loads"));
        assert!(error.contains("scene.xml:") && error.contains(needle), "{error}");
    }
}

const PBRT_SCENE: &str = r#"MediumInterface "" "air"
MakeNamedMedium "air" "string type" "homogeneous" "rgb sigma_a" [0.1 0.2 0.3] "float sigma_s" 2 "float scale" 3 "float g" -0.3
Camera "perspective"
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
WorldBegin
MakeNamedMedium "smoke" "string type" "homogeneous" "spectrum sigma_s" [400 1 700 2]
AttributeBegin
  MediumInterface "smoke" ""
  Material "interface"
  Shape "sphere"
AttributeEnd
MakeNamedMaterial "boundary" "string type" "interface"
AttributeBegin
  MediumInterface "smoke"
  NamedMaterial "boundary"
  Shape "sphere" "float radius" 2
AttributeEnd
Shape "sphere" "float radius" 3
"#;

#[test]
fn pbrt_media_interfaces_camera_and_interface_material() {
    // The camera's medium is the outside medium current at `Camera`; "air" is defined after
    // the interface names it, so that is an error, and defined first it loads.
    let error = pbrt("pbrt_order", PBRT_SCENE).err().unwrap();
    assert!(error.contains("scene.pbrt:1:") && error.contains("unknown medium \"air\""), "{error}");
    let lines: Vec<&str> = PBRT_SCENE.lines().collect();
    let reordered = format!("{}\n{}\n{}", lines[1], lines[0], lines[2..].join("\n"));
    let desc = pbrt("pbrt_ok", &reordered).unwrap();
    let media = &desc.media;
    assert_eq!((media.media.len(), media.camera), (2, Some(0)));
    let air = media.media[0].coefficients::<Rgb>(&());
    assert!((air.sigma_t.r - 3.0 * 2.1).abs() < 1e-5 && (air.sigma_s.b - 6.0).abs() < 1e-5, "{air:?}");
    assert_eq!(media.media[0].phase, PhaseFunction::HenyeyGreenstein { g: -0.3 });
    match &media.media[1].coefficients {
        Coefficients::AbsorptionScattering { sigma_s, .. } => assert!(sigma_s.spectrum.is_some()),
        other => panic!("{other:?}"),
    }
    // The first sphere bounds "smoke"; the second has the same medium on both sides (no
    // transition in pbrt-v4); the third keeps the interface current before the world ("" "air").
    assert_eq!(media.shapes.len(), 2);
    assert_eq!(media.shapes.get(&0), Some(&MediumInterface { interior: Some(1), exterior: None }));
    assert_eq!(media.shapes.get(&2), Some(&MediumInterface { interior: None, exterior: Some(0) }));
    let mut nulls = media.null_materials.clone();
    nulls.sort();
    assert_eq!(nulls, vec![desc.shapes[0].material, desc.shapes[1].material]);
    assert!(!nulls.contains(&desc.shapes[2].material));
}

#[test]
fn pbrt_unsupported_media_are_errors() {
    let cases = [
        (r#"MakeNamedMedium "m" "string type" "cloud""#, "cloud"),
        (r#"MakeNamedMedium "m" "string type" "homogeneous" "string preset" "Skin1""#, "preset"),
        (r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb Le" [1 1 1]"#, "Le"),
        (r#"MediumInterface "nowhere""#, "unknown medium"),
    ];
    for (index, (line, needle)) in cases.iter().enumerate() {
        let text = format!("WorldBegin\n{line}\n");
        let error = pbrt(&format!("pbrt_err{index}"), &text).err().unwrap_or_else(|| panic!("{line} loads"));
        assert!(error.contains("scene.pbrt:2:") && error.contains(needle), "{error}");
    }
}

/// `scenes/cornell-fog.xml` loads as written: one fog medium inside a null cube, a glass
/// sphere with fog outside and vacuum inside, the camera in vacuum, one spot light.
#[test]
fn the_repository_fog_scene_loads() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-fog.xml");
    let d = io::mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    assert_eq!(d.media.media.len(), 1);
    assert_eq!(d.media.camera, None);
    assert_eq!(d.lights.len(), 1);
    let interfaces: Vec<MediumInterface> = d.media.shapes.values().copied().collect();
    assert!(interfaces.contains(&MediumInterface { interior: Some(0), exterior: None }), "{interfaces:?}");
    assert!(interfaces.contains(&MediumInterface { interior: None, exterior: Some(0) }), "{interfaces:?}");
    assert_eq!(d.media.null_materials.len(), 1);
}
