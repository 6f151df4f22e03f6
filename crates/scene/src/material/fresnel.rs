//! Fresnel reflectance of smooth dielectric interfaces, shared by the dielectric, thin,
//! rough and plastic models and by SmallVCM's reference material. (Conductors and the
//! diffuse internal reflectance are in [`crate::microfacet`].)

use math::sqr;

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

/// `int_ior / ext_ior`, or 1 when that is not a positive finite number.
pub(super) fn relative_ior(int_ior: f32, ext_ior: f32) -> f32 {
    let eta = int_ior / ext_ior;
    if eta.is_finite() && eta > 0.0 { eta } else { 1.0 }
}
