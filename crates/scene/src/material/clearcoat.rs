//! The clearcoat lobe of the `principled` model: Burley's GTR1 ("Berry") distribution of
//! normals with α = lerp(0.1, 0.001, clearcoat_gloss), Schlick's Fresnel with R0 = 0.04, and a
//! separable Smith GGX masking with α = 0.25. The value follows Mitsuba 3:
//! `f = 0.25 · clearcoat · F · D · G` (per steradian; no `1/(4 cos θ_i cos θ_o)` factor).
//! Sampling draws `m` with density `D(m) cos θ_m` (per steradian of `m`) and reflects.

use math::{PI, Vec3, sqr};

use super::disney::{lerp, schlick_fresnel};
use spectrum::Rgb;

/// The clearcoat lobe's distribution of microfacet normals.
#[derive(Clone, Copy, Debug)]
pub(super) struct Clearcoat {
    /// Lobe weight (`clearcoat`).
    pub weight: f32,
    /// GTR1 α.
    pub alpha: f32,
}

impl Clearcoat {
    /// The lobe for `clearcoat` and `clearcoat_gloss`.
    pub(super) fn new(clearcoat: f32, gloss: f32) -> Self {
        Clearcoat { weight: clearcoat, alpha: lerp(0.1, 0.001, gloss) }
    }

    /// GTR1 `D(m) = (α² − 1) / (π ln(α²) (1 + (α² − 1) cos² θ_m))` (0 below the surface).
    pub(super) fn d(&self, m: Vec3) -> f32 {
        let a2 = sqr(self.alpha);
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * sqr(m.z)));
        if d * m.z > 1e-20 && d.is_finite() { d } else { 0.0 }
    }

    /// Density of [`Clearcoat::sample_normal`] per steradian of `m`: `D(m) cos θ_m`.
    pub(super) fn normal_pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 { 0.0 } else { m.z * self.d(m) }
    }

    /// A microfacet normal with density `D(m) cos θ_m`.
    pub(super) fn sample_normal(&self, u: [f32; 2]) -> Vec3 {
        let (sin_phi, cos_phi) = math::sin_cos_turns(u[0]);
        let a2 = sqr(self.alpha);
        let cos2 = ((1.0 - a2.powf(1.0 - u[1])) / (1.0 - a2)).clamp(0.0, 1.0);
        let sin = (1.0 - cos2).sqrt();
        Vec3::new(cos_phi * sin, sin_phi * sin, cos2.sqrt())
    }

    /// The lobe's value for `wi`, `wo` above the surface with half vector `h` (on +z) at an
    /// interface of relative IOR `eta` (for Schlick's Fresnel).
    pub(super) fn value(&self, wi: Vec3, wo: Vec3, h: Vec3, eta: f32) -> f32 {
        let fresnel = schlick_fresnel(Rgb::splat(0.04), wi.dot(h), eta).r;
        let g = smith_g1(wi, h, 0.25) * smith_g1(wo, h, 0.25);
        0.25 * self.weight * fresnel * self.d(h) * g
    }
}

/// Smith's isotropic GGX masking `2 / (1 + √(1 + α² tan² θ))` of `v` with the microfacet `h`
/// (0 when `v` sees the back of the microfacet).
fn smith_g1(v: Vec3, h: Vec3, alpha: f32) -> f32 {
    if v.dot(h) * v.z <= 0.0 {
        return 0.0;
    }
    let c2 = sqr(v.z);
    if c2 >= 1.0 {
        return 1.0;
    }
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + sqr(alpha) * tan2).sqrt())
}
