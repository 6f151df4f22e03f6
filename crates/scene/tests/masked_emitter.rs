//! Masked area emitters (an emitting mesh with an alpha mask): masked-out parts neither emit nor
//! block. A 2 × 2 quad of radiance 1 whose mask is off where x < 0 (a quarter of its first
//! triangle's area, three quarters of its second's) must emit only from x > 0, with a point
//! density equal to the area pdf it reports (chi-square, where a uniform density fails), and
//! a flux of half the unmasked quad's, `π · 1 · 2` (Monte Carlo estimate from the emission
//! sampler, 5σ; it would detect a 2 % bias). A constant opacity 0.3 gives 0.3 × the flux: sampled
//! points carry `0.3 · L`, hits `L` (the alpha test keeps 30 % of them), with the same pdfs.
//! A masked emitting sphere is an error; a mesh masked out everywhere emits nothing.

use math::{PI, Rng, Vec2, Vec3, warp};
use scene::desc::{
    CameraDesc, FilmDesc, FilterDesc, Geometry, MeshData, Projection, SceneDescription, ShapeDesc, UvTransform,
};
use scene::light::BoundingSphere;
use scene::material::Material;
use scene::texture::Texture;
use scene::{Light, Scene};
use spectrum::Rgb;
use testkit::{MeanVar, assert_chi2, chi2_square, sidak};

const SAMPLES: usize = 100_000;

/// The square `[-1, 1]² × {0}` facing +z, with uv = ((x + 1)/2, (y + 1)/2).
fn quad() -> Geometry {
    Geometry::Mesh(MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        normals: Vec::new(),
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        attributes: Vec::new(),
    })
}

/// Opacity 0 where u < ½, 1 where u > ½ (a checkerboard squashed along v).
fn half_mask() -> Texture {
    Texture::Checkerboard {
        color0: Rgb::BLACK,
        color1: Rgb::WHITE,
        to_uv: UvTransform { columns: [Vec2::new(1.0, 0.0), Vec2::ZERO], translation: Vec2::ZERO },
    }
}

fn lamp(geometry: Geometry, alpha: Texture) -> ShapeDesc {
    ShapeDesc { name: "lamp".into(), geometry, material: 0, emission: Some(Rgb::WHITE), alpha: Some(alpha) }
}

fn description(shape: ShapeDesc) -> SceneDescription {
    SceneDescription {
        name: "masked emitter".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: -Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
        },
        film: FilmDesc { width: 4, height: 4, filter: FilterDesc::Box },
        materials: vec![Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }],
        shapes: vec![shape],
        lights: Vec::new(),
        max_path_length: Some(5),
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: Vec::new(),
        instances: Vec::new(),
        media: Default::default(),
    }
}

fn build(shape: ShapeDesc) -> Result<Scene, String> {
    Scene::from_description(&description(shape), None).map(|(scene, _)| scene)
}

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::ZERO, radius: 3.0 }
}

/// Mean and standard error of the flux estimate `energy / emission_pdf` (W per channel G),
/// summed over the scene's lights, each sampled `SAMPLES` times.
fn flux(scene: &Scene, seed: u64) -> (f64, f64) {
    let (mut mean, mut variance) = (0.0, 0.0);
    for (i, light) in scene.lights.iter().enumerate() {
        let mut rng = Rng::for_stream(seed, i as u64, 0);
        let mut stats = MeanVar::new();
        for _ in 0..SAMPLES {
            let e = light.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
            stats.push(if e.emission_pdf.0 > 0.0 { f64::from(e.energy.g / e.emission_pdf.0) } else { 0.0 });
        }
        mean += stats.mean();
        variance += stats.variance() / SAMPLES as f64;
    }
    (mean, variance.sqrt())
}

#[test]
fn a_half_masked_quad_emits_half_the_flux_from_its_opaque_half_only() {
    let scene = build(lamp(quad(), half_mask())).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.lights.len(), 2);
    // Every sampled point with energy lies where the mask is on (x > 0).
    for (i, light) in scene.lights.iter().enumerate() {
        let mut rng = Rng::for_stream(1, i as u64, 0);
        let (mut on, mut off) = (0, 0);
        for _ in 0..10_000 {
            let e = light.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
            if e.origin.x < 0.0 {
                assert!(e.energy.is_black(), "light {i}: a masked-out point at {} emits {:?}", e.origin, e.energy);
                off += 1;
            } else {
                on += 1;
            }
        }
        // The density follows the mask: the masked-out part gets only the table's floor.
        assert!(off * 5 < on, "light {i}: {off} samples masked out, {on} on");
    }
    let (mean, error) = flux(&scene, 2);
    let expected = f64::from(PI) * 2.0;
    eprintln!("masked quad flux {mean:.4} ± {error:.4}, expected {expected:.4}");
    assert!((mean - expected).abs() < 5.0 * error, "flux {mean} ± {error}, expected {expected}");
    assert!(5.0 * error < 0.02 * expected, "the test only detects a bias of {}", 5.0 * error / expected);
    // The selection power (tabulated, a midpoint estimate) is close to that flux too.
    let power: f32 = scene.lights.iter().map(|l| l.power(&sphere())).sum();
    assert!((f64::from(power) / expected - 1.0).abs() < 0.1, "power {power}, flux {expected}");
}

#[test]
fn the_masked_emitters_point_density_is_its_reported_area_pdf() {
    let scene = build(lamp(quad(), half_mask())).unwrap_or_else(|e| panic!("{e}"));
    for (i, light) in scene.lights.iter().enumerate() {
        let Light::TexturedTriangle(l) = light else { panic!("light {i} is not a masked triangle: {light:?}") };
        let t = l.triangle;
        let square_of = |p: Vec3| {
            let (b1, b2) = t.barycentrics(p);
            warp::uniform_triangle_inverse(Vec2::new(b1, b2)).map(f64::from)
        };
        let square_pdf = |p: [f64; 2]| {
            let b = warp::uniform_triangle([p[0] as f32, p[1] as f32]);
            f64::from(l.area_pdf(t.point(b.x, b.y)) * t.area())
        };
        let sample =
            |rng: &mut Rng| Some(square_of(light.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).origin));
        let outcome = chi2_square(sample, square_pdf, SAMPLES, 3 + i as u64, 16);
        assert_chi2(&outcome, sidak(1e-3, 2), &format!("masked triangle {i} emission positions"));
        let uniform = chi2_square(sample, |_| 1.0, SAMPLES, 3 + i as u64, 16);
        assert!(!uniform.passed(1e-3), "light {i}: a uniform pdf must fail: p = {}", uniform.p_value);
    }
}

#[test]
fn a_fractional_opacity_scales_the_sampled_radiance_and_the_flux() {
    let scene = build(lamp(quad(), Texture::Constant(Rgb::splat(0.3)))).unwrap_or_else(|e| panic!("{e}"));
    let (mean, error) = flux(&scene, 4);
    let expected = f64::from(PI) * 4.0 * 0.3;
    assert!((mean - expected).abs() < 5.0 * error + 1e-6 * expected, "flux {mean} ± {error}, expected {expected}");
    // Next-event estimation carries 0.3·L; a hit (kept by the alpha test) carries L; the pdfs agree.
    let light = &scene.lights[0];
    let receiver = Vec3::new(0.2, 0.4, 1.0);
    let d = light.sample_direct(receiver, [0.3, 0.6], &sphere()).unwrap();
    let point = receiver + d.distance * d.direction;
    let hit = light.radiance_on_hit(d.direction, point, Vec3::Z, &sphere()).unwrap();
    assert!((d.radiance.g - 0.3).abs() < 1e-6 && (hit.radiance.g - 1.0).abs() < 1e-6, "{d:?} {hit:?}");
    let solid_angle = hit.direct_pdf.to_solid_angle(d.distance * d.distance, d.cos_at_light).0;
    assert!((solid_angle - d.direct_pdf.0).abs() < 1e-4 * d.direct_pdf.0, "{hit:?} {d:?}");
    assert!((hit.emission_pdf.0 - d.emission_pdf.0).abs() < 1e-4 * d.emission_pdf.0, "{hit:?} {d:?}");
}

#[test]
fn masked_emitting_spheres_are_errors_and_fully_masked_meshes_emit_nothing() {
    let ball = Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false };
    let error = build(lamp(ball, half_mask())).unwrap_err();
    assert!(error.contains("lamp") && error.contains("triangle meshes only"), "{error}");
    // A mask that is off everywhere: the mesh emits nothing, no light is made.
    let off = build(lamp(quad(), Texture::Constant(Rgb::BLACK))).unwrap_or_else(|e| panic!("{e}"));
    assert!(off.lights.is_empty(), "{:?}", off.lights);
}
