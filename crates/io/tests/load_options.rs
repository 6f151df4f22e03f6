//! What a file says besides the scene (sample counts, `hide_emitters`, the depth of wrapped
//! integrators), the strict and permissive handling of parameters that change the image but
//! cannot be rendered, texture wrap and filter modes, and the messages for old formats and
//! misnamed parameters.

use std::fs;
use std::path::{Path, PathBuf};

use io::{LoadOptions, LoadedScene, SceneError};
use math::Vec2;
use scene::desc::LightDesc;
use scene::material::Material;
use scene::{FilterMode, Sampling, Texture, WrapMode};

const STRICT: LoadOptions = LoadOptions { permissive: false };
const PERMISSIVE: LoadOptions = LoadOptions { permissive: true };

fn scratch_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-options-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` as `<test>/<name>` and loads it.
fn load(test: &str, name: &str, text: &str, options: &LoadOptions) -> (Result<LoadedScene, SceneError>, PathBuf) {
    let dir = scratch_dir(test);
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    (io::load_scene_with(&path, &[], options), path)
}

fn mitsuba(test: &str, body: &str, options: &LoadOptions) -> (Result<LoadedScene, SceneError>, PathBuf) {
    load(test, "scene.xml", &format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n"), options)
}

const PBRT_HEADER: &str = "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n";

fn pbrt(test: &str, text: &str, options: &LoadOptions) -> (Result<LoadedScene, SceneError>, PathBuf) {
    load(test, "scene.pbrt", text, options)
}

/// Asserts an error in `file` at `line` whose message contains every needle.
fn assert_error(result: Result<LoadedScene, SceneError>, file: &Path, line: u32, needles: &[&str]) {
    let e = result.expect_err("expected an error");
    assert_eq!(e.file, file, "{e}");
    assert_eq!(e.line, Some(line), "{e}");
    assert!(e.column.is_some(), "{e}");
    for needle in needles {
        assert!(e.message.contains(needle), "'{needle}' not in: {e}");
    }
}

#[test]
fn mitsuba_sample_counts_from_sensor_and_top_level_samplers() {
    let in_sensor = r#"<sensor type="perspective"><sampler type="stratified"><integer name="sample_count" value="64"/></sampler></sensor>"#;
    let (r, _) = mitsuba("spp_sensor", in_sensor, &STRICT);
    assert_eq!(r.unwrap().settings.samples_per_pixel, Some(64));
    let (r, _) = mitsuba(
        "spp_top",
        r#"<sampler type="independent"><integer name="sample_count" value="9"/></sampler>"#,
        &STRICT,
    );
    assert_eq!(r.unwrap().settings.samples_per_pixel, Some(9));
    // Mitsuba's default sample count is 4; no sampler at all gives none.
    let (r, _) = mitsuba("spp_default", r#"<sampler type="independent"/>"#, &STRICT);
    assert_eq!(r.unwrap().settings.samples_per_pixel, Some(4));
    let (r, _) = mitsuba("spp_none", "", &STRICT);
    assert_eq!(r.unwrap().settings.samples_per_pixel, None);
    let (r, path) = mitsuba(
        "spp_zero",
        r#"<sampler type="independent"><integer name="sample_count" value="0"/></sampler>"#,
        &STRICT,
    );
    assert_error(r, &path, 2, &["sample_count"]);
    let (r, path) = mitsuba("spp_twice", &format!("{in_sensor}\n<sampler type=\"independent\"/>"), &STRICT);
    assert_error(r, &path, 3, &["second <sampler>"]);
}

#[test]
fn pbrt_sampler_pixelsamples() {
    let (r, _) = pbrt(
        "pbrt_spp",
        &format!("Sampler \"zsobol\" \"integer pixelsamples\" 128\n{PBRT_HEADER}WorldBegin\n"),
        &STRICT,
    );
    assert_eq!(r.unwrap().settings.samples_per_pixel, Some(128));
    let (r, _) = pbrt("pbrt_spp_default", &format!("Sampler \"halton\"\n{PBRT_HEADER}WorldBegin\n"), &STRICT);
    assert_eq!(r.unwrap().settings.samples_per_pixel, Some(16));
    let (r, _) = pbrt("pbrt_spp_none", &format!("{PBRT_HEADER}WorldBegin\n"), &STRICT);
    assert_eq!(r.unwrap().settings.samples_per_pixel, None);
    let (r, path) = pbrt("pbrt_spp_bad", "Sampler \"halton\" \"integer pixelsamples\" -2\n", &STRICT);
    assert_error(r, &path, 1, &["pixelsamples"]);
}

#[test]
fn aov_and_moment_use_the_depth_of_the_integrator_they_wrap() {
    for wrapper in ["aov", "moment"] {
        let body = format!(
            r#"<integrator type="{wrapper}"><string name="aovs" value="dd.y:depth"/>
                <integrator type="path" name="image"><integer name="max_depth" value="7"/></integrator>
            </integrator>"#
        );
        let (r, _) = mitsuba(wrapper, &body, &STRICT);
        let s = r.unwrap_or_else(|e| panic!("{e}")).description;
        assert_eq!(s.max_path_length, Some(7), "{wrapper}");
        assert!(s.warnings.iter().any(|w| w.contains(&format!("'{wrapper}'"))), "{:?}", s.warnings);
        assert!(!s.warnings.iter().any(|w| w.contains("nested")), "{:?}", s.warnings);
    }
    // Nested twice; 'direct' inside gives 2 segments.
    let (r, _) = mitsuba(
        "nested_twice",
        r#"<integrator type="moment"><integrator type="aov"><integrator type="direct"/></integrator></integrator>"#,
        &STRICT,
    );
    assert_eq!(r.unwrap().description.max_path_length, Some(2));
}

#[test]
fn hide_emitters_is_an_error_unless_permissive() {
    let body = "<integrator type=\"path\">\n<boolean name=\"hide_emitters\" value=\"true\"/></integrator>";
    let (r, path) = mitsuba("hide", body, &STRICT);
    assert_error(r, &path, 3, &["hide_emitters", "permissive"]);
    let (r, _) = mitsuba("hide_permissive", body, &PERMISSIVE);
    let loaded = r.unwrap();
    assert!(loaded.settings.hide_emitters);
    assert!(
        loaded.description.warnings.iter().any(|w| w.contains("hide_emitters")),
        "{:?}",
        loaded.description.warnings
    );
    // false is fine either way.
    let (r, _) = mitsuba(
        "hide_false",
        r#"<integrator type="path"><boolean name="hide_emitters" value="false"/></integrator>"#,
        &STRICT,
    );
    assert!(!r.unwrap().settings.hide_emitters);
    // The old API is strict.
    assert!(io::load_scene(&path, &[]).is_err());
}

#[test]
fn spot_light_texture_is_projected_in_the_spots_frame() {
    let checks = r#"<rgb name="color0" value="0.1"/><rgb name="color1" value="0.3"/>"#;
    let body = format!(
        "<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"30\"/>\n\
         <texture type=\"checkerboard\" name=\"texture\">{checks}</texture>\n\
         <transform name=\"to_world\"><lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/></transform></emitter>"
    );
    let (r, _) = mitsuba("spot_texture", &body, &STRICT);
    let s = r.unwrap_or_else(|e| panic!("{e}")).description;
    let LightDesc::Spot { texture: Some(t), .. } = &s.lights[0] else { panic!("{:?}", s.lights[0]) };
    // Mitsuba's look-at frame: x = up × direction (left), y = up.
    assert!((t.x_axis - math::Vec3::X).length() < 1e-6 && (t.y_axis - math::Vec3::Y).length() < 1e-6, "{t:?}");
    assert!(matches!(*t.texture, Texture::Checkerboard { .. }));
    // A missing image is an error at the texture, and a cutoff of 90° cannot be projected.
    let missing = "<emitter type=\"spot\">\n<texture type=\"bitmap\" name=\"texture\"><string name=\"filename\" value=\"x.png\"/></texture></emitter>";
    let (r, path) = mitsuba("spot_texture_missing", missing, &PERMISSIVE);
    assert_error(r, &path, 3, &["x.png"]);
    let wide = body.replace("value=\"30\"", "value=\"100\"");
    let (r, path) = mitsuba("spot_texture_wide", &wide, &STRICT);
    assert_error(r, &path, 2, &["cutoff_angle below 90"]);
}

#[test]
fn pbrt_spot_reads_conedeltaangle_and_rejects_the_misnamed_conedelta() {
    let spot = |delta: &str| {
        format!(
            "{PBRT_HEADER}WorldBegin\nLightSource \"spot\" \"float coneangle\" 40 \"float {delta}\" 10 \"rgb I\" [1 1 1]\n"
        )
    };
    let (r, _) = pbrt("conedeltaangle", &spot("conedeltaangle"), &STRICT);
    match r.unwrap().description.lights[0] {
        LightDesc::Spot { cutoff_degrees, beam_width_degrees, .. } => {
            assert_eq!((cutoff_degrees, beam_width_degrees), (40.0, 30.0))
        }
        ref l => panic!("{l:?}"),
    }
    let (r, path) = pbrt("conedelta", &spot("conedelta"), &PERMISSIVE);
    assert_error(r, &path, 3, &["conedeltaangle"]);
}

/// A bitmap texture on a diffuse sphere, with extra properties.
fn mitsuba_bitmap(test: &str, extra: &str, options: &LoadOptions) -> Result<Texture, SceneError> {
    let dir = scratch_dir(test);
    // A 3×1 ramp: codes 0, 128, 255 (raw, so the texels are the codes / 255).
    let ramp = image::RgbImage::from_fn(3, 1, |x, _| image::Rgb([[0, 128, 255][x as usize]; 3]));
    ramp.save(dir.join("ramp.png")).unwrap();
    let body = format!(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
        <string name="filename" value="ramp.png"/><boolean name="raw" value="true"/>{extra}</texture></bsdf></shape>"#
    );
    let path = dir.join("scene.xml");
    fs::write(&path, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    let s = io::load_scene_with(&path, &[], options)?.description;
    match &s.materials[s.shapes[0].material as usize] {
        Material::Diffuse { reflectance } => Ok(reflectance.clone()),
        m => panic!("{m:?}"),
    }
}

#[test]
fn mitsuba_bitmap_wrap_and_filter_modes_are_applied() {
    let at = |t: &Texture, u: f32| t.eval(Vec2::new(u, 0.5)).r;
    let (t0, t1, t2) = (0.0, 128.0 / 255.0, 1.0);
    // Default: repeat + bilinear, the plain bitmap.
    let t = mitsuba_bitmap("bitmap_default", "", &STRICT).unwrap();
    assert!(matches!(t, Texture::Bitmap { .. }));
    let cases = [
        ("mirror", "bilinear", WrapMode::Mirror, FilterMode::Bilinear),
        ("clamp", "nearest", WrapMode::Clamp, FilterMode::Nearest),
        ("repeat", "nearest", WrapMode::Repeat, FilterMode::Nearest),
    ];
    for (wrap, filter, wrap_mode, filter_mode) in cases {
        let extra =
            format!(r#"<string name="wrap_mode" value="{wrap}"/><string name="filter_type" value="{filter}"/>"#);
        let t = mitsuba_bitmap(&format!("bitmap_{wrap}_{filter}"), &extra, &STRICT).unwrap_or_else(|e| panic!("{e}"));
        match &t {
            Texture::SampledBitmap { sampling, .. } => {
                assert_eq!(*sampling, Sampling { wrap: wrap_mode, filter: filter_mode });
            }
            t => panic!("{t:?}"),
        }
        // At u = 0, half a texel left of texel 0's centre: mirror blends texel 0 with its
        // mirror image (texel 0); nearest takes texel floor(0 · 3) = 0. Just below u = 0 the
        // neighbour is texel 2 under repeat and texel 0 under mirror and clamp.
        assert!((at(&t, 0.0) - t0).abs() < 1e-6, "{wrap} {filter}");
        let below = match wrap_mode {
            WrapMode::Repeat => t2,
            _ => t0,
        };
        assert!((at(&t, -0.01) - below).abs() < 1e-6, "{wrap} {filter}");
        // Nearest never blends: a quarter texel right of the middle centre is the middle texel.
        if filter_mode == FilterMode::Nearest {
            assert!((at(&t, 1.75 / 3.0) - t1).abs() < 1e-6);
        }
    }
    for (extra, needle) in [
        (r#"<string name="wrap_mode" value="wobble"/>"#, "wrap_mode"),
        (r#"<string name="filter_type" value="cubic"/>"#, "filter_type"),
    ] {
        let e = mitsuba_bitmap("bitmap_bad", extra, &PERMISSIVE).unwrap_err();
        assert!(e.message.contains(needle), "{e}");
    }
}

#[test]
fn pbrt_imagemap_filter_and_wrap() {
    let dir = scratch_dir("pbrt_filter");
    image::RgbImage::from_fn(2, 2, |x, _| image::Rgb([[0, 255][x as usize]; 3])).save(dir.join("t.png")).unwrap();
    let load = |params: &str, options: &LoadOptions| {
        let path = dir.join("scene.pbrt");
        fs::write(
            &path,
            format!(
                "{PBRT_HEADER}WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"t.png\"\n  {params}\n\
                 Material \"diffuse\" \"texture reflectance\" \"t\"\nShape \"sphere\"\n"
            ),
        )
        .unwrap();
        (io::load_scene_with(&path, &[], options), path)
    };
    let sampling = |r: Result<LoadedScene, SceneError>| {
        let s = r.unwrap_or_else(|e| panic!("{e}")).description;
        match &s.materials[s.shapes[0].material as usize] {
            Material::TwoSided { front, .. } => match front.as_ref() {
                Material::Diffuse { reflectance: Texture::SampledBitmap { sampling, .. } } => Some(*sampling),
                Material::Diffuse { reflectance: Texture::Bitmap { .. } } => None,
                m => panic!("{m:?}"),
            },
            m => panic!("{m:?}"),
        }
    };
    assert_eq!(sampling(load("", &STRICT).0), None);
    assert_eq!(
        sampling(load("\"string filter\" \"point\" \"string wrap\" \"clamp\"", &STRICT).0),
        Some(Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Nearest })
    );
    assert_eq!(
        sampling(load("\"string wrap\" \"black\"", &STRICT).0),
        Some(Sampling { wrap: WrapMode::Black, filter: FilterMode::Bilinear })
    );
    // MIP-mapped filters change the image: errors unless permissive (then bilinear).
    for filter in ["ewa", "trilinear"] {
        let (r, path) = load(&format!("\"string filter\" \"{filter}\""), &STRICT);
        assert_error(r, &path, 4, &[filter, "not supported", "permissive"]);
        let (r, _) = load(&format!("\"string filter\" \"{filter}\""), &PERMISSIVE);
        let warnings = r.as_ref().unwrap().description.warnings.clone();
        assert_eq!(sampling(r), None);
        assert!(warnings.iter().any(|w| w.contains(filter)), "{warnings:?}");
    }
    let (r, path) = load("\"string wrap\" \"octahedralsphere\"", &PERMISSIVE);
    assert_error(r, &path, 4, &["octahedralsphere"]);
}

#[test]
fn old_mitsuba_formats_say_so() {
    let (r, path) =
        load("old_version", "old.xml", "<scene version=\"0.6.0\">\n<shape type=\"sphere\"/>\n</scene>\n", &PERMISSIVE);
    assert_error(r, &path, 1, &["0.6.0", "old format", "not supported"]);
    let film = "<sensor type=\"perspective\">\n<film type=\"ldrfilm\"/></sensor>";
    let (r, path) = mitsuba("ldrfilm", film, &PERMISSIVE);
    assert_error(r, &path, 3, &["ldrfilm", "old format", "not supported"]);
}

#[test]
fn volume_textures_are_named_as_such() {
    let body = "<shape type=\"sphere\"><bsdf type=\"diffuse\">\n<texture type=\"volume\" name=\"reflectance\">\
                <volume type=\"gridvolume\" name=\"volume\"><string name=\"filename\" value=\"v.vol\"/></volume>\
                </texture></bsdf></shape>";
    let (r, path) = mitsuba("volume_texture", body, &PERMISSIVE);
    assert_error(r, &path, 3, &["<texture type=\"volume\">", "not supported"]);
}

#[test]
fn integrators_and_filters_that_change_the_image_are_errors_unless_permissive() {
    let cases = [
        ("mi_depth", "<integrator type=\"depth\"/>", 2, "'depth'"),
        (
            "mi_box",
            "<sensor type=\"perspective\"><film type=\"hdrfilm\">\n<rfilter type=\"box\"><float name=\"radius\" value=\"1\"/></rfilter></film></sensor>",
            3,
            "radius 1",
        ),
    ];
    for (test, body, line, needle) in cases {
        let (r, path) = mitsuba(test, body, &STRICT);
        assert_error(r, &path, line, &[needle, "not supported", "permissive"]);
        let (r, _) = mitsuba(test, body, &PERMISSIVE);
        let s = r.unwrap_or_else(|e| panic!("{e}")).description;
        assert!(s.warnings.iter().any(|w| w.contains(needle)), "{:?}", s.warnings);
    }
    let pbrt_cases = [
        ("pbrt_ao", "Integrator \"ambientocclusion\"\n", "ambientocclusion"),
        ("pbrt_regularize", "Integrator \"volpath\" \"bool regularize\" true\n", "regularize"),
    ];
    for (test, integrator, needle) in pbrt_cases {
        let text = format!("{integrator}{PBRT_HEADER}WorldBegin\n");
        let (r, path) = pbrt(test, &text, &STRICT);
        assert_error(r, &path, 1, &[needle, "not supported", "permissive"]);
        let (r, _) = pbrt(test, &text, &PERMISSIVE);
        let s = r.unwrap_or_else(|e| panic!("{e}")).description;
        assert!(s.warnings.iter().any(|w| w.contains(needle)), "{:?}", s.warnings);
    }
    // The light-transport integrators load quietly.
    let (r, _) =
        pbrt("pbrt_bdpt", &format!("Integrator \"bdpt\" \"integer maxdepth\" 3\n{PBRT_HEADER}WorldBegin\n"), &STRICT);
    assert_eq!(r.unwrap().description.max_path_length, Some(4));
}

#[test]
fn textures_on_constant_only_parameters_are_errors_unless_permissive() {
    // A checkerboard of 0.1 and 0.3: its mean over uv ∈ [0, 1]² is 0.2.
    let checks = r#"<rgb name="color0" value="0.1"/><rgb name="color1" value="0.3"/>"#;
    let rough = format!(
        "<shape type=\"sphere\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"ggx\"/>\n\
         <texture type=\"checkerboard\" name=\"alpha\">{checks}</texture></bsdf></shape>"
    );
    // A textured roughness is supported (crates/io/tests/bsdf_maps.rs): it loads strictly.
    let (r, _) = mitsuba("textured_alpha", &rough, &STRICT);
    let s = r.unwrap_or_else(|e| panic!("{e}")).description;
    match &s.materials[s.shapes[0].material as usize] {
        Material::TexturedRoughness { alpha_u, remap: false, .. } => {
            assert!(matches!(alpha_u, scene::Texture::Checkerboard { .. }), "{alpha_u:?}");
        }
        m => panic!("{m:?}"),
    }

    let emitter = format!(
        "<shape type=\"sphere\"><emitter type=\"area\">\n<texture type=\"checkerboard\" name=\"radiance\">{checks}</texture>\
         </emitter></shape>"
    );
    let (r, path) = mitsuba("textured_radiance", &emitter, &STRICT);
    assert_error(r, &path, 2, &["'radiance'", "triangle meshes", "permissive"]);
    let (r, _) = mitsuba("textured_radiance", &emitter, &PERMISSIVE);
    let s = r.unwrap_or_else(|e| panic!("{e}")).description;
    let e = s.shapes[0].emission.unwrap();
    assert!((e.r - 0.2).abs() < 1e-6 && (e.b - 0.2).abs() < 1e-6, "{e:?}");
    assert!(s.emission_spectra.textures.is_empty());
    // On a mesh (a rectangle) the texture is kept for the triangle emitters.
    let rectangle = emitter.replace("type=\"sphere\"", "type=\"rectangle\"");
    let (r, _) = mitsuba("textured_radiance_mesh", &rectangle, &STRICT);
    let s = r.unwrap_or_else(|e| panic!("{e}")).description;
    assert!(matches!(s.emission_spectra.textures.get(&0).map(|t| &**t), Some(Texture::Checkerboard { .. })));
}

#[test]
fn pbrt_diffuse_area_light_image_textures_meshes_only() {
    // A 2×1 image, codes 0 and 255 (sRGB: linear 0 and 1), scaled by 3, looked up at (u, 1 − v).
    let dir = scratch_dir("pbrt_area_image");
    let image = image::RgbImage::from_fn(2, 1, |x, _| image::Rgb([[0, 255][x as usize]; 3]));
    image.save(dir.join("glow.png")).unwrap();
    let light = "AreaLightSource \"diffuse\" \"string filename\" \"glow.png\" \"float scale\" 3\n";
    let mesh = "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] \
                \"point2 uv\" [0 0 1 0 0 1]\n";
    let path = dir.join("scene.pbrt");
    fs::write(&path, format!("{PBRT_HEADER}WorldBegin\n{light}{mesh}")).unwrap();
    let s = io::load_scene_with(&path, &[], &STRICT).unwrap_or_else(|e| panic!("{e}")).description;
    let texture = s.emission_spectra.textures.get(&0).expect("the mesh's emission texture");
    assert!((texture.eval(Vec2::new(0.25, 0.5)).r - 0.0).abs() < 1e-6);
    assert!((texture.eval(Vec2::new(0.75, 0.5)).g - 3.0).abs() < 1e-5);
    assert!(s.shapes[0].emission.is_some());
    // 'L' and 'filename' exclude each other; spheres cannot carry the image.
    let both = light.replace("\"float scale\" 3", "\"rgb L\" [1 1 1]");
    fs::write(&path, format!("{PBRT_HEADER}WorldBegin\n{both}{mesh}")).unwrap();
    assert_error(io::load_scene_with(&path, &[], &STRICT), &path, 3, &["'L' and 'filename'"]);
    fs::write(&path, format!("{PBRT_HEADER}WorldBegin\n{light}Shape \"sphere\"\n")).unwrap();
    assert_error(io::load_scene_with(&path, &[], &STRICT), &path, 4, &["triangle mesh"]);
}
