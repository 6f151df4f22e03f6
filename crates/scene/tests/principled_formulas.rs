//! The `principled` and `principledthin` values against independent truths: parameter sets
//! that reduce to the GGX conductor (F = 1) and to the rough dielectric (values and pdfs from
//! those models' own code), and closed forms of Mitsuba 3's Disney diffuse, retro-reflection,
//! fake subsurface, sheen, clearcoat and the thin sheet's Lambertian transmission, written
//! out here from the formulas (flat shading, so values are the shading-frame BSDF).

use math::{PI, Rng, Vec2, Vec3, sqr};
use scene::material::{PrincipledParameters, PrincipledThinParameters};
use scene::{Bsdf, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;

fn c(v: f32) -> Texture {
    Texture::Constant(Rgb::splat(v))
}

fn principled(edit: impl FnOnce(&mut PrincipledParameters)) -> Material {
    let mut p = PrincipledParameters::default();
    edit(&mut p);
    Material::Principled(Box::new(p))
}

fn thin(edit: impl FnOnce(&mut PrincipledThinParameters)) -> Material {
    let mut p = PrincipledThinParameters::default();
    edit(&mut p);
    Material::PrincipledThin(Box::new(p))
}

fn point() -> ShadingPoint {
    ShadingPoint {
        geometric_normal: Vec3::Z,
        shading_normal: Vec3::Z,
        uv: Vec2::ZERO,
        tangent: Vec3::ZERO,
        attribute: Rgb::BLACK,
    }
}

fn direction(theta_degrees: f32, phi: f32) -> Vec3 {
    let t = theta_degrees.to_radians();
    Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
}

/// Value (green channel) and forward/reverse pdfs of `material` for a pair.
fn query(material: &Material, fixed: Vec3, generated: Vec3, mode: TransportMode) -> (f32, f32, f32) {
    Bsdf::new(material, &point(), fixed, mode)
        .and_then(|b| b.evaluate(generated))
        .map_or((0.0, 0.0, 0.0), |e| (e.value.g, e.pdf.forward.0, e.pdf.reverse.0))
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6
}

/// Random pairs of directions, all over the sphere.
fn pairs(seed: u64, count: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::for_stream(seed, 0, 0);
    let mut sphere = || math::warp::uniform_sphere(rng.uniform2());
    (0..count).map(|_| (sphere(), sphere())).collect()
}

/// Metallic 1 with a white base colour is the GGX conductor with F = 1 and
/// `α = roughness²/√(1 − 0.9·anisotropic)`, `roughness²·√(1 − 0.9·anisotropic)`.
#[test]
fn white_metal_is_the_ggx_mirror_conductor() {
    for (roughness, anisotropic) in [(0.3f32, 0.0f32), (0.6, 0.7)] {
        let metal = principled(|p| {
            p.base_color = c(1.0);
            p.metallic = c(1.0);
            p.roughness = c(roughness);
            p.anisotropic = c(anisotropic);
        });
        let aspect = (1.0 - 0.9 * anisotropic).sqrt();
        let conductor = Material::RoughConductor {
            alpha_u: sqr(roughness) / aspect,
            alpha_v: sqr(roughness) * aspect,
            eta: Rgb::BLACK,
            k: Rgb::BLACK,
            specular_reflectance: c(1.0),
            distribution: scene::microfacet::Distribution::Ggx,
        };
        let mut compared = 0;
        for (a, b) in pairs(5, 2000) {
            let x = query(&metal, a, b, TransportMode::Radiance);
            let y = query(&conductor, a, b, TransportMode::Radiance);
            assert!(close(x.0, y.0) && close(x.1, y.1) && close(x.2, y.2), "{a} {b}: {x:?} vs {y:?}");
            compared += usize::from(y.0 > 0.0);
        }
        assert!(compared > 300, "{compared} non-zero pairs");
    }
}

/// Transmission 1 with a white base colour is the rough dielectric of the same IOR, from
/// both sides and in both transport modes (values and pdfs).
#[test]
fn white_full_transmission_is_the_rough_dielectric() {
    let glass = principled(|p| {
        p.base_color = c(1.0);
        p.spec_trans = c(1.0);
        p.roughness = c(0.5);
        p.eta = 1.5;
    });
    let dielectric = Material::RoughDielectric {
        alpha_u: 0.25,
        alpha_v: 0.25,
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: c(1.0),
        specular_transmittance: c(1.0),
        distribution: scene::microfacet::Distribution::Ggx,
    };
    let mut compared = [0; 2];
    for mode in [TransportMode::Radiance, TransportMode::Importance] {
        for (a, b) in pairs(6, 4000) {
            let x = query(&glass, a, b, mode);
            let y = query(&dielectric, a, b, mode);
            assert!(close(x.0, y.0) && close(x.1, y.1) && close(x.2, y.2), "{mode:?} {a} {b}: {x:?} vs {y:?}");
            if y.0 > 0.0 {
                compared[usize::from(a.z * b.z < 0.0)] += 1;
            }
        }
    }
    assert!(compared[0] > 500 && compared[1] > 500, "reflected / refracted pairs compared: {compared:?}");
}

/// Schlick's weight.
fn schlick(cos: f32) -> f32 {
    (1.0 - cos).powi(5)
}

/// With `eta = 1` the dielectric specular vanishes (F = 0; Mitsuba skips the lobe), leaving
/// the Disney diffuse `base/π · ((1 − Fi/2)(1 − Fo/2) + R(Fo + Fi + Fo·Fi·(R − 1)))` with
/// `F = (1 − cos)⁵`, `R = 2·roughness·cos²θ_d` (at normal incidence `θ_d = θ_o/2`), lerped
/// towards the fake subsurface by flatness, plus the sheen `sheen·(1 − cos θ_d)⁵` (untinted).
#[test]
fn disney_diffuse_retro_subsurface_and_sheen_follow_the_formulas() {
    let fixed = Vec3::Z;
    for (roughness, flatness, sheen) in [(0.0f32, 0.0f32, 0.0f32), (0.8, 0.0, 0.0), (0.5, 0.7, 0.0), (0.4, 0.3, 0.9)] {
        let base = 0.6;
        let material = principled(|p| {
            p.base_color = c(base);
            p.roughness = c(roughness);
            p.flatness = c(flatness);
            p.sheen = c(sheen);
            p.eta = 1.0;
        });
        for theta in [0.0f32, 30.0, 60.0, 85.0] {
            let wo = direction(theta, 0.4);
            let cos_d = (theta.to_radians() / 2.0).cos();
            let (fi, fo) = (schlick(1.0), schlick(wo.z));
            let rr = 2.0 * roughness * sqr(cos_d);
            let diffuse = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo) + rr * (fo + fi + fo * fi * (rr - 1.0));
            let fss90 = rr / 2.0;
            let fss = (1.0 + (fss90 - 1.0) * fo) * (1.0 + (fss90 - 1.0) * fi);
            let subsurface = 1.25 * (fss * (1.0 / (wo.z + 1.0) - 0.5) + 0.5);
            let expected = base / PI * ((1.0 - flatness) * diffuse + flatness * subsurface) + sheen * schlick(cos_d);
            let (value, ..) = query(&material, fixed, wo, TransportMode::Radiance);
            assert!(close(value, expected), "r {roughness} fl {flatness} sh {sheen} θ {theta}: {value} vs {expected}");
        }
    }
}

/// A black base with `eta = 1` leaves the clearcoat alone: `0.25·clearcoat·F·D·G` with
/// Schlick's F (R0 = 0.04), GTR1 `D = (α² − 1)/(π ln α² (1 + (α² − 1) cos² θ_h))`,
/// `α = 0.1 + (0.001 − 0.1)·gloss`, and the separable Smith GGX G with α = 0.25.
#[test]
fn clearcoat_follows_the_formula() {
    for (clearcoat, gloss) in [(1.0f32, 0.0f32), (0.5, 0.8)] {
        let material = principled(|p| {
            p.base_color = c(0.0);
            p.clearcoat = c(clearcoat);
            p.clearcoat_gloss = c(gloss);
            p.eta = 1.0;
        });
        let alpha = 0.1 + (0.001 - 0.1) * gloss;
        let smith = |cos: f32| 2.0 / (1.0 + (1.0 + sqr(0.25) * (1.0 - sqr(cos)) / sqr(cos)).sqrt());
        for (ti, to) in [(0.0f32, 0.0f32), (20.0, 25.0), (50.0, 40.0), (70.0, 75.0)] {
            let wi = direction(ti, 0.0);
            let wo = direction(to, PI);
            let h = (wi + wo).normalize();
            let a2 = sqr(alpha);
            let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * sqr(h.z)));
            let f = 0.04 + 0.96 * schlick(wi.dot(h));
            let g = smith(wi.z) * smith(wo.z);
            let expected = 0.25 * clearcoat * f * d * g;
            let (value, ..) = query(&material, wi, wo, TransportMode::Radiance);
            assert!(close(value, expected), "cc {clearcoat} gloss {gloss} {ti}/{to}: {value} vs {expected}");
        }
    }
}

/// The thin sheet with `diff_trans = 2` and no specular part is a Lambertian transmitter
/// `base/π` from both sides, with no reflection; with `diff_trans = 0`, a smooth (roughness 0)
/// Disney diffuse reflector `base/π·(1 − Fi/2)(1 − Fo/2)`.
#[test]
fn thin_sheet_diffuse_lobes_follow_the_formulas() {
    let base = 0.7;
    let transmitter = thin(|p| {
        p.base_color = c(base);
        p.diff_trans = c(2.0);
    });
    let reflector = thin(|p| {
        p.base_color = c(base);
        p.roughness = c(0.0);
    });
    for (ti, to) in [(10.0f32, 130.0f32), (60.0, 100.0), (170.0, 20.0), (120.0, 45.0)] {
        let (wi, wo) = (direction(ti, 0.2), direction(to, 2.5));
        let (value, ..) = query(&transmitter, wi, wo, TransportMode::Radiance);
        assert!(close(value, base / PI), "{ti}/{to}: {value}");
        let mirrored = Vec3::new(wo.x, wo.y, -wo.z);
        let (reflected, ..) = query(&transmitter, wi, mirrored, TransportMode::Radiance);
        assert_eq!(reflected, 0.0);
        let (value, ..) = query(&reflector, wi, mirrored, TransportMode::Radiance);
        let expected = base / PI * (1.0 - 0.5 * schlick(wi.z.abs())) * (1.0 - 0.5 * schlick(wo.z.abs()));
        assert!(close(value, expected), "{ti}/{to}: {value} vs {expected}");
    }
}
