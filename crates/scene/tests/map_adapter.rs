//! Mitsuba's per-query treatment of normal- and bump-mapped materials (`material/map_adapter.rs`):
//! the albedo of a normal-mapped Lambertian surface against a quadrature of Mitsuba's
//! definition (mirrored normal for a camera direction below the perturbed one, shadowing
//! factor on the light direction), one BSDF in both transport modes (values and pdf pairs),
//! and the sampler against its pdf when the normal is mirrored.

use math::{Rng, Vec2, Vec3};
use scene::material::{MapOptions, SurfaceTangents};
use scene::microfacet::Distribution;
use scene::{Bsdf, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;
use testkit::mitsuba_maps::tilted_diffuse_albedo;
use testkit::{MeanVar, assert_chi2, chi2_sphere};

fn diffuse(rho: f32) -> Material {
    Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(rho)) }
}

fn rough_conductor() -> Material {
    Material::RoughConductor {
        distribution: Distribution::Ggx,
        alpha_u: 0.3,
        alpha_v: 0.1,
        eta: Rgb::new(0.2, 0.9, 1.1),
        k: Rgb::new(3.9, 2.4, 2.1),
        specular_reflectance: Texture::Constant(Rgb::WHITE),
    }
}

/// `nested` under a constant normal map that tilts the normal by `a` radians towards +x.
fn tilted(a: f32, nested: Material) -> Material {
    let texel = Rgb::new(0.5 + 0.5 * a.sin(), 0.5, 0.5 + 0.5 * a.cos());
    Material::NormalMap { normals: Texture::Constant(texel), nested: Box::new(nested), options: MapOptions::MITSUBA }
}

/// The shading point of a mapped material on the plane z = 0 with ∂p/∂u = +x, as the scene
/// builds it.
fn point(material: &Material) -> ShadingPoint {
    let t = SurfaceTangents {
        geometric_normal: Vec3::Z,
        shading_normal: Vec3::Z,
        uv: Vec2::ZERO,
        dp_du: Vec3::X,
        dp_dv: Vec3::Y,
    };
    ShadingPoint {
        geometric_normal: Vec3::Z,
        shading_normal: material.perturbed_shading_normal(&t),
        uv: Vec2::ZERO,
        tangent: Vec3::X,
        attribute: Rgb::BLACK,
    }
}

/// Mean of `value · cos / pdf` over `samples` BSDF samples (the directional albedo).
fn albedo(bsdf: &Bsdf, samples: u32, seed: u64) -> MeanVar {
    let mut rng = Rng::for_stream(seed, 0, 0);
    let mut stats = MeanVar::new();
    for _ in 0..samples {
        let weight =
            bsdf.sample(rng.uniform3()).map_or(0.0, |s| f64::from(s.value.r * s.cos_generated / s.pdf.forward.0));
        stats.push(weight);
    }
    stats
}

/// A Lambertian surface whose normal map tilts the normal by `a` reflects `ρ/π ∫ max(0, l·n)
/// G(l) dω` over the geometric upper hemisphere in radiance mode, whether the camera direction
/// lies above the tilted normal or below it (the mirrored normal gives the same integral by
/// symmetry). The unshadowed sky-view factor and a 2 % smaller tilt are rejected.
#[test]
fn mapped_diffuse_albedo_is_mitsubas() {
    let rho = 0.8;
    let samples = 200_000;
    for (k, a) in [0.3f32, 0.9, 1.3].into_iter().enumerate() {
        let material = tilted(a, diffuse(rho));
        let point = point(&material);
        let expected = tilted_diffuse_albedo(f64::from(rho), f64::from(a), true);
        // Above the tilted normal, and 80° from the normal on the side it tilts away from.
        for (m, fixed) in
            [Vec3::new(0.2, 0.1, 0.95), Vec3::new(-(1.4f32.sin()), 0.0, 1.4f32.cos())].into_iter().enumerate()
        {
            let fixed = fixed.normalize();
            let bsdf = Bsdf::new(&material, &point, fixed, TransportMode::Radiance).expect("a BSDF");
            let stats = albedo(&bsdf, samples, 7 + 2 * k as u64 + m as u64);
            // 4.5 standard errors: six tests at a family-wise level ~4e-5.
            let tolerance = 4.5 * stats.std_error();
            let what = format!("a = {a}, fixed {fixed}: {} vs {expected} (± {tolerance})", stats.mean());
            assert!((stats.mean() - expected).abs() < tolerance, "{what}");
            if k > 0 {
                let unshadowed = tilted_diffuse_albedo(f64::from(rho), f64::from(a), false);
                assert!((stats.mean() - unshadowed).abs() > tolerance, "{what}: the unshadowed value passes");
                let smaller = tilted_diffuse_albedo(f64::from(rho), 0.98 * f64::from(a), true);
                assert!((stats.mean() - smaller).abs() > tolerance, "{what}: a 2 % smaller tilt passes");
            }
        }
    }
}

/// The radiance BSDF with fixed direction `c` and the importance BSDF with fixed direction `l`
/// are one BSDF `f(c, l)`: equal values, and the forward pdf of each is the reverse pdf of the
/// other, also where the camera-side direction mirrors the normal.
#[test]
fn both_transport_modes_evaluate_one_mapped_bsdf() {
    let mut rng = Rng::for_stream(11, 0, 0);
    let mut hemisphere = || {
        let [a, b, _] = rng.uniform3();
        let d = math::warp::uniform_sphere([a, b]);
        Vec3::new(d.x, d.y, d.z.abs())
    };
    let (mut compared, mut mirrored, mut zero_pdfs) = (0, 0, 0);
    for nested in [diffuse(0.7), rough_conductor()] {
        let material = tilted(0.9, nested);
        let point = point(&material);
        for _ in 0..4000 {
            let (c, l) = (hemisphere(), hemisphere());
            let radiance = Bsdf::new(&material, &point, c, TransportMode::Radiance).and_then(|b| b.evaluate(l));
            let importance = Bsdf::new(&material, &point, l, TransportMode::Importance).and_then(|b| b.evaluate(c));
            let (r, i) = match (radiance, importance) {
                (Some(r), Some(i)) => (r, i),
                (None, None) => continue,
                (r, i) => panic!("c {c}, l {l}: radiance {r:?}, importance {i:?}"),
            };
            let close = |x: f32, y: f32| (x - y).abs() <= 1e-4 * x.abs().max(y.abs()).max(1e-3);
            let what = format!("c {c}, l {l}: radiance {r:?}, importance {i:?}");
            assert!(close(r.value.r, i.value.r) && close(r.value.b, i.value.b), "{what}");
            assert!(close(r.pdf.forward.0, i.pdf.reverse.0) && close(r.pdf.reverse.0, i.pdf.forward.0), "{what}");
            compared += 1;
            mirrored += usize::from(c.dot(point.shading_normal) <= 0.0);
            zero_pdfs += usize::from(r.pdf.reverse.0 == 0.0);
        }
    }
    // The comparisons reach the mirrored normal and the importance sampler's rejections.
    assert!(compared > 2000 && mirrored > 100 && zero_pdfs > 50, "{compared} {mirrored} {zero_pdfs}");
}

/// With the fixed direction below the tilted normal, the sampler of both modes draws
/// directions with the density its evaluation reports.
#[test]
fn mirrored_sampler_matches_its_pdf() {
    let material = tilted(0.5, rough_conductor());
    let point = point(&material);
    let fixed = Vec3::new(-(1.3f32.sin()), 0.1, 1.3f32.cos()).normalize();
    assert!(fixed.dot(point.shading_normal) < 0.0);
    for (i, mode) in [TransportMode::Radiance, TransportMode::Importance].into_iter().enumerate() {
        let bsdf = Bsdf::new(&material, &point, fixed, mode).expect("a BSDF");
        let outcome = chi2_sphere(
            |rng: &mut Rng| bsdf.sample(rng.uniform3()).map(|s| s.direction),
            |d| bsdf.evaluate(d.normalize()).map_or(0.0, |e| f64::from(e.pdf.forward.0)),
            100_000,
            60 + i as u64,
            24,
            32,
        );
        assert_chi2(&outcome, testkit::sidak(1e-3, 2), &format!("mirrored rough conductor ({mode:?})"));
    }
}

/// Without the adapter (pbrt's maps, or Mitsuba's flags off) a tilted Lambertian surface
/// reflects the unshadowed sky-view factor, and a camera direction below the tilted normal
/// scatters nothing.
#[test]
fn maps_without_the_adapter_are_plain() {
    let (rho, a) = (0.8, 0.9f32);
    let Material::NormalMap { normals, nested, .. } = tilted(a, diffuse(rho)) else { unreachable!() };
    let material = Material::NormalMap { normals, nested, options: MapOptions::NONE };
    let point = point(&material);
    let bsdf = Bsdf::new(&material, &point, Vec3::new(0.2, 0.1, 0.95).normalize(), TransportMode::Radiance);
    let stats = albedo(&bsdf.expect("a BSDF"), 200_000, 3);
    let expected = tilted_diffuse_albedo(f64::from(rho), f64::from(a), false);
    let tolerance = 4.5 * stats.std_error();
    assert!((stats.mean() - expected).abs() < tolerance, "{} vs {expected} (± {tolerance})", stats.mean());
    let below = Vec3::new(-(1.4f32.sin()), 0.0, 1.4f32.cos());
    assert!(Bsdf::new(&material, &point, below, TransportMode::Radiance).is_none());
}
