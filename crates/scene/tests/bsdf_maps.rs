//! Normal and bump maps (Mitsuba's `normalmap`, `bumpmap`): the perturbed shading normal
//! against closed forms, the gradient of an image texture against the slope of a ramp, and the
//! BSDF of a mapped material (its sampler against its pdf; its energy is in `map_adapter.rs`).

use scene::microfacet::Distribution;
use std::sync::Arc;

use math::{Frame, Rng, Vec2, Vec3};
use scene::desc::{TextureImage, UvTransform};
use scene::material::{MapOptions, SurfaceTangents, luminance_gradient};
use scene::{Bsdf, FilterMode, Material, Sampling, ShadingPoint, Texture, TransportMode, WrapMode};
use spectrum::Rgb;
use testkit::{assert_chi2, chi2_sphere};

fn diffuse(rho: f32) -> Material {
    Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(rho)) }
}

fn normal_map(value: Rgb, nested: Material) -> Material {
    Material::NormalMap { normals: Texture::Constant(value), nested: Box::new(nested), options: MapOptions::MITSUBA }
}

/// The encoded tangent-space normal tilted by `a` radians from `n` towards `s`.
fn tilted(a: f32) -> Rgb {
    Rgb::new(0.5 + 0.5 * a.sin(), 0.5, 0.5 + 0.5 * a.cos())
}

/// Tangents at a point of a sheared, scaled parameterisation with a shading normal off the
/// geometric one.
fn tangents(seed: u64) -> SurfaceTangents {
    let mut rng = Rng::for_stream(seed, 0, 0);
    let mut unit = || {
        let [a, b, _] = rng.uniform3();
        math::warp::uniform_sphere([a, b])
    };
    let geometric_normal = unit();
    let shading_normal = (geometric_normal + 0.3 * unit()).normalize();
    let frame = Frame::from_z(geometric_normal);
    let dp_du = (frame.x * 2.0 + frame.y * 0.5 + geometric_normal * 0.1) * 1.7;
    let dp_dv = frame.y * 0.8 - frame.x * 0.2;
    SurfaceTangents { geometric_normal, shading_normal, uv: Vec2::new(0.3, 0.6), dp_du, dp_dv }
}

#[test]
fn identity_normal_map_keeps_the_shading_normal() {
    for seed in 0..20 {
        let t = tangents(seed);
        let n = normal_map(Rgb::new(0.5, 0.5, 1.0), diffuse(0.5)).perturbed_shading_normal(&t);
        assert!((n - t.shading_normal).length() < 1e-6, "seed {seed}: {n:?} vs {:?}", t.shading_normal);
    }
}

#[test]
fn tilted_normal_map_turns_the_normal_towards_the_tangent() {
    for seed in 0..20 {
        let t = tangents(seed);
        let a = 0.6;
        let n = normal_map(tilted(a), diffuse(0.5)).perturbed_shading_normal(&t);
        // Mitsuba's frame: s = dp_du without its normal component.
        let ns = t.shading_normal;
        let s = (t.dp_du - ns * ns.dot(t.dp_du)).normalize();
        let expected = (ns * a.cos() + s * a.sin()).normalize();
        assert!((n - expected).length() < 1e-5, "seed {seed}: {n:?} vs {expected:?}");
        // A wrong angle is caught at this tolerance.
        let wrong = (ns * (a + 0.01).cos() + s * (a + 0.01).sin()).normalize();
        assert!((n - wrong).length() > 1e-3);
    }
}

/// A `width × 1` image whose texel `i` holds `slope · (i + ½)/width` (a ramp of `slope` per
/// unit of u).
fn ramp(width: u32, slope: f32) -> Arc<TextureImage> {
    let pixels = (0..width).map(|i| Rgb::splat(slope * (i as f32 + 0.5) / width as f32)).collect();
    Arc::new(TextureImage { width, height: 1, pixels })
}

#[test]
fn gradient_of_a_bilinear_ramp_is_its_slope() {
    let clamp = Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Bilinear };
    let plain = Texture::bitmap(ramp(16, 3.0), UvTransform::IDENTITY, clamp);
    // to_uv scales u by 2 and swaps the axes: ∂h/∂v = 2·3, ∂h/∂u = 0.
    let swapped = UvTransform { columns: [Vec2::new(0.0, 1.0), Vec2::new(2.0, 0.0)], translation: Vec2::new(0.1, 0.0) };
    let transformed = Texture::bitmap(ramp(16, 3.0), swapped, clamp);
    let mut rng = Rng::for_stream(5, 0, 0);
    for _ in 0..200 {
        let [a, b, _] = rng.uniform3();
        // Inside the first and last half texel the clamped image is flat.
        let u = 1.0 / 32.0 + a * (1.0 - 2.0 / 32.0);
        let g = luminance_gradient(&plain, Vec2::new(u, b));
        assert!((g.x - 3.0).abs() < 2e-3 && g.y.abs() < 1e-6, "u = {u}: {g:?}");
        let v = (u - 0.1) / 2.0;
        let g = luminance_gradient(&transformed, Vec2::new(b, v));
        assert!(g.x.abs() < 1e-6 && (g.y - 6.0).abs() < 4e-3, "v = {v}: {g:?}");
    }
    let nearest = Texture::bitmap(
        ramp(16, 3.0),
        UvTransform::IDENTITY,
        Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Nearest },
    );
    assert_eq!(luminance_gradient(&nearest, Vec2::new(0.4, 0.5)), Vec2::ZERO);
    assert_eq!(luminance_gradient(&Texture::Constant(Rgb::WHITE), Vec2::new(0.4, 0.5)), Vec2::ZERO);
}

#[test]
fn bump_map_of_a_ramp_tilts_a_plane_by_its_slope() {
    let clamp = Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Bilinear };
    let (slope, scale) = (3.0, 0.25);
    let material = Material::BumpMap {
        height: Texture::bitmap(ramp(16, slope), UvTransform::IDENTITY, clamp),
        scale,
        nested: Box::new(diffuse(0.5)),
        options: MapOptions::MITSUBA,
    };
    // The plane z = 0 with p = (2u, 3v, 0).
    let t = SurfaceTangents {
        geometric_normal: Vec3::Z,
        shading_normal: Vec3::Z,
        uv: Vec2::new(0.4, 0.5),
        dp_du: Vec3::new(2.0, 0.0, 0.0),
        dp_dv: Vec3::new(0.0, 3.0, 0.0),
    };
    // ∂p/∂u' = (2, 0, scale·slope): n' ∝ (−scale·slope/2, 0, 1).
    let expected = Vec3::new(-scale * slope / 2.0, 0.0, 1.0).normalize();
    let n = material.perturbed_shading_normal(&t);
    assert!((n - expected).length() < 1e-4, "{n:?} vs {expected:?}");
    // Flipped to the side of the geometric normal when the parameterisation is mirrored.
    let mirrored = SurfaceTangents { dp_dv: -t.dp_dv, ..t };
    assert!(material.perturbed_shading_normal(&mirrored).z > 0.0);
}

/// The shading point of a mapped material as the scene builds it.
fn mapped_point(material: &Material, t: &SurfaceTangents) -> ShadingPoint {
    ShadingPoint {
        geometric_normal: t.geometric_normal,
        shading_normal: material.perturbed_shading_normal(t),
        uv: t.uv,
        tangent: t.dp_du,
        attribute: spectrum::Rgb::BLACK,
    }
}

fn flat_tangents() -> SurfaceTangents {
    SurfaceTangents {
        geometric_normal: Vec3::Z,
        shading_normal: Vec3::Z,
        uv: Vec2::ZERO,
        dp_du: Vec3::X,
        dp_dv: Vec3::Y,
    }
}

#[test]
fn normal_mapped_rough_conductor_sampler_matches_its_pdf() {
    let material = normal_map(
        tilted(0.5),
        Material::RoughConductor {
            distribution: Distribution::Ggx,
            alpha_u: 0.3,
            alpha_v: 0.1,
            eta: Rgb::new(0.2, 0.9, 1.1),
            k: Rgb::new(3.9, 2.4, 2.1),
            specular_reflectance: Texture::Constant(Rgb::WHITE),
        },
    );
    let point = mapped_point(&material, &flat_tangents());
    let fixed = Vec3::new(-0.3, 0.2, 0.9).normalize();
    for (i, mode) in [TransportMode::Radiance, TransportMode::Importance].into_iter().enumerate() {
        let bsdf = Bsdf::new(&material, &point, fixed, mode).expect("a BSDF");
        let outcome = chi2_sphere(
            |rng: &mut Rng| bsdf.sample(rng.uniform3()).map(|s| s.direction),
            |d| bsdf.evaluate(d.normalize()).map_or(0.0, |e| f64::from(e.pdf.forward.0)),
            100_000,
            40 + i as u64,
            24,
            32,
        );
        assert_chi2(&outcome, testkit::sidak(1e-3, 2), &format!("normal-mapped rough conductor ({mode:?})"));
    }
}

#[test]
fn maps_only_as_the_outermost_material() {
    let mapped = normal_map(tilted(0.2), diffuse(0.5));
    assert!(mapped.validate().is_ok());
    let blend = Material::Blend {
        weight: Texture::Constant(Rgb::splat(0.5)),
        first: Box::new(mapped.clone()),
        second: Box::new(diffuse(0.2)),
    };
    assert!(blend.validate().unwrap_err().contains("outermost"));
    let twice = normal_map(tilted(0.2), mapped);
    assert!(twice.validate().unwrap_err().contains("outermost"));
    let two_sided = normal_map(tilted(0.2), Material::TwoSided { front: Box::new(diffuse(0.5)), back: None });
    assert!(two_sided.validate().is_ok());
}

fn rough_conductor(alpha_u: f32, alpha_v: f32) -> Material {
    Material::RoughConductor {
        distribution: Distribution::Ggx,
        alpha_u,
        alpha_v,
        eta: Rgb::new(0.2, 0.9, 1.1),
        k: Rgb::new(3.9, 2.4, 2.1),
        specular_reflectance: Texture::Constant(Rgb::WHITE),
    }
}

fn textured(alpha_u: Texture, alpha_v: Texture, remap: bool, nested: Material) -> Material {
    Material::TexturedRoughness { alpha_u, alpha_v, remap, nested: Box::new(nested) }
}

/// Value and pdfs of two materials agree exactly over many direction pairs at `uv`.
fn assert_same_bsdf(a: &Material, b: &Material, uv: Vec2, what: &str) {
    let point = ShadingPoint { uv, ..ShadingPoint::flat(Vec3::Z) };
    let mut rng = Rng::for_stream(3, 0, 0);
    for _ in 0..200 {
        let [u0, u1, _] = rng.uniform3();
        let fixed = math::warp::cosine_hemisphere([u0, u1]);
        let [u2, u3, _] = rng.uniform3();
        let generated = math::warp::uniform_sphere([u2, u3]);
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let (x, y) = (Bsdf::new(a, &point, fixed, mode), Bsdf::new(b, &point, fixed, mode));
            let (x, y) = (x.and_then(|x| x.evaluate(generated)), y.and_then(|y| y.evaluate(generated)));
            assert_eq!(x, y, "{what}: {fixed:?} → {generated:?}");
        }
    }
}

#[test]
fn textured_roughness_is_the_rough_model_at_the_texture_value() {
    let c = |v: f32| Texture::Constant(Rgb::splat(v));
    // Constant textures: the nested model's own α is replaced.
    let plain = rough_conductor(0.3, 0.1);
    assert_same_bsdf(&textured(c(0.3), c(0.1), false, rough_conductor(0.7, 0.7)), &plain, Vec2::ZERO, "constant");
    // pbrt's remapping: α = √roughness.
    assert_same_bsdf(&textured(c(0.09), c(0.01), true, rough_conductor(0.7, 0.7)), &plain, Vec2::ZERO, "remapped");
    // A checkerboard: each cell is the model at that cell's value.
    let checks = |a: f32, b: f32| Texture::Checkerboard {
        color0: Rgb::splat(a),
        color1: Rgb::splat(b),
        to_uv: UvTransform::IDENTITY,
    };
    let m = textured(checks(0.05, 0.3), checks(0.3, 0.05), false, rough_conductor(0.7, 0.7));
    assert_same_bsdf(&m, &rough_conductor(0.05, 0.3), Vec2::new(0.2, 0.2), "checkerboard cell 0");
    assert_same_bsdf(&m, &rough_conductor(0.3, 0.05), Vec2::new(0.7, 0.2), "checkerboard cell 1");
    // The rough dielectric and the (isotropic, α_u) rough plastic.
    let dielectric = |u: f32, v: f32| Material::RoughDielectric {
        distribution: Distribution::Ggx,
        alpha_u: u,
        alpha_v: v,
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: c(1.0),
        specular_transmittance: c(1.0),
    };
    assert_same_bsdf(
        &textured(c(0.2), c(0.4), false, dielectric(0.9, 0.9)),
        &dielectric(0.2, 0.4),
        Vec2::ZERO,
        "dielectric",
    );
    let plastic = |a: f32| Material::RoughPlastic {
        distribution: Distribution::Ggx,
        alpha: a,
        diffuse_reflectance: c(0.5),
        specular_reflectance: c(1.0),
        int_ior: 1.5,
        ext_ior: 1.0,
        nonlinear: false,
    };
    assert_same_bsdf(&textured(c(0.2), c(0.6), false, plastic(0.9)), &plastic(0.2), Vec2::ZERO, "plastic");
    // A different α is told apart.
    let point = ShadingPoint::flat(Vec3::Z);
    let fixed = Vec3::new(0.3, 0.0, 0.95).normalize();
    let generated = Vec3::new(-0.2, 0.1, 0.97).normalize();
    let eval =
        |m: &Material| Bsdf::new(m, &point, fixed, TransportMode::Radiance).unwrap().evaluate(generated).unwrap();
    assert_ne!(eval(&textured(c(0.31), c(0.1), false, rough_conductor(0.3, 0.1))).value, eval(&plain).value);
    // Only around a rough model.
    assert!(textured(c(0.3), c(0.3), false, diffuse(0.5)).validate().unwrap_err().contains("rough"));
}
