//! pbrt-v4's `goniometric` light: a point light whose intensity over the sphere is a square
//! image in the equal-area octahedral parametrisation (facts from pbrt-v4's
//! `GoniometricLight::Create`):
//! * `string filename` (required here: without it pbrt-v4 warns and emits nothing), a square
//!   image; its single channel is the mean of R, G and B (or its `Y` channel);
//! * `spectrum I` (default: the colour space's illuminant, i.e. white in RGB), normalised to
//!   unit luminance like every pbrt-v4 light spectrum, times `float scale` (default 1);
//! * `float power` (> 0): scales the light to that flux, `scale *= power / (4π · mean(image))`;
//! * the light's frame is the current transformation with its y and z axes swapped: the image's
//!   centre (the map's +z) points along the light space's +y.

use std::path::Path;
use std::sync::Arc;

use scene::desc::LightDesc;
use spectrum::Rgb;

use super::lights::light_image;
use super::parser::Directive;
use super::transform::{Mat4, normalize};
use super::{err, f32v, resolve, similarity_scale};
use crate::scene_error::SceneError;

/// The light of directive `d` (file `file`) under the transformation `ctm`, with the intensity
/// `intensity` (`I` × `scale`, as the caller read them).
pub(super) fn goniometric_light(
    file: &Path,
    d: &Directive,
    ctm: &Mat4,
    intensity: Rgb,
) -> Result<LightDesc, SceneError> {
    let p = &d.params;
    let (filename, fpos) =
        p.string("filename")?.ok_or_else(|| err(file, d.pos, "goniometric: \"filename\" is required"))?;
    let image = light_image(&resolve(file, &filename), 1.0).map_err(|e| p.error(fpos, e))?;
    if image.width != image.height || image.width == 0 {
        return Err(p.error(
            fpos,
            format!(
                "goniometric: the image is {}×{}; pbrt-v4 needs a square equal-area octahedral image",
                image.width, image.height
            ),
        ));
    }
    let mut intensity = intensity;
    if let Some(power) = p.float_opt("power")?.filter(|&power| power > 0.0) {
        let sum: f64 = image.pixels.iter().map(|t| f64::from(t.r + t.g + t.b) / 3.0).sum();
        let flux = 4.0 * std::f64::consts::PI * sum / image.pixels.len() as f64;
        if flux <= 0.0 {
            return Err(p.error(fpos, "goniometric: a black image cannot have a power"));
        }
        intensity *= (f64::from(power) / flux) as f32;
    }
    if similarity_scale(ctm).is_none() {
        return Err(err(file, d.pos, "goniometric light under a non-uniform scale or shear"));
    }
    let axis = |v| normalize(ctm.vector(v)).map(f32v).ok_or_else(|| err(file, d.pos, "singular transformation"));
    let (x, y, z) = (axis([1.0, 0.0, 0.0])?, axis([0.0, 1.0, 0.0])?, axis([0.0, 0.0, 1.0])?);
    Ok(LightDesc::Goniometric {
        position: f32v(ctm.point([0.0; 3])),
        // pbrt-v4 swaps y and z: the map's local (x, y, z) is the light space's (x, z, y).
        frame: [x, z, y],
        image: Arc::clone(&image),
        intensity,
    })
}
