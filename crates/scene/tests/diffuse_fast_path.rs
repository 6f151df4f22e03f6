//! The plain `diffuse` material's BSDF (`material/diffuse_bsdf.rs`, built without the leaf-model
//! mixture) against the mixture's own evaluation of the same Lambertian: a blend whose weight is
//! 0 keeps its first material alone with every blend and selection factor exactly 1, so the
//! mixture computes the same floats. Every query must agree bit for bit, on random geometry with
//! interpolated shading normals (both sides of the geometric normal, degenerate ones, tangents),
//! fixed and generated directions from the whole sphere, both transport modes, and textured and
//! black reflectances.

use math::{Rng, Vec2, Vec3};
use scene::{Bsdf, BsdfEval, BsdfSample, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;

fn uniform_sphere(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.uniform();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * rng.uniform();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn bits_of_eval(e: &Option<BsdfEval>) -> Option<[u32; 6]> {
    e.map(|e| {
        [
            e.value.r.to_bits(),
            e.value.g.to_bits(),
            e.value.b.to_bits(),
            e.cos_generated.to_bits(),
            e.pdf.forward.0.to_bits(),
            e.pdf.reverse.0.to_bits(),
        ]
    })
}

fn bits_of_sample(s: &Option<BsdfSample>) -> Option<([u32; 3], [u32; 6], bool)> {
    s.map(|s| {
        let eval = BsdfEval { value: s.value, cos_generated: s.cos_generated, pdf: s.pdf };
        (
            [s.direction.x.to_bits(), s.direction.y.to_bits(), s.direction.z.to_bits()],
            bits_of_eval(&Some(eval)).unwrap(),
            s.dispersive,
        )
    })
}

/// A random shading point: a unit geometric normal, a shading normal tilted from it (sometimes
/// equal, sometimes flipped or degenerate), a tangent (sometimes zero), random uv.
fn shading_point(rng: &mut Rng) -> ShadingPoint {
    let geometric = uniform_sphere(rng);
    let shading = match (rng.uniform() * 5.0) as u32 {
        0 => geometric,
        1 => -(geometric + 0.3 * uniform_sphere(rng)).normalize(),
        2 => geometric.cross(uniform_sphere(rng)).normalize(),
        _ => (geometric + 0.4 * uniform_sphere(rng)).normalize(),
    };
    let tangent = if rng.uniform() < 0.5 { Vec3::ZERO } else { uniform_sphere(rng) };
    ShadingPoint {
        geometric_normal: geometric,
        shading_normal: shading,
        uv: Vec2::new(rng.uniform() * 4.0, rng.uniform() * 4.0),
        tangent,
        attribute: Rgb::BLACK,
    }
}

#[test]
fn diffuse_bsdf_matches_the_mixture_bit_for_bit() {
    let reflectances = [
        Texture::Constant(Rgb::new(0.885809, 0.698859, 0.666422)),
        Texture::Constant(Rgb::new(1.4, 0.2, 0.0)),
        Texture::Constant(Rgb::BLACK),
        Texture::Checkerboard {
            color0: Rgb::new(0.1, 0.5, 0.9),
            color1: Rgb::splat(0.0),
            to_uv: scene::desc::UvTransform::IDENTITY,
        },
    ];
    let mut rng = Rng::for_stream(17, 0, 0);
    let (mut built, mut compared) = (0usize, 0usize);
    for reflectance in reflectances {
        let plain = Material::Diffuse { reflectance: reflectance.clone() };
        let through_mixture = Material::Blend {
            weight: Texture::Constant(Rgb::BLACK),
            first: Box::new(plain.clone()),
            second: Box::new(Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }),
        };
        for _ in 0..4000 {
            let point = shading_point(&mut rng);
            let fixed = uniform_sphere(&mut rng);
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let a = Bsdf::new(&plain, &point, fixed, mode);
                let b = Bsdf::new(&through_mixture, &point, fixed, mode);
                assert_eq!(a.is_some(), b.is_some(), "{point:?} {fixed:?} {mode:?}");
                let (Some(a), Some(b)) = (a, b) else { continue };
                built += 1;
                assert_eq!(a.continuation_probability().to_bits(), b.continuation_probability().to_bits());
                assert_eq!(a.cos_fixed().to_bits(), b.cos_fixed().to_bits());
                assert_eq!(a.fixed_direction(), b.fixed_direction());
                assert_eq!((a.is_delta(), a.has_specular(), a.mode()), (b.is_delta(), b.has_specular(), b.mode()));
                assert_eq!(a.null_transmission(), b.null_transmission());
                for _ in 0..8 {
                    let generated = uniform_sphere(&mut rng);
                    let (ea, eb) = (a.evaluate(generated), b.evaluate(generated));
                    assert_eq!(bits_of_eval(&ea), bits_of_eval(&eb), "evaluate {generated:?}");
                    compared += usize::from(ea.is_some());
                    let u = [rng.uniform(), rng.uniform(), rng.uniform()];
                    assert_eq!(bits_of_sample(&a.sample(u)), bits_of_sample(&b.sample(u)), "sample {u:?}");
                    assert_eq!(a.sample(u).map(|s| s.lobe), b.sample(u).map(|s| s.lobe));
                    assert!(a.sample_specular(u).is_none() && b.sample_specular(u).is_none());
                }
            }
        }
    }
    // The comparison must have exercised the non-trivial cases.
    assert!(built > 5000 && compared > 10000, "built {built}, compared {compared}");
}
