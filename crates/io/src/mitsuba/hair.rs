//! `<bsdf type="hair">`: Mitsuba 3's hair BSDF (Chiang et al. 2016, the model of
//! [`scene::material::HairParameters`]). Properties: `eumelanin` and `pheomelanin` (default 1.3
//! and 0.2) or `sigma_a` (a constant colour; not both), times `scale` (default 1); `int_ior`
//! (default 1.55, Mitsuba's "amber") and `ext_ior` (default air) give `η = int/ext`;
//! `longitudinal_roughness` and `azimuthal_roughness` (`β_m`, `β_n`, default 0.3, in [0, 1]);
//! `scale_tilt` (`α`, degrees, default 2). Mitsuba's transmittance uses the same chord length
//! `2 cos γ_t / cos θ_t` as pbrt, so its `sigma_a·scale` is our `σ_a` per fibre radius.

use scene::material::{HairParameters, Material};
use spectrum::Rgb;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::Plugin;
use crate::scene_error::SceneError;

impl<'a> Loader<'a> {
    /// The hair material of `p` (see the module documentation).
    pub(crate) fn hair(&mut self, p: &Plugin<'a>) -> Result<Material, SceneError> {
        let pigments = p.has("eumelanin") || p.has("pheomelanin");
        let sigma_a = match p.color("sigma_a", SpectrumUse::Unbounded, &mut self.warnings)? {
            Some(_) if pigments => {
                return Err(p.error("give either the pigments (eumelanin, pheomelanin) or 'sigma_a', not both"));
            }
            Some(c) => Rgb::new(c[0] as f32, c[1] as f32, c[2] as f32),
            None => HairParameters::sigma_a_from_melanin(
                p.float_or("eumelanin", 1.3)? as f32,
                p.float_or("pheomelanin", 0.2)? as f32,
            ),
        };
        let scale = p.float_or("scale", 1.0)? as f32;
        let int_ior = self.ior(p, "int_ior", 1.55)?;
        let ext_ior = self.ior(p, "ext_ior", 1.000277)?;
        if int_ior == ext_ior {
            return Err(p.error("the interior and exterior indices of refraction must differ"));
        }
        let hair = HairParameters {
            sigma_a: sigma_a * scale,
            eta: (int_ior / ext_ior) as f32,
            beta_m: p.float_or("longitudinal_roughness", 0.3)? as f32,
            beta_n: p.float_or("azimuthal_roughness", 0.3)? as f32,
            alpha: p.float_or("scale_tilt", 2.0)? as f32,
        };
        hair.validate().map_err(|e| p.error(e))?;
        Ok(Material::Hair(hair))
    }
}
