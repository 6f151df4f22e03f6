//! The initial merging radius r_0 (world units): the length the radius factor multiplies (the
//! scene's *merging scale*), the resolution rule of [`RadiusMode::Global`] and the per-pixel
//! footprints of [`RadiusMode::PerPixel`]. The iteration schedule r_i = r_0 · (i+1)^((α−1)/2)
//! lives in the engine.
//!
//! **Merging scale.** The scale is the scene's bounding-sphere radius R_scene unless the camera
//! sees a much smaller part of the scene. The visible part is measured by probe rays: the
//! pinhole (lens-centre) rays through the (G+1)² raster points `(W·i/G, H·j/G)`, `i, j ∈ 0..=G`,
//! G = [`VISIBLE_PROBES`] (the image's corners and edges included); R_vis is the radius of the
//! bounding sphere of the box around the points they hit. With s = R_vis / R_scene:
//!
//! ```text
//!             ⎧ R_scene            s ≥ 1/2
//! scale   =   ⎨ 4 s² · R_scene     1/4 < s < 1/2
//!             ⎩ R_vis              s ≤ 1/4
//! ```
//!
//! A camera that sees most of the scene (the built-in Cornell boxes: s = 0.97–0.99) keeps
//! exactly the scene-relative radius, bit for bit; a camera that sees a small part of a large
//! scene (Mitsuba's projector scenes: a 2000-unit floor seen over ±11 units, s ≈ 0.01) gets a
//! radius relative to what it sees, so merging does not blur the image over many pixels. The
//! middle branch joins the two continuously and monotonically (4s² = 1 at s = 1/2, = s at
//! s = 1/4). When no probe ray hits anything, or the hits span a single point, the scale is
//! R_scene. The probes run in a fixed order on the calling thread, so the scale is a function
//! of the scene alone: every rank of a distributed render, a resumed render and the
//! memory-efficient mode compute the same radius.
//!
//! Why the visible part: merging happens at camera vertices, and the radius trades blur (bias,
//! growing with r relative to the image's features) for noise. The features the image resolves
//! scale with what the camera sees, not with geometry far outside the view; vertices beyond the
//! first bounce still merge with the same radius (only the per-pixel mode varies it).

use math::{Aabb, Vec2};
use rayon::prelude::*;
use scene::Scene;

use super::{RadiusMode, VcmSettings};

/// The pixel count up to which [`RadiusMode::Global`] uses the scene-relative radius unscaled
/// (512², the resolution of SmallVCM's scenes, on which the default radius factor was chosen).
pub const RADIUS_REFERENCE_PIXELS: u64 = 512 * 512;

/// The probe grid of the visible part: (G+1)² rays for G = 32 (see the module docs).
pub const VISIBLE_PROBES: u32 = 32;

/// The visible part's size and the merging scale of a scene (world units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergingScale {
    /// Radius of the scene's bounding sphere, R_scene.
    pub scene_radius: f32,
    /// Radius of the bounding sphere of the points the probe rays hit, R_vis (`None` when
    /// they hit nothing).
    pub visible_radius: Option<f32>,
    /// The length the radius factor multiplies (module docs).
    pub scale: f32,
}

impl MergingScale {
    /// The merging scale of `scene` (module docs).
    pub fn of(scene: &Scene) -> Self {
        let scene_radius = scene.bounding_sphere.radius;
        let visible_radius = visible_radius(scene);
        Self { scene_radius, visible_radius, scale: merging_scale(scene_radius, visible_radius) }
    }
}

/// The merging scale from R_scene and R_vis (module docs).
fn merging_scale(scene_radius: f32, visible_radius: Option<f32>) -> f32 {
    let Some(visible) = visible_radius.filter(|r| r.is_finite() && *r > 0.0) else { return scene_radius };
    let s = visible / scene_radius;
    if s >= 0.5 {
        scene_radius
    } else if s > 0.25 {
        4.0 * s * s * scene_radius
    } else {
        visible
    }
}

/// R_vis: the bounding-sphere radius of the box around the points the probe rays hit, or
/// `None` when none hits.
pub fn visible_radius(scene: &Scene) -> Option<f32> {
    let camera = &scene.camera;
    let (width, height) = (camera.width as f32, camera.height as f32);
    let grid = VISIBLE_PROBES as f32;
    let mut bounds = Aabb::EMPTY;
    for j in 0..=VISIBLE_PROBES {
        for i in 0..=VISIBLE_PROBES {
            let raster = Vec2::new(width * i as f32 / grid, height * j as f32 / grid);
            if let Some(hit) = scene.intersect(&camera.generate_ray(raster)) {
                bounds = bounds.grow(hit.position);
            }
        }
    }
    (!bounds.is_empty()).then(|| bounds.bounding_sphere().1)
}

/// The merging radius of the first iteration (world units) before the per-pixel footprints:
/// `radius_factor` × the merging scale ([`MergingScale`]), times √([`RADIUS_REFERENCE_PIXELS`] /
/// pixels) above the reference pixel count in [`RadiusMode::Global`]. (N_L light sub-paths, one
/// per pixel, over a disc of radius r: a query finds on average ∝ N_L r² light vertices, which
/// this scaling keeps constant.)
pub fn base_radius(scene: &Scene, settings: &VcmSettings) -> f32 {
    global_shrink(settings.radius_factor * MergingScale::of(scene).scale, scene, settings, f64::sqrt)
}

/// `radius` times `root`([`RADIUS_REFERENCE_PIXELS`] / pixels) above the reference pixel count
/// in [`RadiusMode::Global`] (√ for the disc, ∛ for the ball), else `radius` unchanged.
fn global_shrink(radius: f32, scene: &Scene, settings: &VcmSettings, root: fn(f64) -> f64) -> f32 {
    let pixels = scene.camera.pixel_count() as u64;
    if settings.radius_mode == RadiusMode::Global && pixels > RADIUS_REFERENCE_PIXELS {
        radius * root(RADIUS_REFERENCE_PIXELS as f64 / pixels as f64) as f32
    } else {
        radius
    }
}

/// The default volume radius factor ([`VcmSettings::volume_radius_factor`]): the merge ball at
/// medium vertices over the volume scale ([`base_volume_radius`]; docs/media.md, "The volume
/// radius", measured on `scenes/cornell-fog.xml` and Mitsuba's `participating_media` scenes).
pub const DEFAULT_VOLUME_RADIUS_FACTOR: f32 = 0.025;

/// The merging radius at medium vertices of the first iteration (world units):
/// `volume_radius_factor` × the *volume scale*, times ∛([`RADIUS_REFERENCE_PIXELS`] / pixels)
/// above the reference pixel count in [`RadiusMode::Global`] (a ball of radius r_V finds on
/// average ∝ N_L r_V³ light vertices in a medium, which this scaling keeps constant).
///
/// The volume scale is the merging scale ([`MergingScale`]), or the bounding-sphere radius of
/// the smallest bounded medium when that is smaller ([`smallest_medium_radius`]): the ball loses
/// the part of it that lies outside the medium, so its radius must be small against the medium
/// itself, not only against the view (a medium sphere of radius 0.8 in a scene seen over ±5
/// units came out 5 % dark with the view-relative radius, docs/media.md).
pub fn base_volume_radius(scene: &Scene, settings: &VcmSettings) -> f32 {
    let view = MergingScale::of(scene).scale;
    let scale = smallest_medium_radius(scene).map_or(view, |r| r.min(view));
    global_shrink(settings.volume_radius_factor * scale, scene, settings, f64::cbrt)
}

/// The bounding-sphere radius of the smallest bounded medium (world units): a medium is bounded
/// by the world primitives that name it as their *interior*, and its extent is the box around
/// them. A medium that no primitive names as its interior (the camera's medium, or one named
/// only outside objects) is unbounded and does not count; `None` when no medium is bounded.
pub fn smallest_medium_radius(scene: &Scene) -> Option<f32> {
    let media = &scene.media;
    let mut boxes = vec![Aabb::EMPTY; media.media.len()];
    for (primitive, interface) in scene.primitives.iter().zip(&media.interfaces) {
        if let Some(inside) = interface.and_then(|i| i.interior)
            && let Some(extent) = boxes.get_mut(inside as usize)
        {
            *extent = extent.union(primitive.shape.bounds());
        }
    }
    boxes
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| b.bounding_sphere().1)
        .filter(|r| r.is_finite() && *r > 0.0)
        .reduce(f32::min)
}

/// Per-pixel merging radii before the iteration schedule: the radius of a disc with the area
/// of the pixel's footprint at the first surface hit by the ray through its centre (and the
/// lens centre), [`scene::Camera::footprint_radius`]: `d·sqrt(cos³/π)/f` for perspective
/// cameras (d the distance, f the image-plane distance in pixels, cos at the camera),
/// `sqrt(A_pixel/π)` for the orthographic camera. Pixels that see nothing get `fallback`.
pub(super) fn pixel_footprints(scene: &Scene, fallback: f32) -> Vec<f32> {
    let camera = &scene.camera;
    let width = camera.width as usize;
    (0..camera.pixel_count())
        .into_par_iter()
        .map(|index| {
            let raster = Vec2::new((index % width) as f32 + 0.5, (index / width) as f32 + 0.5);
            let ray = camera.generate_ray(raster);
            match scene.intersect(&ray) {
                None => fallback,
                Some(hit) => camera.footprint_radius(&ray, hit.distance),
            }
        })
        .collect()
}

#[cfg(test)]
#[path = "radius_tests.rs"]
mod tests;
