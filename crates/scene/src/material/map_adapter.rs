//! What Mitsuba 3's `normalmap` and `bumpmap` adapters do with the perturbed normal at each BSDF
//! query (their `flip_invalid_normals` and `use_shadowing_function`, both on by default since
//! Mitsuba 3.7, and the suite's references were rendered with them):
//!
//! - **Flipping invalid normals** (Schüssler et al. 2017): when the camera-side direction `c`
//!   lies below the perturbed normal `n_p` (`(c·n₀)(c·n_p) ≤ 0`, `n₀` the unperturbed normal),
//!   the BSDF uses `n_p` mirrored about `n₀` (its tangential part negated:
//!   `2(n₀·n_p) n₀ − n_p`) instead of going black.
//! - **Shadowing the bump terminator** (Estevez et al. 2019): the BSDF value is multiplied by
//!   `G(l) = 2 / (1 + √(1 + α² tan²θ_l))`, `θ_l` the angle of the light-side direction `l` to
//!   `n₀` and `α² = min(tan²θ_p / 8, 1)`, `θ_p` the angle of `n_p` to `n₀`.
//!
//! Each is switched by [`MapOptions`] (pbrt's maps use neither). The camera side is the fixed direction in radiance mode and the generated one in importance
//! mode, so that both modes describe one BSDF `f(c, l)` (see [`super::mixture`], which applies
//! this). The scene replaces the hit's shading normal by `n_p`; the unperturbed normal `n₀` is
//! not kept, so the geometric normal stands for it (exact for spheres and flat-shaded meshes;
//! within the angle between face and vertex normals on smooth meshes).

use math::Vec3;

use super::shading::consistent;

/// Which parts of Mitsuba's adapter a normal or bump map uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapOptions {
    /// Mirror the perturbed normal for a camera-side direction below it (Mitsuba's
    /// `flip_invalid_normals`); otherwise such a query scatters nothing.
    pub flip_invalid_normals: bool,
    /// Multiply by the bump-terminator shadowing factor (Mitsuba's `use_shadowing_function`).
    pub shadowing: bool,
}

impl MapOptions {
    /// Mitsuba 3's defaults: both on.
    pub const MITSUBA: MapOptions = MapOptions { flip_invalid_normals: true, shadowing: true };
    /// Neither (pbrt-v4's normal and bump maps).
    pub const NONE: MapOptions = MapOptions { flip_invalid_normals: false, shadowing: false };
}

/// The perturbed normal of a hit and the data of Mitsuba's per-query adapter (all unit vectors,
/// world space, on the side of the geometric normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct MapAdapter {
    /// The unperturbed normal `n₀` (the geometric normal, see the module documentation).
    original: Vec3,
    /// The perturbed normal `n_p`.
    perturbed: Vec3,
    /// `n_p` mirrored about `n₀`.
    flipped: Vec3,
    /// `α²` of the shadowing function (0 without shadowing).
    alpha_squared: f32,
    /// Whether invalid normals are mirrored.
    flip: bool,
}

impl MapAdapter {
    /// The adapter for the perturbed normal `perturbed` at a point whose unperturbed normal is
    /// `original` (both unit, `perturbed` on the side of `original`).
    pub(super) fn new(original: Vec3, perturbed: Vec3, options: MapOptions) -> Self {
        let cos = original.dot(perturbed);
        let flipped = (2.0 * cos * original - perturbed).normalize_or(perturbed);
        let alpha_squared = if options.shadowing { (0.125 * tan_squared(cos)).min(1.0) } else { 0.0 };
        Self { original, perturbed, flipped, alpha_squared, flip: options.flip_invalid_normals }
    }

    /// Whether a query whose camera-side direction is `camera_side` uses the mirrored normal.
    #[inline]
    pub(super) fn flips_for(&self, camera_side: Vec3) -> bool {
        self.flip && camera_side.dot(self.original) * camera_side.dot(self.perturbed) <= 0.0
    }

    /// Whether the importance-mode sampler for the light-side (fixed) direction `light_side`
    /// samples about the mirrored normal: when `light_side` cannot scatter about the
    /// perturbed one (see [`super::mixture`]).
    #[inline]
    pub(super) fn sampler_flips_for(&self, light_side: Vec3) -> bool {
        self.flip && !consistent(light_side.dot(self.original), light_side.dot(self.perturbed))
    }

    /// The perturbed normal, mirrored when `flipped`.
    #[inline]
    pub(super) fn normal(&self, flipped: bool) -> Vec3 {
        if flipped { self.flipped } else { self.perturbed }
    }

    /// The shadowing factor `G(l)` ∈ (0, 1] for the unit light-side direction `light_side`.
    #[inline]
    pub(super) fn shadowing(&self, light_side: Vec3) -> f32 {
        if self.alpha_squared == 0.0 {
            return 1.0;
        }
        let tan2 = tan_squared(light_side.dot(self.original));
        let g = 2.0 / (1.0 + (1.0 + self.alpha_squared * tan2).sqrt());
        if g.is_finite() { g } else { 0.0 }
    }
}

/// `tan²θ` from `cos θ` (infinite at `cos θ = 0`).
#[inline]
fn tan_squared(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0) / (cos * cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A normal tilted by `angle` from +z towards +x.
    fn tilted(angle: f32) -> Vec3 {
        Vec3::new(angle.sin(), 0.0, angle.cos())
    }

    #[test]
    fn the_mirrored_normal_negates_the_tangential_part() {
        let a = MapAdapter::new(Vec3::Z, Vec3::new(0.3, -0.4, 0.866).normalize(), MapOptions::MITSUBA);
        let p = a.normal(false);
        let f = a.normal(true);
        assert!((f - Vec3::new(-p.x, -p.y, p.z)).length() < 1e-6, "{f} against {p}");
    }

    #[test]
    fn flipping_follows_the_camera_side_direction() {
        let a = MapAdapter::new(Vec3::Z, tilted(0.5), MapOptions::MITSUBA);
        // Above both tangent planes; below the tilted one (grazing, tilted away); behind.
        assert!(!a.flips_for(tilted(-0.3)));
        assert!(a.flips_for(tilted(-1.4)));
        assert!(!a.flips_for(-tilted(0.2)));
    }

    #[test]
    fn shadowing_matches_the_closed_form() {
        // θ_p = 30°: α² = tan²30° / 8 = 1/24; at θ_l = 60°, tan² = 3: G = 2 / (1 + √(1 + 1/8)).
        let a = MapAdapter::new(Vec3::Z, tilted(30f32.to_radians()), MapOptions::MITSUBA);
        let expected = 2.0 / (1.0 + (1.0f32 + 3.0 / 24.0).sqrt());
        let g = a.shadowing(tilted(60f32.to_radians()));
        assert!((g - expected).abs() < 1e-5, "{g} against {expected}");
        // No perturbation, no shadowing; grazing light, no light at all.
        assert_eq!(MapAdapter::new(Vec3::Z, Vec3::Z, MapOptions::MITSUBA).shadowing(tilted(1.5)), 1.0);
        assert!(a.shadowing(Vec3::X) < 1e-3);
        // α² saturates at 1 (θ_p ≥ 70.5°).
        let steep = MapAdapter::new(Vec3::Z, tilted(80f32.to_radians()), MapOptions::MITSUBA);
        let g = steep.shadowing(tilted(45f32.to_radians()));
        assert!((g - 2.0 / (1.0 + 2f32.sqrt())).abs() < 1e-5, "{g}");
    }
}
