//! Surface vertices of the MIS oracles (`mis_oracle.rs`, `mis_oracle_media.rs`): the four
//! reference materials of their random paths (diffuse, glossy, mirror, glass), their BSDFs and
//! the random normals the path builders give them.

#![allow(dead_code)]

use math::{Rng, Vec3};
use scene::{Bsdf, Material, ReferenceMaterial, ShadingPoint, TransportMode};
use spectrum::Rgb;

/// Diffuse, glossy (Phong), mirror and glass (ior 1.5).
pub fn materials() -> [ReferenceMaterial; 4] {
    [
        ReferenceMaterial::diffuse(Rgb::new(0.6, 0.5, 0.4)),
        ReferenceMaterial {
            diffuse: Rgb::splat(0.2),
            phong: Rgb::splat(0.5),
            phong_exponent: 8.0,
            ..ReferenceMaterial::BLACK
        },
        ReferenceMaterial { mirror: Rgb::splat(0.9), ..ReferenceMaterial::BLACK },
        ReferenceMaterial { mirror: Rgb::splat(1.0), ior: 1.5, ..ReferenceMaterial::BLACK },
    ]
}

/// A uniformly distributed unit vector.
pub fn random_unit(rng: &mut Rng) -> Vec3 {
    math::warp::uniform_sphere(rng.uniform2())
}

/// A unit normal whose cosine with `towards` is at least 0.3.
pub fn facing_normal(towards: Vec3, rng: &mut Rng) -> Vec3 {
    loop {
        let n = (towards + 0.8 * random_unit(rng)).normalize();
        if n.dot(towards) > 0.3 {
            return n;
        }
    }
}

/// The BSDF of a reference material with the shading normal equal to the geometric one.
pub fn reference_bsdf(material: &ReferenceMaterial, normal: Vec3, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
    Bsdf::new(&Material::from(*material), &ShadingPoint::flat(normal), fixed, mode)
}
