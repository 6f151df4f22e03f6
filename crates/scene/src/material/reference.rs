//! SmallVCM's material (the built-in reference scenes): a sum of Lambertian diffuse,
//! normalised Phong, a perfect mirror and, when `ior ≥ 0`, a smooth dielectric, on the
//! geometric normal only. Diffuse and Phong are one-sided: zero unless both directions lie at
//! least [`COSINE_EPSILON`] above the surface; mirror and glass work from both sides. Lobes
//! are chosen in proportion to their albedos; the non-delta pdfs are solid-angle densities
//! (cosine `cos θ/π`, Phong `(n+1)/(2π) cos^n α`) times the lobe probability; a delta lobe's
//! "pdf" is its probability.

use math::{COSINE_EPSILON, Frame, INV_PI, PdfW, Vec3, sqr, warp};
use spectrum::Rgb;

use super::fresnel::fresnel_dielectric;
use super::query::{BsdfEval, BsdfSample, LobeKind, PdfPair};
use super::shading::TransportMode;

/// Below this cosine between the generated direction and the mirrored fixed direction, the
/// Phong lobe is zero.
const PHONG_COSINE_EPSILON: f32 = 1e-3;

/// SmallVCM's material as a sum of components (all reflectances in `[0, 1]` per channel): the
/// material of the built-in reference scenes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceMaterial {
    /// Lambertian reflectance ρd.
    pub diffuse: Rgb,
    /// Phong reflectance ρs.
    pub phong: Rgb,
    /// Phong exponent n.
    pub phong_exponent: f32,
    /// Mirror reflectance ρm (Fresnel-weighted when `ior ≥ 0`).
    pub mirror: Rgb,
    /// Relative index of refraction inside/outside; negative means "no refraction".
    pub ior: f32,
}

impl ReferenceMaterial {
    /// A material that absorbs everything (used for emitters).
    pub const BLACK: ReferenceMaterial = ReferenceMaterial {
        diffuse: Rgb::BLACK,
        phong: Rgb::BLACK,
        phong_exponent: 1.0,
        mirror: Rgb::BLACK,
        ior: -1.0,
    };

    /// Pure Lambertian reflector.
    pub const fn diffuse(rho: Rgb) -> Self {
        ReferenceMaterial { diffuse: rho, ..Self::BLACK }
    }

    /// True when neither the diffuse nor the Phong lobe reflects anything, so that a BSDF built
    /// from this material is purely specular ([`crate::Bsdf::is_delta`]) or absorbs everything
    /// (no BSDF) at every point and for every direction: no vertex on it is connected to or
    /// merged at.
    pub fn is_specular_only(&self) -> bool {
        self.diffuse.luminance() == 0.0 && self.phong.luminance() == 0.0
    }
}

/// Lobe selection probabilities, proportional to each lobe's albedo (luminance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct LobeProbabilities {
    diffuse: f32,
    phong: f32,
    reflect: f32,
    refract: f32,
}

/// SmallVCM's BSDF (the [`Material::Reference`] case), built on the geometric normal only.
#[derive(Clone, Copy, Debug)]
pub(super) struct ReferenceBsdf {
    material: ReferenceMaterial,
    frame: Frame,
    local_fixed: Vec3,
    pub(super) mode: TransportMode,
    probabilities: LobeProbabilities,
    fresnel: f32,
    continuation: f32,
}

/// `x^n` for the Phong exponent: repeated squaring for integer exponents (the usual case,
/// several times faster than `powf`), `powf` otherwise.
#[inline]
fn pow_exponent(x: f32, n: f32) -> f32 {
    if n.fract() == 0.0 && (0.0..=4096.0).contains(&n) { x.powi(n as i32) } else { x.powf(n) }
}

impl ReferenceBsdf {
    #[inline]
    pub(super) fn new(
        material: &ReferenceMaterial,
        normal: Vec3,
        fixed: Vec3,
        mode: TransportMode,
    ) -> Option<ReferenceBsdf> {
        let frame = Frame::from_z(normal);
        let local_fixed = frame.to_local(fixed);
        if local_fixed.z.abs() < COSINE_EPSILON {
            return None;
        }
        let fresnel = fresnel_dielectric(local_fixed.z, material.ior);
        let albedo_diffuse = material.diffuse.luminance();
        let albedo_phong = material.phong.luminance();
        let albedo_reflect = fresnel * material.mirror.luminance();
        let albedo_refract = if material.ior > 0.0 { 1.0 - fresnel } else { 0.0 };
        let total = albedo_diffuse + albedo_phong + albedo_reflect + albedo_refract;
        if total < 1e-9 {
            return None;
        }
        let probabilities = LobeProbabilities {
            diffuse: albedo_diffuse / total,
            phong: albedo_phong / total,
            reflect: albedo_reflect / total,
            refract: albedo_refract / total,
        };
        // Russian roulette keeps the path with the largest per-channel albedo, so a path's
        // weight never grows through the roulette (refraction has weight 1 − F).
        let refract_weight = if material.ior > 0.0 { 1.0 - fresnel } else { 0.0 };
        let continuation =
            ((material.diffuse + material.phong + material.mirror * fresnel).max_component() + refract_weight).min(1.0);
        Some(ReferenceBsdf { material: *material, frame, local_fixed, mode, probabilities, fresnel, continuation })
    }

    /// Probability of continuing a path through this vertex (Russian roulette). It enters the
    /// MIS pdfs as a factor.
    pub(super) fn continuation_probability(&self) -> f32 {
        self.continuation
    }

    /// True when every lobe with non-zero probability is a delta lobe, so that evaluation is
    /// always zero and the vertex cannot be connected to or merged at.
    pub(super) fn is_delta(&self) -> bool {
        self.probabilities.diffuse == 0.0 && self.probabilities.phong == 0.0
    }

    /// `|cos θ|` of the fixed direction with the geometric normal.
    pub(super) fn cos_fixed(&self) -> f32 {
        self.local_fixed.z.abs()
    }

    /// The fixed direction in world space.
    pub(super) fn fixed_direction(&self) -> Vec3 {
        self.frame.to_world(self.local_fixed)
    }

    /// Evaluates the non-specular lobes for the unit world direction `generated`. Returns
    /// `None` when the value is zero (other side of the surface, below a one-sided lobe, or a
    /// purely specular material).
    pub(super) fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        let local_generated = self.frame.to_local(generated);
        if local_generated.z * self.local_fixed.z <= 0.0 {
            return None;
        }
        let mut value = Rgb::BLACK;
        let mut pdf = PdfPair::default();
        self.add_non_delta(local_generated, &mut value, &mut pdf);
        if value.is_black() {
            return None;
        }
        Some(BsdfEval { value, cos_generated: local_generated.z.abs(), pdf })
    }

    /// Samples a direction with three uniform numbers: `u[2]` picks the lobe (in proportion to
    /// the lobe albedos), `u[0..2]` the direction within it. Returns `None` when the sample
    /// carries no energy (e.g. a Phong direction below the surface, which is rejected rather
    /// than continued through the surface).
    pub(super) fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let p = self.probabilities;
        let pick = u[2];
        if pick < p.diffuse + p.phong {
            let local = if pick < p.diffuse {
                if self.local_fixed.z < COSINE_EPSILON {
                    return None;
                }
                warp::cosine_hemisphere([u[0], u[1]])
            } else {
                let lobe_axis = self.reflected_fixed();
                Frame::from_z(lobe_axis).to_world(warp::power_cosine([u[0], u[1]], self.material.phong_exponent))
            };
            // Evaluate the world direction exactly as `evaluate` would, so that a sample and
            // the evaluation of its direction always agree (also at the horizon).
            let direction = self.frame.to_world(local);
            let lobe = if pick < p.diffuse { LobeKind::Diffuse } else { LobeKind::Glossy };
            return BsdfSample::of_lobe(direction, self.evaluate(direction)?, lobe);
        }
        if pick < p.diffuse + p.phong + p.reflect {
            return Some(self.sample_reflection(p.reflect));
        }
        self.sample_refraction(p.refract)
    }

    /// Samples only the specular (delta) lobes, chosen in proportion to their albedos among
    /// themselves (`u[2]` picks the lobe). The pdfs are the probabilities of that restricted
    /// choice. Used where the non-specular part is estimated otherwise, e.g. photon mapping
    /// merges at a mixed vertex and continues through its specular part only. `None` when the
    /// material has no specular lobe.
    pub(super) fn sample_specular(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let p = self.probabilities;
        let specular = p.reflect + p.refract;
        if specular <= 0.0 {
            return None;
        }
        if u[2] * specular < p.reflect {
            Some(self.sample_reflection(p.reflect / specular))
        } else {
            self.sample_refraction(p.refract / specular)
        }
    }

    /// True when the material has a specular (delta) lobe.
    pub(super) fn has_specular(&self) -> bool {
        self.probabilities.reflect + self.probabilities.refract > 0.0
    }

    /// The mirror lobe, chosen with probability `probability`.
    fn sample_reflection(&self, probability: f32) -> BsdfSample {
        let local = self.reflected_fixed();
        let cos = local.z.abs();
        BsdfSample {
            direction: self.frame.to_world(local),
            value: self.material.mirror * (self.fresnel / cos),
            cos_generated: cos,
            pdf: PdfPair { forward: PdfW(probability), reverse: PdfW(probability) },
            lobe: LobeKind::SpecularReflection,
            dispersive: false,
        }
    }

    /// The fixed direction mirrored about the normal, in local coordinates.
    fn reflected_fixed(&self) -> Vec3 {
        Vec3::new(-self.local_fixed.x, -self.local_fixed.y, self.local_fixed.z)
    }

    /// Adds diffuse and Phong values and their selection-weighted pdfs for a local direction.
    fn add_non_delta(&self, local_generated: Vec3, value: &mut Rgb, pdf: &mut PdfPair) {
        let p = self.probabilities;
        let fixed = self.local_fixed;
        if fixed.z < COSINE_EPSILON || local_generated.z < COSINE_EPSILON {
            return;
        }
        if p.diffuse > 0.0 {
            *value += self.material.diffuse * INV_PI;
            pdf.forward.0 += p.diffuse * warp::cosine_hemisphere_pdf(local_generated.z);
            pdf.reverse.0 += p.diffuse * warp::cosine_hemisphere_pdf(fixed.z);
        }
        if p.phong > 0.0 {
            let cos_alpha = self.reflected_fixed().dot(local_generated);
            if cos_alpha > PHONG_COSINE_EPSILON {
                let n = self.material.phong_exponent;
                let lobe = pow_exponent(cos_alpha, n);
                *value += self.material.phong * ((n + 2.0) * 0.5 * INV_PI * lobe);
                // The lobe around reflect(fixed) evaluated at generated has the same cosine
                // as the lobe around reflect(generated) evaluated at fixed.
                let density = p.phong * (n + 1.0) * 0.5 * INV_PI * lobe;
                pdf.forward.0 += density;
                pdf.reverse.0 += density;
            }
        }
    }

    /// The refraction lobe, chosen with probability `probability`; `None` under total internal
    /// reflection or without a dielectric.
    fn sample_refraction(&self, probability: f32) -> Option<BsdfSample> {
        if probability <= 0.0 {
            return None;
        }
        let fixed = self.local_fixed;
        // eta = η on the fixed side / η on the generated side.
        let (eta, sign) = if fixed.z > 0.0 { (1.0 / self.material.ior, -1.0) } else { (self.material.ior, 1.0) };
        let sin_t2 = sqr(eta) * (1.0 - sqr(fixed.z)).max(0.0);
        if sin_t2 >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin_t2).sqrt();
        let local = Vec3::new(-eta * fixed.x, -eta * fixed.y, sign * cos_t);
        let transmit = 1.0 - self.fresnel;
        // Radiance is compressed by (η_fixed/η_generated)² when it crosses into the denser
        // medium towards the camera; importance is not (Veach 1997, §5.2).
        let scale = match self.mode {
            TransportMode::Radiance => transmit * sqr(eta),
            TransportMode::Importance => transmit,
        };
        Some(BsdfSample {
            direction: self.frame.to_world(local),
            value: Rgb::splat(scale / cos_t),
            cos_generated: cos_t,
            pdf: PdfPair { forward: PdfW(probability), reverse: PdfW(probability) },
            lobe: LobeKind::SpecularTransmission,
            dispersive: false,
        })
    }
}
