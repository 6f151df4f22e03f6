//! Emission spectra through `Scene::from_description` and `Scene::emission`: a tabulated emitter
//! emits exactly its samples (linearly interpolated) at the path's wavelengths, scaled by the
//! factor its query applied; RGB mode returns the RGB value untouched; a blackbody follows
//! Planck's law; bad spectra and re-absorbed fluorescence are build errors.

use std::sync::Arc;

use math::{Rng, Vec3};
use scene::Scene;
use scene::desc::{
    CameraDesc, EmissionSpectra, EmissionSpectrum, FilmDesc, FilterDesc, Geometry, LightDesc, MeshData, Projection,
    SceneDescription, ShapeDesc, TextureImage,
};
use scene::material::Material;
use scene::texture::Texture;
use spectrum::fluorescence::{Band, Fluorescence};
use spectrum::tabulated::Tabulated;
use spectrum::{Hero4, Rgb, SpectralMode, Wavelengths4};

/// The samples of the test spectrum (nm, spectral radiance).
const POINTS: [(f32, f32); 4] = [(400.0, 0.0), (500.0, 8.0), (600.0, 15.6), (700.0, 18.4)];

/// Linear interpolation of [`POINTS`], zero outside: the test's own evaluation.
fn points_at(lambda: f32) -> f32 {
    for w in POINTS.windows(2) {
        let ((l0, v0), (l1, v1)) = (w[0], w[1]);
        if (l0..=l1).contains(&lambda) {
            return v0 + (v1 - v0) * (lambda - l0) / (l1 - l0);
        }
    }
    0.0
}

fn tabulated() -> EmissionSpectrum {
    EmissionSpectrum::Tabulated(Arc::new(Tabulated::new(&POINTS).unwrap()))
}

fn quad(z: f32) -> Geometry {
    Geometry::Mesh(MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ],
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        attributes: Vec::new(),
    })
}

fn description(materials: Vec<Material>, shapes: Vec<ShapeDesc>, lights: Vec<LightDesc>) -> SceneDescription {
    SceneDescription {
        name: "spectra".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: -Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
        },
        film: FilmDesc { width: 4, height: 4, filter: FilterDesc::Box },
        materials,
        shapes,
        lights,
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: EmissionSpectra::default(),
        objects: Vec::new(),
        instances: Vec::new(),
        media: Default::default(),
    }
}

fn diffuse() -> Material {
    Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }
}

/// A two-triangle emitter with the test spectrum (shape 1), a plain RGB emitter (shape 0), a
/// point light with the test spectrum and a spot light without.
fn spectral_scene(base: Rgb) -> Scene {
    let shapes = vec![
        ShapeDesc {
            name: "plain".into(),
            geometry: quad(-1.0),
            material: 0,
            emission: Some(Rgb::splat(1.0)),
            alpha: None,
        },
        ShapeDesc { name: "tabulated".into(), geometry: quad(0.0), material: 0, emission: Some(base), alpha: None },
    ];
    let lights = vec![
        LightDesc::Point { position: Vec3::new(0.0, 0.0, 2.0), intensity: base * 2.0 },
        LightDesc::Point { position: Vec3::new(0.0, 1.0, 2.0), intensity: Rgb::splat(1.0) },
    ];
    let mut desc = description(vec![diffuse()], shapes, lights);
    desc.emission_spectra.shapes.insert(1, tabulated());
    desc.emission_spectra.lights.insert(0, tabulated().scaled(2.0).unwrap());
    Scene::from_description(&desc, None).unwrap().0
}

#[test]
fn tabulated_emitter_emits_its_samples_at_the_wavelengths() {
    // The RGB value is some colour; only ratios of it matter for the spectrum.
    let base = Rgb::new(1.9, 1.1, 0.35);
    let scene = spectral_scene(base);
    // Lights: 0 (plain quad: one parallelogram), 1 (tabulated quad), 2 (point with spectrum),
    // 3 (point).
    assert_eq!(scene.lights.len(), 4);
    assert!(scene.light_spectrum(0).is_none() && scene.light_spectrum(1).is_some());
    assert!(scene.light_spectrum(2).is_some() && scene.light_spectrum(3).is_none());
    let mut rng = Rng::new(7, 3);
    for _ in 0..1000 {
        let w = Wavelengths4::sample(rng.uniform(), rng.uniform(), false);
        // The query returned the base value itself: exactly the samples.
        let v: Hero4 = scene.emission(1, &w, base);
        for j in 0..4 {
            let truth = points_at(w.lambda[j]);
            assert!((v.0[j] - truth).abs() <= 1e-5 * truth.max(1.0), "λ {} {} vs {truth}", w.lambda[j], v.0[j]);
        }
        // A query that scaled the base by 0.37 (a cosine, a falloff) scales the spectrum alike;
        // the point light's spectrum carries its factor 2.
        let k = 0.37f32;
        let scaled: Hero4 = scene.emission(1, &w, base * k);
        let point: Hero4 = scene.emission(2, &w, base * 2.0 * k);
        for j in 0..4 {
            let truth = k * points_at(w.lambda[j]);
            assert!((scaled.0[j] - truth).abs() <= 1e-5 * truth.max(1.0));
            assert!((point.0[j] - 2.0 * truth).abs() <= 2e-5 * truth.max(1.0));
        }
        // Lights without a spectrum upsample their RGB value, as before.
        let grey = Rgb::splat(0.8);
        assert_eq!(scene.emission::<Hero4>(0, &w, grey), Hero4::from_emission(&w, grey));
        assert_eq!(scene.emission::<Hero4>(3, &w, grey), Hero4::from_emission(&w, grey));
    }
    // RGB mode: the value itself, bit for bit, with or without a spectrum.
    for light in 0..4 {
        let rgb = Rgb::new(0.123_456_7, 3.0e-7, 12.5);
        assert_eq!(scene.emission::<Rgb>(light, &(), rgb), rgb);
    }
}

#[test]
fn factor_uses_the_largest_channel_and_a_black_base_gives_zero() {
    let spectrum = scene::LightSpectrum { spectrum: tabulated(), base: Rgb::BLACK };
    assert_eq!(spectrum.factor(Rgb::splat(1.0)), 0.0);
    let spectrum = scene::LightSpectrum { spectrum: tabulated(), base: Rgb::new(0.0, 0.5, 0.25) };
    assert_eq!(spectrum.factor(Rgb::new(0.0, 1.0, 0.5)), 2.0);
}

/// Planck's law written out here (W·m⁻²·sr⁻¹·nm⁻¹), CODATA constants.
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    let (h, c, k) = (6.626_070_15e-34, 299_792_458.0, 1.380_649e-23);
    let l = lambda_nm * 1e-9;
    2.0 * h * c * c / (l.powi(5) * ((h * c / (l * k * kelvin)).exp() - 1.0)) * 1e-9
}

#[test]
fn blackbody_follows_plancks_law_and_its_colour_matches_brute_force() {
    let s = EmissionSpectrum::Blackbody { kelvin: 3000.0, scale: 0.5 };
    for lambda in [360.0f32, 450.0, 555.0, 700.0, 830.0] {
        let truth = 0.5 * planck(f64::from(lambda), 3000.0);
        assert!((f64::from(s.eval(lambda)) / truth - 1.0).abs() < 1e-4, "{lambda}: {} vs {truth}", s.eval(lambda));
    }
    // Zero outside the CIE range, as Mitsuba 3's blackbody.
    assert_eq!(s.eval(359.0), 0.0);
    assert_eq!(s.eval(831.0), 0.0);
    // XYZ by a 0.01 nm midpoint rule.
    let n = 47_000;
    let mut brute = [0.0f64; 3];
    for i in 0..n {
        let l = 360.0 + (i as f64 + 0.5) * 0.01;
        let c = spectrum::cie::cmf(l as f32);
        for k in 0..3 {
            brute[k] += 0.5 * planck(l, 3000.0) * f64::from(c[k]) * 0.01 / spectrum::cie::CIE_Y_INTEGRAL;
        }
    }
    let xyz = s.xyz();
    for k in 0..3 {
        assert!((xyz[k] / brute[k] - 1.0).abs() < 1e-5, "{xyz:?} vs {brute:?}");
    }
    assert!(EmissionSpectrum::Blackbody { kelvin: -1.0, scale: 1.0 }.validate().is_err());
    assert!(EmissionSpectrum::Blackbody { kelvin: 3000.0, scale: f32::NAN }.validate().is_err());
}

fn error(desc: &SceneDescription) -> String {
    match Scene::from_description(desc, None) {
        Ok(_) => panic!("expected a build error"),
        Err(e) => e,
    }
}

#[test]
fn bad_spectra_are_build_errors() {
    let shape =
        || ShapeDesc { name: "q".into(), geometry: quad(0.0), material: 0, emission: Some(Rgb::WHITE), alpha: None };
    let mut desc = description(vec![diffuse()], vec![shape()], Vec::new());
    desc.emission_spectra.shapes.insert(3, tabulated());
    assert!(error(&desc).contains("shape 3"), "{}", error(&desc));

    let mut desc = description(vec![diffuse()], vec![shape()], Vec::new());
    let negative = Tabulated::new(&[(400.0, 1.0), (500.0, -0.5)]).unwrap();
    desc.emission_spectra.shapes.insert(0, EmissionSpectrum::Tabulated(Arc::new(negative)));
    assert!(error(&desc).contains("negative"), "{}", error(&desc));

    let image = Arc::new(TextureImage { width: 2, height: 2, pixels: vec![Rgb::WHITE; 4] });
    let env = LightDesc::EnvMap { image, scale: 1.0, to_world: [Vec3::X, Vec3::Y, Vec3::Z] };
    let mut desc = description(vec![diffuse()], vec![shape()], vec![env]);
    desc.emission_spectra.lights.insert(0, tabulated());
    assert!(error(&desc).contains("image environment"), "{}", error(&desc));
}

fn fluorescent(absorption: (f32, f32), emission: (f32, f32)) -> Material {
    let band = |(c, w): (f32, f32)| Band { center_nm: c, half_width_nm: w };
    Material::Fluorescent {
        reflectance: Texture::Constant(Rgb::splat(0.3)),
        fluorescence: Fluorescence::new(0.5, band(absorption), band(emission), 0.8).unwrap(),
    }
}

#[test]
fn fluorescent_emission_must_not_overlap_any_absorption_band() {
    let sphere = |material: u32| ShapeDesc {
        name: format!("ball{material}"),
        geometry: Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false },
        material,
        emission: None,
        alpha: None,
    };
    let a = fluorescent((450.0, 30.0), (550.0, 30.0));
    // Absorbs 520–560 nm, where `a` re-emits.
    let overlapping = fluorescent((540.0, 20.0), (640.0, 30.0));
    let desc = description(vec![a.clone(), overlapping], vec![sphere(0), sphere(1)], Vec::new());
    let e = error(&desc);
    assert!(e.contains("material 0") && e.contains("material 1") && e.contains("overlaps"), "{e}");
    // Absorbs 380–420 nm and re-emits 600–640 nm: neither touches the other's bands.
    let separate = fluorescent((400.0, 20.0), (620.0, 20.0));
    let desc = description(vec![a, separate], vec![sphere(0), sphere(1)], Vec::new());
    assert!(Scene::from_description(&desc, None).is_ok());
}
