//! Integrators and the progressive driver.
//!
//! * [`path_tracer`]: the reference path tracer (BSDF sampling + next-event estimation,
//!   combined by MIS), deliberately independent of the VCM engine.
//! * [`volumetric`]: the path tracer's walk through participating media and null boundaries.
//! * [`eye_light`]: a fast `|cos|` shading preview.
//! * [`vcm`]: the VCM engine (light tracing, PPM, BPM, BPT, VCM).
//! * [`fluorescent`]: wavelength shifts at fluorescent vertices, shared by all integrators.
//! * [`hash_grid`]: the range search for vertex merging.
//! * [`splat_frame`]: camera samples splatted over the pixels their filter reaches.
//! * [`distributed`]: one render over several ranks (MPI), bit-identical to one process.
//! * [`driver`]: the integrators behind one interface, threads, determinism; `render_with`.
//! * [`progressive`]: one iteration at a time into the film, and the budget loop with
//!   checkpoints and progress (every front end's loop).

pub mod distributed;
pub mod driver;
pub mod eye_light;
pub mod fluorescent;
pub mod hash_grid;
mod null_walk;
pub mod parallelism;
pub mod path_tracer;
pub mod primary_samples;
pub(crate) use math::prefetch;
pub mod progressive;
pub mod splat_frame;
pub mod vcm;
pub mod volumetric;
pub mod wavelength_sequence;

pub use driver::{Algorithm, RenderOutput, RenderSettings, render};
pub use parallelism::{Parallelism, worker_threads};

/// The balance heuristic weight of a sample drawn with density `own` when another technique
/// would have drawn it with density `other` (both in the same measure).
#[inline]
pub fn balance_heuristic(own: f32, other: f32) -> f32 {
    if own + other > 0.0 { own / (own + other) } else { 0.0 }
}

/// The power heuristic (exponent 2) weight of a sample drawn with density `own` when another
/// technique would have drawn it with density `other` (both in the same measure).
#[inline]
pub fn power_heuristic(own: f32, other: f32) -> f32 {
    let (a, b) = (own * own, other * other);
    if a + b > 0.0 && a.is_finite() { a / (a + b) } else { balance_heuristic(own, other) }
}
