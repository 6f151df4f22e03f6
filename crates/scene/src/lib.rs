//! Everything a scene is made of: shapes and their intersection, the BVH, materials and the
//! per-hit BSDF, lights, the camera, the film and the built-in reference scenes.
//!
//! This crate does not know about integrators or file formats.

pub mod accel;
pub mod alpha;
pub mod build;
pub mod camera;
pub mod cornell;
pub mod desc;
pub mod film;
pub mod filter;
pub mod instance;
pub mod light;
pub mod light_selection;
pub mod light_tree;
pub mod light_tree_bounds;
pub mod material;
pub mod medium;
pub mod microfacet;
pub mod scene;
pub mod shape;
pub mod tangent;
pub mod texture;

pub use alpha::AlphaMask;
pub use camera::Camera;
pub use film::{Film, FilmSums, FrameBuffer, Summation};
pub use filter::Filter;
pub use light::{BoundingSphere, DirectSample, EmissionSample, HitRadiance, Light};
pub use material::{
    Bsdf, BsdfEval, BsdfSample, LobeKind, Material, MaterialFlags, PdfPair, ReferenceMaterial, ShadingPoint,
    TransportMode,
};
pub use scene::{LightSpectrum, Primitive, Scene, SurfaceHit};
pub use texture::{FilterMode, Sampling, Texture, TexturePoint, WrapMode};
