//! The walk of a straight segment through the surfaces light passes without a vertex: index-
//! matched (null) boundaries and, in scenes with media, thin dielectrics (their straight-through
//! transmission, [`crate::volumetric::null_factor`]). Shadow rays of the volumetric path tracer
//! ([`crate::volumetric::tracked_transmittance`]) and the VCM engine's connection segments
//! (`crate::vcm::medium::segment`) both walk with it, so they cross the same surfaces and switch
//! media the same way; each evaluates its own pieces.

use math::{RAY_EPSILON, Ray, Vec3};
use scene::Scene;
use spectrum::SpectralMode;

use crate::volumetric::null_factor;

/// One piece of a segment between the surfaces it crosses, lying in one medium (or vacuum).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Piece {
    /// The medium of the piece (`None` = vacuum).
    pub medium: Option<u32>,
    /// Distance of the piece's start from the segment's start (scene units).
    pub start: f32,
    /// Distance of the piece's end from the segment's start (scene units).
    pub end: f32,
    /// The piece starts at the segment's start.
    pub first: bool,
    /// The piece ends at the segment's end.
    pub last: bool,
}

/// Walks the segment from `point` along unit `direction` over `distance` (may be infinite),
/// starting in `medium`: calls `piece` for each piece in order, switching media at the
/// interfaces it crosses, and returns the product of the crossing factors of its surfaces (1
/// for a null boundary, `T·(1 − R')` for a thin dielectric). `None` when any other surface
/// blocks it (over the open interval `(ε, distance − ε)`, as [`Scene::occluded`]) or a factor
/// is black.
pub(crate) fn walk<S: SpectralMode>(
    scene: &Scene,
    point: Vec3,
    direction: Vec3,
    distance: f32,
    medium: Option<u32>,
    w: &S::Wavelengths,
    mut piece: impl FnMut(&Piece),
) -> Option<S> {
    let media = &scene.media;
    let mut medium = medium;
    let mut carried = S::splat(1.0);
    // Distances from `point`: of the last surface crossed and of the current ray origin.
    let (mut crossed, mut offset, mut first) = (0.0f32, RAY_EPSILON, true);
    loop {
        let remaining = distance - offset - RAY_EPSILON;
        let ray = Ray::new(point + offset * direction, direction);
        let hit = if remaining > 0.0 { scene.intersect(&ray).filter(|h| h.distance < remaining) } else { None };
        let end = hit.as_ref().map_or(distance, |h| offset + h.distance);
        piece(&Piece { medium, start: crossed, end, first, last: hit.is_none() });
        first = false;
        let Some(hit) = hit else { break };
        if !media.is_null(hit.material) {
            carried *= null_factor::<S>(scene, &hit, direction, w)?;
        }
        if let Some(i) = media.interface(hit.primitive) {
            medium = i.medium_towards(direction, hit.normal);
        }
        crossed = end;
        offset = end + RAY_EPSILON;
    }
    (!carried.is_black()).then_some(carried)
}
