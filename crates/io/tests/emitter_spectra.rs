//! Spectral emitters and the fluorescent material in scene files: Mitsuba `<spectrum>` and
//! blackbody emitters keep their spectrum beside their RGB value, pbrt-v4 blackbody and sampled
//! lights too (normalised to luminance 1); `<bsdf type="fluorescent">` and its errors; and a
//! directly seen spectral emitter renders, in expectation, exactly the colour of its spectrum.

use std::path::PathBuf;

use io::SceneError;
use io::mitsuba::{load, tabulated_spectrum_to_rgb, xyz_to_linear_srgb};
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::Scene;
use scene::desc::{EmissionSpectrum, SceneDescription};
use scene::material::Material;
use spectrum::Rgb;
use testkit::{MeanVar, TempDir, sidak, z_test_p};

/// Writes `body` to `scene.{extension}` in a fresh directory; returns the directory's guard
/// (keep it while the file is used) and the file's path.
fn write_scene(body: &str, extension: &str) -> (TempDir, PathBuf) {
    let dir = TempDir::new("emitter-spectra");
    let path = dir.join(format!("scene.{extension}"));
    std::fs::write(&path, body).unwrap();
    (dir, path)
}

fn mitsuba(body: &str) -> Result<SceneDescription, (SceneError, PathBuf)> {
    let (_dir, path) = write_scene(&format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n"), "xml");
    load(&path, &[]).map_err(|e| (e, path))
}

fn mitsuba_ok(body: &str) -> SceneDescription {
    mitsuba(body).unwrap_or_else(|(e, _)| panic!("{e}"))
}

/// The error of a Mitsuba scene body; asserts it is at `line` of the file (the body starts on
/// line 2) and mentions every needle.
fn mitsuba_error(body: &str, line: u32, needles: &[&str]) {
    let (e, path) = match mitsuba(body) {
        Ok(_) => panic!("expected an error for\n{body}"),
        Err(x) => x,
    };
    let text = e.to_string();
    assert_eq!(e.file, path, "{text}");
    assert_eq!(e.line, Some(line), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

/// Planck's law written out here (W·m⁻²·sr⁻¹·nm⁻¹), CODATA constants.
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    let (h, c, k) = (6.626_070_15e-34, 299_792_458.0, 1.380_649e-23);
    let l = lambda_nm * 1e-9;
    2.0 * h * c * c / (l.powi(5) * ((h * c / (l * k * kelvin)).exp() - 1.0)) * 1e-9
}

/// `∫ s (x̄, ȳ, z̄) dλ / ∫ ȳ dλ` over 360–830 nm by a 0.01 nm midpoint rule, with the CIE tables
/// of `spectrum::cie` (linearly interpolated).
fn brute_xyz(s: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0f64; 3];
    for i in 0..47_000 {
        let l = 360.0 + (i as f64 + 0.5) * 0.01;
        let c = spectrum::cie::cmf(l as f32);
        for k in 0..3 {
            xyz[k] += s(l) * f64::from(c[k]) * 0.01 / spectrum::cie::CIE_Y_INTEGRAL;
        }
    }
    xyz
}

fn assert_rgb(a: Rgb, b: [f64; 3], relative: f64) {
    let a = a.to_array();
    for c in 0..3 {
        assert!((f64::from(a[c]) - b[c]).abs() <= relative * b[c].abs().max(1e-3), "{a:?} vs {b:?}");
    }
}

const TABLE: &str = "400:0, 500:8, 600:15.6, 700:18.4";
const TABLE_POINTS: [(f64, f64); 4] = [(400.0, 0.0), (500.0, 8.0), (600.0, 15.6), (700.0, 18.4)];

#[test]
fn mitsuba_tabulated_and_constant_emitters_keep_their_spectrum() {
    let d = mitsuba_ok(&format!(
        r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
        <shape type="rectangle"><emitter type="area"><spectrum name="radiance" value="{TABLE}"/></emitter></shape>
        <emitter type="point"><spectrum name="intensity" value="5"/></emitter>
        <emitter type="point"><rgb name="intensity" value="5"/></emitter>"#
    ));
    assert_eq!(d.emission_spectra.shapes.len(), 1);
    assert_eq!(d.emission_spectra.lights.len(), 1);
    // The RGB value stays what the RGB variants compute.
    let rgb = tabulated_spectrum_to_rgb(&TABLE_POINTS, true);
    assert_rgb(d.shapes[1].emission.unwrap(), rgb, 1e-6);
    let Some(EmissionSpectrum::Tabulated(t)) = d.emission_spectra.shapes.get(&1) else {
        panic!("{:?}", d.emission_spectra)
    };
    let points: Vec<(f32, f32)> = t.points().collect();
    assert_eq!(points, TABLE_POINTS.map(|(l, v)| (l as f32, v as f32)));
    // A constant spectrum emits the same value at every wavelength (Mitsuba's `uniform`).
    let Some(EmissionSpectrum::Tabulated(flat)) = d.emission_spectra.lights.get(&0) else {
        panic!("{:?}", d.emission_spectra)
    };
    for lambda in [360.0, 455.5, 830.0] {
        assert_eq!(flat.eval(lambda), 5.0);
    }
}

#[test]
fn mitsuba_blackbody_emitters_in_both_forms() {
    let d = mitsuba_ok(
        r#"<shape type="rectangle"><emitter type="area">
            <spectrum type="blackbody" name="radiance"><float name="temperature" value="3000"/></spectrum>
        </emitter></shape>
        <emitter type="spot"><blackbody name="intensity" temperature="5000K" scale="0.25"/></emitter>"#,
    );
    assert_eq!(d.emission_spectra.shapes.get(&0), Some(&EmissionSpectrum::Blackbody { kelvin: 3000.0, scale: 1.0 }));
    assert_eq!(d.emission_spectra.lights.get(&0), Some(&EmissionSpectrum::Blackbody { kelvin: 5000.0, scale: 0.25 }));
    // The RGB value is the colour of the absolute spectral radiance (emission normalisation,
    // Mitsuba's XYZ → sRGB matrix).
    let truth = |kelvin: f64, scale: f64| xyz_to_linear_srgb(brute_xyz(|l| scale * planck(l, kelvin)));
    assert_rgb(d.shapes[0].emission.unwrap(), truth(3000.0, 1.0), 1e-4);
    let scene::desc::LightDesc::Spot { intensity, .. } = d.lights[0] else { panic!() };
    assert_rgb(intensity, truth(5000.0, 0.25), 1e-4);
}

#[test]
fn bad_blackbodies_are_errors_with_positions() {
    mitsuba_error(
        r#"<shape type="rectangle"><emitter type="area">
            <blackbody name="radiance" temperature="-3"/></emitter></shape>"#,
        3,
        &["temperature", "positive"],
    );
    mitsuba_error(
        r#"<shape type="rectangle"><emitter type="area">
            <spectrum type="blackbody" name="radiance"><float name="scale" value="2"/></spectrum></emitter></shape>"#,
        3,
        &["missing", "temperature"],
    );
    mitsuba_error(
        r#"<bsdf type="diffuse">
            <blackbody name="reflectance" temperature="3000"/></bsdf>"#,
        3,
        &["blackbody", "emitted"],
    );
    mitsuba_error(
        r#"<shape type="rectangle"><emitter type="area">
            <spectrum type="d65" name="radiance"/></emitter></shape>"#,
        3,
        &["unsupported spectrum type 'd65'"],
    );
}

const FLUORESCENT: &str = r#"<bsdf type="fluorescent" id="glow">
    <rgb name="reflectance" value="0.2, 0.3, 0.4"/>
    <float name="absorption_peak" value="0.6"/>
    <float name="absorption_center" value="450"/>
    <float name="absorption_width" value="40"/>
    <float name="emission_center" value="560"/>
    <float name="emission_width" value="30"/>
    <float name="quantum_yield" value="0.9"/>
</bsdf>"#;

#[test]
fn fluorescent_material_is_read() {
    let d = mitsuba_ok(&format!("{FLUORESCENT}\n<shape type=\"sphere\"><ref id=\"glow\"/></shape>"));
    let Material::Fluorescent { reflectance, fluorescence } = &d.materials[d.shapes[0].material as usize] else {
        panic!("{:?}", d.materials)
    };
    assert_eq!(*reflectance, scene::Texture::Constant(Rgb::new(0.2, 0.3, 0.4)));
    assert_eq!(fluorescence.absorption_peak, 0.6);
    assert_eq!((fluorescence.absorption.center_nm, fluorescence.absorption.half_width_nm), (450.0, 40.0));
    assert_eq!((fluorescence.emission.center_nm, fluorescence.emission.half_width_nm), (560.0, 30.0));
    assert_eq!(fluorescence.quantum_yield, 0.9);
    assert!(Scene::from_description(&d, Some((4, 4))).unwrap().0.has_fluorescence());
}

#[test]
fn bad_fluorescent_parameters_are_errors_with_positions() {
    let with = |name: &str, value: &str| {
        let mut lines: Vec<String> = FLUORESCENT.lines().map(str::to_string).collect();
        let i = lines.iter().position(|l| l.contains(&format!("\"{name}\""))).unwrap();
        if value.is_empty() {
            lines.remove(i);
        } else {
            lines[i] = format!("    <float name=\"{name}\" value=\"{value}\"/>");
        }
        lines.join("\n")
    };
    // The <bsdf> element is on line 2.
    mitsuba_error(&with("absorption_peak", "1.5"), 2, &["fluorescent", "absorption peak"]);
    mitsuba_error(&with("quantum_yield", "-0.1"), 2, &["quantum yield"]);
    mitsuba_error(&with("emission_center", "470"), 2, &["above the absorption band"]);
    mitsuba_error(&with("absorption_width", "0.5"), 2, &["absorption band"]);
    mitsuba_error(&with("emission_center", ""), 2, &["missing", "emission_center"]);
    // 0.8 reflected + 0.6 · 0.9 re-emitted > 1.
    let bright = FLUORESCENT.replace("0.2, 0.3, 0.4", "0.8");
    mitsuba_error(&bright, 2, &["exceeds 1"]);
    // A non-number where a number belongs: at the property's line.
    mitsuba_error(&FLUORESCENT.replace("value=\"40\"", "value=\"wide\""), 6, &["bad number"]);
}

#[test]
fn fluorescent_bands_of_two_materials_must_not_overlap() {
    let other = |absorption_center: f32| {
        FLUORESCENT
            .replace("id=\"glow\"", "id=\"other\"")
            .replace("value=\"450\"", &format!("value=\"{absorption_center}\""))
            .replace("value=\"560\"", "value=\"680\"")
    };
    let body = |c: f32| {
        format!(
            "{FLUORESCENT}\n{}\n<shape type=\"sphere\"><ref id=\"glow\"/></shape>\n\
             <shape type=\"sphere\"><ref id=\"other\"/></shape>",
            other(c)
        )
    };
    // `other` absorbs 510–590 nm, where `glow` re-emits (530–590 nm).
    let d = mitsuba_ok(&body(550.0));
    let e = Scene::from_description(&d, Some((4, 4))).err().unwrap();
    assert!(e.contains("overlaps"), "{e}");
    // Absorbing 370–450 nm it is fine.
    assert!(Scene::from_description(&mitsuba_ok(&body(410.0)), Some((4, 4))).is_ok());
}

#[test]
fn pbrt_blackbody_and_sampled_lights_keep_a_unit_luminance_spectrum() {
    let (_dir, path) = write_scene(
        "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" [3000] \"float scale\" 2\n\
         Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n\
         LightSource \"point\" \"spectrum I\" [400 1 500 3 700 2] \"float scale\" 3\n\
         LightSource \"point\" \"rgb I\" [1 1 1]\n",
        "pbrt",
    );
    let d = io::pbrt::load(&path).unwrap_or_else(|e| panic!("{e}"));
    // pbrt-v4 divides a light's scale by its spectrum's luminance: Y = scale.
    let Some(bb @ EmissionSpectrum::Blackbody { kelvin, .. }) = d.emission_spectra.shapes.get(&0) else {
        panic!("{:?}", d.emission_spectra)
    };
    assert_eq!(*kelvin, 3000.0);
    let y = brute_xyz(|l| f64::from(bb.eval(l as f32)))[1];
    assert!((y / 2.0 - 1.0).abs() < 1e-4, "Y = {y}");
    let sampled = d.emission_spectra.lights.get(&0).expect("sampled spectrum kept");
    let y = brute_xyz(|l| f64::from(sampled.eval(l as f32)))[1];
    assert!((y / 3.0 - 1.0).abs() < 1e-4, "Y = {y}");
    // Its shape is the file's: values 1 : 3 : 2.
    assert!((sampled.eval(500.0) / sampled.eval(400.0) - 3.0).abs() < 1e-5);
    assert!(!d.emission_spectra.lights.contains_key(&1), "rgb lights have no spectrum");
    // The RGB values keep pbrt's normalisation too (Y = scale with the loader's CMF fit).
    let e = d.shapes[0].emission.unwrap();
    assert!((e.luminance() / 2.0 - 1.0).abs() < 2e-3, "{e:?}");
}

/// A large emitting rectangle facing a camera that sees nothing else, with `radiance` inside
/// its `<emitter>`.
fn facing_emitter(radiance: &str) -> String {
    format!(
        r#"<integrator type="path"><integer name="max_depth" value="1"/></integrator>
        <sensor type="perspective">
            <float name="fov" value="20"/>
            <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
                <rfilter type="box"/></film>
        </sensor>
        <shape type="rectangle">
            <transform name="to_world"><scale value="10"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
            <emitter type="area">{radiance}</emitter>
        </shape>"#
    )
}

/// Image means per channel, one sample per iteration, over `iterations` iterations of path
/// tracing with paths of one segment.
fn image_means(scene: &Scene, spectral: bool, iterations: u64) -> [MeanVar; 3] {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name("pt").unwrap(),
        budget: Budget::Iterations(iterations),
        max_length: 1,
        seed: 11,
        spectral,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(scene, &settings).unwrap();
    let mut stats = [MeanVar::new(); 3];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "no rejected samples");
        let pixels = &renderer.frame().pixels;
        let mut sum = [0.0f64; 3];
        for p in pixels {
            for (s, v) in sum.iter_mut().zip(p.to_array()) {
                *s += f64::from(v);
            }
        }
        for (s, total) in stats.iter_mut().zip(sum) {
            s.push(total / pixels.len() as f64);
        }
    }
    stats
}

#[test]
fn directly_seen_spectral_emitters_render_their_colour() {
    let cases = [
        (format!(r#"<spectrum name="radiance" value="{TABLE}"/>"#), {
            let t = spectrum::tabulated::Tabulated::new(&TABLE_POINTS.map(|(l, v)| (l as f32, v as f32))).unwrap();
            brute_xyz(move |l| f64::from(t.eval(l as f32)))
        }),
        (r#"<blackbody name="radiance" temperature="2700" scale="0.01"/>"#.to_string(), {
            brute_xyz(|l| 0.01 * planck(l, 2700.0))
        }),
        // A narrow green band outside the sRGB gamut: its red channel is negative, which the
        // RGB value clamps to 0 and only the spectrum reproduces.
        (r#"<spectrum name="radiance" value="505:0, 520:10, 535:0"/>"#.to_string(), {
            brute_xyz(|l| 10.0 * (1.0 - (l - 520.0).abs() / 15.0).max(0.0))
        }),
    ];
    // 3 cases × 3 channels, 1 % overall false-alarm rate.
    let alpha = sidak(0.01, 9);
    let mut discriminating = false;
    for (radiance, xyz) in cases {
        let d = mitsuba_ok(&facing_emitter(&radiance));
        let (scene, _) = Scene::from_description(&d, None).unwrap();
        // RGB mode: exactly the loader's RGB value in every pixel.
        let base = d.shapes[0].emission.unwrap();
        let rgb = image_means(&scene, false, 2);
        for (c, s) in rgb.iter().enumerate() {
            assert_eq!(s.mean() as f32, base.to_array()[c], "{radiance}: RGB mode");
        }
        // Spectral mode: the film's colour of the spectrum (spectrum::cie's XYZ → sRGB) in
        // expectation, whatever the loader's RGB value.
        let truth = spectrum::cie::xyz_to_linear_srgb(xyz.map(|v| v as f32)).to_array();
        let stats = image_means(&scene, true, 400);
        for (c, s) in stats.iter().enumerate() {
            let p = z_test_p(s.mean() - f64::from(truth[c]), s.std_error());
            eprintln!(
                "{radiance}: channel {c}: mean {:.5} ± {:.5}, truth {:.5}, RGB value {:.5}, p {p:.3}",
                s.mean(),
                s.std_error(),
                truth[c],
                base.to_array()[c]
            );
            assert!(p > alpha, "{radiance}: channel {c}: {} ± {} vs {}", s.mean(), s.std_error(), truth[c]);
            // Could the test tell the spectrum from the upsampled RGB value?
            discriminating |= (f64::from(truth[c] - base.to_array()[c])).abs() > 10.0 * s.std_error();
        }
    }
    assert!(discriminating, "no case separates the spectrum from its RGB value");
}
