//! Materials of the reference scenes and the per-hit BSDF built from them.
//!
//! A [`Material`] is a sum of components: Lambertian diffuse, normalised Phong, a perfect mirror
//! and, when `ior ≥ 0`, a smooth dielectric (the mirror part becomes Fresnel-weighted and a
//! refraction lobe appears). A [`Bsdf`] is built per hit from the material, the geometric normal,
//! the *fixed* direction (the one the walk arrived from, pointing away from the surface) and the
//! [`TransportMode`]. Every query takes the *generated* direction and returns both pdfs:
//! `forward` (fixed → generated) and `reverse` (generated → fixed), in solid angle. Russian
//! roulette is **not** included in these pdfs; the integrator multiplies them by
//! [`Bsdf::continuation_probability`].
//!
//! Diffuse and Phong are one-sided: zero unless both directions lie at least
//! [`COSINE_EPSILON`] above the surface on the side the normal points to. Mirror and glass
//! work from both sides. Specular lobes use "pdf = probability of picking the lobe" and
//! value `ρ/|cos θ|` (tech report eq. 52).

use math::{COSINE_EPSILON, Frame, INV_PI, PdfW, Vec2, Vec3, sqr, warp};

use crate::texture::Texture;
use spectrum::Rgb;

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
}

/// A material: the closed set of scattering models the renderer knows. Index-of-refraction
/// fields are absolute (`int_ior` inside, `ext_ior` outside, the side the geometric normal
/// points to); `alpha` is the GGX roughness (`α = roughness²` in the Disney convention, as
/// Mitsuba's `alpha`). Conductors take the complex IOR `eta + i·k` relative to the outside.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// SmallVCM's component material (built-in scenes).
    Reference(ReferenceMaterial),
    /// Lambertian, one-sided (black from behind, as Mitsuba's `diffuse`).
    Diffuse {
        /// Reflectance.
        reflectance: Texture,
    },
    /// Smooth conductor (Fresnel-weighted mirror); `eta = 0, k = ∞`-like perfect mirrors use
    /// [`Material::perfect_mirror`].
    Conductor {
        /// Real part of the relative IOR per channel.
        eta: Rgb,
        /// Imaginary part (absorption) per channel.
        k: Rgb,
        /// Factor on the reflection.
        specular_reflectance: Texture,
    },
    /// GGX microfacet conductor with visible-normal sampling.
    RoughConductor {
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
        /// Real part of the relative IOR per channel.
        eta: Rgb,
        /// Imaginary part per channel.
        k: Rgb,
        /// Factor on the reflection.
        specular_reflectance: Texture,
    },
    /// Smooth dielectric interface (Fresnel reflection + refraction).
    Dielectric {
        /// IOR inside.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Thin dielectric sheet: reflection and straight-through transmission with the
    /// inter-reflections of a thin slab summed analytically.
    ThinDielectric {
        /// IOR of the sheet.
        int_ior: f32,
        /// IOR around it.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// GGX microfacet dielectric (Walter et al. 2007).
    RoughDielectric {
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
        /// IOR inside.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Diffuse base under a smooth dielectric coating (Mitsuba's `plastic`).
    Plastic {
        /// Reflectance of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's specular reflection.
        specular_reflectance: Texture,
        /// IOR of the coating.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Account for colour shifts from internal scattering (Mitsuba's `nonlinear`).
        nonlinear: bool,
    },
    /// Diffuse base under a rough (GGX) dielectric coating (Mitsuba's `roughplastic`).
    RoughPlastic {
        /// Isotropic GGX roughness of the coating.
        alpha: f32,
        /// Reflectance of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's specular reflection.
        specular_reflectance: Texture,
        /// IOR of the coating.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Account for colour shifts from internal scattering.
        nonlinear: bool,
    },
    /// Linear blend `(1 − weight)·first + weight·second`.
    Blend {
        /// Blend weight in [0, 1] (the first channel of the texture is used).
        weight: Texture,
        /// Material at weight 0.
        first: Box<Material>,
        /// Material at weight 1.
        second: Box<Material>,
    },
    /// Makes a one-sided material two-sided: seen from behind it behaves as `back` (or as
    /// `front` when `back` is `None`) with the normal flipped.
    TwoSided {
        /// Material on the front side.
        front: Box<Material>,
        /// Material on the back side; `None` = the same as the front.
        back: Option<Box<Material>>,
    },
}

impl Material {
    /// A perfect mirror (Mitsuba's `conductor` without a material).
    pub fn perfect_mirror() -> Self {
        Material::Conductor { eta: Rgb::BLACK, k: Rgb::BLACK, specular_reflectance: Texture::Constant(Rgb::WHITE) }
    }
}

impl From<ReferenceMaterial> for Material {
    fn from(m: ReferenceMaterial) -> Self {
        Material::Reference(m)
    }
}

/// The local geometry at a surface point that a BSDF needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Unit geometric normal (defines the sides of the surface and all cosines the
    /// integrators use).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated mesh normal; equal to the geometric normal
    /// otherwise). BSDF lobes are oriented by it.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
}

impl ShadingPoint {
    /// A point whose shading normal is its geometric normal, at uv (0, 0).
    pub fn flat(normal: Vec3) -> Self {
        Self { geometric_normal: normal, shading_normal: normal, uv: Vec2::ZERO }
    }
}

/// Which quantity a sub-path carries. The adjoint BSDF differs for refraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    /// Camera sub-paths: radiance flows towards the fixed direction.
    Radiance,
    /// Light sub-paths: importance flows towards the fixed direction.
    Importance,
}

/// Which kind of lobe produced a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    /// Lambertian.
    Diffuse,
    /// Normalised Phong.
    Glossy,
    /// Perfect reflection (delta).
    SpecularReflection,
    /// Perfect refraction (delta).
    SpecularTransmission,
}

impl LobeKind {
    /// True for the delta lobes.
    pub fn is_specular(self) -> bool {
        matches!(self, LobeKind::SpecularReflection | LobeKind::SpecularTransmission)
    }
}

/// Forward and reverse solid-angle pdfs of one direction pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdfPair {
    /// Density of generating the generated direction given the fixed one.
    pub forward: PdfW,
    /// Density of generating the fixed direction given the generated one.
    pub reverse: PdfW,
}

/// Result of [`Bsdf::evaluate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfEval {
    /// BSDF value f (per steradian), without the cosine.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction with the normal.
    pub cos_generated: f32,
    /// Lobe-selection-weighted pdfs of the non-specular lobes.
    pub pdf: PdfPair,
}

/// Result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The generated unit direction (world space, pointing away from the surface).
    pub direction: Vec3,
    /// BSDF value f; for specular lobes `ρ/|cos θ|`.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction.
    pub cos_generated: f32,
    /// pdfs; for specular lobes the lobe-selection probability.
    pub pdf: PdfPair,
    /// The lobe that was sampled.
    pub lobe: LobeKind,
}

/// Lobe selection probabilities, proportional to each lobe's albedo (luminance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct LobeProbabilities {
    diffuse: f32,
    phong: f32,
    reflect: f32,
    refract: f32,
}

/// A BSDF at one hit, for one fixed direction and transport mode.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    material: ReferenceMaterial,
    frame: Frame,
    local_fixed: Vec3,
    mode: TransportMode,
    probabilities: LobeProbabilities,
    fresnel: f32,
    continuation: f32,
}

/// Unpolarised Fresnel reflectance of a smooth dielectric with relative IOR `ior` (inside over
/// outside) for a direction with cosine `cos_incident` to the outward normal (negative: the
/// direction is inside). Returns 1 for total internal reflection and for `ior < 0`.
pub fn fresnel_dielectric(cos_incident: f32, ior: f32) -> f32 {
    if ior < 0.0 {
        return 1.0;
    }
    let (cos_i, eta) = if cos_incident < 0.0 { (-cos_incident, ior) } else { (cos_incident, 1.0 / ior) };
    // eta = η_incident / η_transmitted.
    let sin_t2 = sqr(eta) * (1.0 - sqr(cos_i)).max(0.0);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let r_parallel = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_perpendicular = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (sqr(r_parallel) + sqr(r_perpendicular))
}

/// `x^n` for the Phong exponent: repeated squaring for integer exponents (the usual case,
/// several times faster than `powf`), `powf` otherwise.
#[inline]
fn pow_exponent(x: f32, n: f32) -> f32 {
    if n.fract() == 0.0 && (0.0..=4096.0).contains(&n) { x.powi(n as i32) } else { x.powf(n) }
}

impl Bsdf {
    /// Builds the BSDF at a hit with unit geometric `normal` for the unit `fixed` direction
    /// (pointing away from the surface). Returns `None` when the material cannot scatter
    /// (all components black) or the fixed direction is grazing.
    pub fn new(material: &Material, point: &ShadingPoint, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
        match material {
            Material::Reference(m) => Self::reference(m, point.geometric_normal, fixed, mode),
            _ => None,
        }
    }

    fn reference(material: &ReferenceMaterial, normal: Vec3, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
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
        Some(Bsdf { material: *material, frame, local_fixed, mode, probabilities, fresnel, continuation })
    }

    /// Probability of continuing a path through this vertex (Russian roulette). It enters the
    /// MIS pdfs as a factor.
    pub fn continuation_probability(&self) -> f32 {
        self.continuation
    }

    /// True when every lobe with non-zero probability is a delta lobe, so that evaluation is
    /// always zero and the vertex cannot be connected to or merged at.
    pub fn is_delta(&self) -> bool {
        self.probabilities.diffuse == 0.0 && self.probabilities.phong == 0.0
    }

    /// The transport mode the BSDF was built for.
    pub fn mode(&self) -> TransportMode {
        self.mode
    }

    /// `|cos θ|` of the fixed direction with the geometric normal.
    pub fn cos_fixed(&self) -> f32 {
        self.local_fixed.z.abs()
    }

    /// The fixed direction in world space.
    pub fn fixed_direction(&self) -> Vec3 {
        self.frame.to_world(self.local_fixed)
    }

    /// Evaluates the non-specular lobes for the unit world direction `generated`. Returns
    /// `None` when the value is zero (other side of the surface, below a one-sided lobe, or a
    /// purely specular material).
    pub fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
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
    pub fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
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
            let eval = self.evaluate(direction)?;
            if eval.pdf.forward.0 <= 0.0 {
                return None;
            }
            let lobe = if pick < p.diffuse { LobeKind::Diffuse } else { LobeKind::Glossy };
            return Some(BsdfSample {
                direction,
                value: eval.value,
                cos_generated: eval.cos_generated,
                pdf: eval.pdf,
                lobe,
            });
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
    pub fn sample_specular(&self, u: [f32; 3]) -> Option<BsdfSample> {
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
    pub fn has_specular(&self) -> bool {
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
        })
    }
}
