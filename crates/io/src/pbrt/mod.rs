//! pbrt-v4 scene loader: our own tokenizer and parser (the `pbrt4` crate is unusable, see
//! `DEPENDENCIES.md`) and the conversion to a [`SceneDescription`].
//!
//! # Conventions and conversions
//!
//! - **Coordinates.** pbrt's numbers are used as they are; its "left-handed" system only
//!   changes how a picture is drawn, not a formula. The camera looks along its +z with +y up
//!   and +x to the right of the image. The transformation at `Camera` is camera-from-world;
//!   the [`CameraDesc`] gets the world-space images of the camera's origin and axes (so a
//!   `LookAt` without `Scale -1 1 1` gives the mirror image of the same `lookat` in Mitsuba,
//!   exactly as in the two renderers).
//! - **Field of view.** pbrt's `fov` spans the shorter image axis; we convert it to the
//!   horizontal field of view for the film's aspect ratio (square pixels).
//! - **Path length.** pbrt's `maxdepth` counts bounces (0 = only emitters seen directly), so the
//!   path length in segments is `maxdepth + 1`. Without an `Integrator` directive pbrt's default
//!   `maxdepth` 5 applies (6 segments).
//! - **Filters.** `box` (radius 0.5 only), `triangle` → [`FilterDesc::Tent`], `gaussian`
//!   (`sigma`, `xradius` = `yradius`) → [`FilterDesc::Gaussian`]: pbrt evaluates
//!   `max(0, g(x) − g(radius))` with the Gaussian of standard deviation `sigma`, the same
//!   shifted, truncated Gaussian as ours and Mitsuba's, so the mapping is exact. pbrt's default
//!   is `sigma` 0.5, radius 1.5.
//! - **Orientation.** A triangle's front side follows pbrt: the side of `(p1 − p0) × (p2 − p0)`
//!   in world space, flipped when `ReverseOrientation` is active XOR the transformation swaps
//!   handedness; a mesh with normals `N` instead faces each triangle towards its vertex normals.
//!   We wind the triangles so that our right-hand-rule normal is pbrt's. Spheres and discs face
//!   outward / along +z, flipped by `ReverseOrientation` only.
//! - **Two-sided materials.** pbrt's diffuse and conductor materials reflect on both sides;
//!   ours are one-sided, so they are wrapped in [`Material::TwoSided`]. Dielectrics are
//!   naturally two-sided.
//! - **Emission.** Area lights are one-sided (pbrt's default); `"bool twosided" true` is an
//!   error. Light spectra are normalised to luminance 1 as pbrt-v4 does (see [`color`]); `rgb`
//!   values are used as given.
//! - **Roughness.** With `remaproughness` true (the default) α = √roughness (pbrt-v4's
//!   `RoughnessToAlpha`), else α = roughness. Below α = 10⁻³ on both axes the surface is smooth,
//!   as in pbrt.
//! - **Normal and bump maps.** A material's `string normalmap` becomes
//!   [`Material::NormalMap`] (the image read linear, looked up at (u, 1 − v)) and its
//!   `texture displacement` a [`Material::BumpMap`] with scale 1 (the exact gradient instead of
//!   pbrt's finite difference; pbrt's `displacement · ∂n/∂u` term is omitted). Both at once is
//!   an error.
//! - **Mix.** pbrt's `mix` picks `materials[1]` with probability `amount`; the expectation is our
//!   [`Material::Blend`] with weight `amount`.
//! - **Image environment maps** are resampled from pbrt's equal-area octahedral square to
//!   lat-long (see [`envmap`]).
//! - **File names** (`Include`, `Import`, meshes, images) are relative to the directory of the
//!   file that names them. `Import` is treated as `Include`. Gzip-compressed scene and PLY
//!   files (`.pbrt.gz`, `.ply.gz`; recognised by their content) are decompressed.
//! - **Media**: homogeneous media, `MediumInterface` and the `interface` material (see
//!   `medium.rs`); grid media are errors.
//! - **Unsupported** features are errors naming them (grid media, textures other
//!   than `imagemap`/`checkerboard`/`constant`/`scale`/`mix`, `measured`, `subsurface`, …);
//!   the layered `coateddiffuse` and `coatedconductor` are in `coated.rs`; `hair` is here and
//!   `curve` shapes (tessellated into tubes) in `curve.rs`;
//!   unsupported optional parameters are warnings in [`SceneDescription::warnings`].

mod alpha;
mod coated;
pub mod color;
mod curve;
pub mod envmap;
mod goniometric;
mod grid_medium;
mod instancing;
mod medium;
mod nanovdb_medium;
mod parser;
pub mod tokenizer;
mod transform;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use math::{Vec2, Vec3};
use scene::desc::{
    CameraDesc, EmissionSpectra, EmissionSpectrum, FilmDesc, FilterDesc, Geometry, LightDesc, MeshData, Projection,
    SceneDescription, ShapeDesc, TextureImage, UvTransform,
};
use scene::material::{HairParameters, Material};
use scene::microfacet::Distribution;
use scene::texture::{FilterMode, Sampling, Texture, WrapMode};
use spectrum::Rgb;
use spectrum::tabulated::Tabulated;

use crate::options::{LoadOptions, LoadedScene, RenderSettings};
use crate::pbrt::parser::{Directive, ParamSet, Parser, Value};
use crate::pbrt::tokenizer::Pos;
use crate::pbrt::transform::{Mat4, V3, dot, norm, normalize};
use crate::scene_error::SceneError;

/// How deep `Include`s may nest (guards against include cycles).
const MAX_INCLUDE_DEPTH: usize = 32;

/// Below this GGX α on both axes a surface counts as smooth (pbrt-v4's `EffectivelySmooth`).
const SMOOTH_ALPHA: f32 = 1e-3;

/// Loads a pbrt-v4 scene (strict: see [`load_with`]).
///
/// Errors name the file, line and column and what was expected: unknown directives, shape,
/// material, light and texture types, unsupported features, parameters of the wrong type or
/// count, unbalanced `AttributeBegin`/`AttributeEnd`, missing files and malformed numbers.
pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    load_with(path, &LoadOptions::default()).map(|loaded| loaded.description)
}

/// Loads a pbrt-v4 scene with `options` and returns the file's `Sampler` `pixelsamples` too.
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let mut builder = Builder::new(options.permissive);
    builder.run_file(path, None, 0)?;
    let settings = builder.settings;
    Ok(LoadedScene { description: builder.finish(path)?, settings })
}

/// The state that `AttributeBegin` saves.
#[derive(Clone, Debug)]
struct GraphicsState {
    ctm: Mat4,
    reverse_orientation: bool,
    /// Index into the materials; `None` = pbrt's default (diffuse 0.5).
    material: Option<u32>,
    /// Radiance of the current area light.
    area_light: Option<Rgb>,
    /// Its spectrum, when given spectrally.
    area_light_spectrum: Option<EmissionSpectrum>,
    /// Its radiance image (`filename`, scale applied), for triangle meshes.
    area_light_texture: Option<Arc<Texture>>,
    /// The current `MediumInterface` (see `medium.rs`).
    medium_interface: scene::medium::MediumInterface,
}

/// What a `*Begin` pushed.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Block {
    Attribute,
    Transform,
}

/// The camera directive, resolved when the film is known.
#[derive(Clone, Debug)]
struct CameraSpec {
    world_from_camera: Mat4,
    orthographic: bool,
    fov_degrees: f32,
    lens_radius: f32,
    focal_distance: f32,
    file: PathBuf,
    pos: Pos,
}

/// A named texture.
#[derive(Clone, Debug)]
struct NamedTexture {
    texture: Texture,
}

struct Builder {
    world: bool,
    state: GraphicsState,
    stack: Vec<(GraphicsState, Block, PathBuf, Pos)>,
    named_coordinate_systems: HashMap<String, Mat4>,
    named_materials: HashMap<String, (Material, Option<u32>)>,
    textures: HashMap<String, NamedTexture>,
    camera: Option<CameraSpec>,
    resolution: (u32, u32),
    filter: FilterDesc,
    max_path_length: Option<u32>,
    materials: Vec<Material>,
    default_material: Option<u32>,
    shapes: Vec<ShapeDesc>,
    /// Object definitions and instances (`ObjectBegin`, `ObjectInstance`; see `instancing.rs`).
    objects: Vec<scene::desc::ObjectDesc>,
    instances: Vec<scene::desc::InstanceDesc>,
    object_of_name: HashMap<String, u32>,
    /// The object being defined: its name, the file and position where it began, and the
    /// world's shapes meanwhile.
    defining: Option<(String, PathBuf, Pos, Vec<ShapeDesc>)>,
    lights: Vec<LightDesc>,
    emission_spectra: EmissionSpectra,
    warnings: Vec<String>,
    /// The `Sampler`'s sample count.
    settings: RenderSettings,
    /// Unsupported image-changing parameters are warnings instead of errors.
    permissive: bool,
    /// Named media, the current `MediumInterface`, interfaces and `interface` materials (see
    /// `medium.rs`).
    media: medium::PbrtMedia,
}

fn f32v(a: V3) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

fn err(file: &Path, pos: Pos, message: impl Into<String>) -> SceneError {
    SceneError::at(file, pos.line, pos.column, message)
}

impl Builder {
    fn new(permissive: bool) -> Self {
        Self {
            world: false,
            state: GraphicsState {
                ctm: Mat4::IDENTITY,
                reverse_orientation: false,
                material: None,
                area_light: None,
                area_light_spectrum: None,
                area_light_texture: None,
                medium_interface: Default::default(),
            },
            stack: Vec::new(),
            named_coordinate_systems: HashMap::new(),
            named_materials: HashMap::new(),
            textures: HashMap::new(),
            camera: None,
            resolution: (1280, 720),
            filter: FilterDesc::Gaussian { stddev: 0.5, radius: 1.5 },
            // pbrt's default integrator has maxdepth 5.
            max_path_length: Some(6),
            materials: Vec::new(),
            default_material: None,
            shapes: Vec::new(),
            objects: Vec::new(),
            instances: Vec::new(),
            object_of_name: HashMap::new(),
            defining: None,
            lights: Vec::new(),
            emission_spectra: EmissionSpectra::default(),
            warnings: Vec::new(),
            settings: RenderSettings::default(),
            permissive,
            media: medium::PbrtMedia::default(),
        }
    }

    /// Something in the file the renderer cannot reproduce: an error, or a warning saying what
    /// is done `instead` when the load is permissive.
    fn unsupported(&mut self, error: SceneError, instead: &str) -> Result<(), SceneError> {
        crate::options::unsupported(self.permissive, &mut self.warnings, error, instead)
    }

    fn warn(&mut self, file: &Path, pos: Pos, message: impl AsRef<str>) {
        self.warnings.push(format!("{}:{}:{}: {}", file.display(), pos.line, pos.column, message.as_ref()));
    }

    fn warn_unused(&mut self, params: &ParamSet) {
        let unused = params.unused();
        self.warnings.extend(unused);
    }

    /// Parses and runs one file; `from` is the including directive for messages.
    fn run_file(&mut self, path: &Path, from: Option<(&Path, Pos)>, depth: usize) -> Result<(), SceneError> {
        crate::trace::opened(path);
        let text = crate::gz::read_maybe_gzip(path).map_err(|e| match from {
            Some((file, pos)) => err(file, pos, format!("'{}': {e}", path.display())),
            None => SceneError::in_file(path, e),
        })?;
        let text = String::from_utf8(text).map_err(|_| SceneError::in_file(path, "not a UTF-8 text file"))?;
        let tokens = tokenizer::tokenize(path, &text)?;
        let mut parser = Parser::new(path, tokens);
        while let Some(directive) = parser.next_directive()? {
            self.directive(path, directive, depth)?;
        }
        if depth == 0 {
            self.check_objects_closed()?;
        }
        if depth == 0
            && let Some((_, block, file, pos)) = self.stack.last()
        {
            let name = if *block == Block::Attribute { "AttributeBegin" } else { "TransformBegin" };
            return Err(err(file, *pos, format!("{name} is never closed (missing {}End)", &name[..name.len() - 5])));
        }
        Ok(())
    }

    fn require_world(&self, file: &Path, d: &Directive, inside: bool) -> Result<(), SceneError> {
        if inside && !self.world {
            return Err(err(file, d.pos, format!("{} is only allowed after WorldBegin", d.name)));
        }
        if !inside && self.world {
            return Err(err(file, d.pos, format!("{} is only allowed before WorldBegin", d.name)));
        }
        Ok(())
    }

    fn concat(&mut self, file: &Path, d: &Directive, m: Option<Mat4>) -> Result<(), SceneError> {
        let m = m
            .filter(Mat4::is_finite)
            .ok_or_else(|| err(file, d.pos, format!("{}: degenerate transformation", d.name)))?;
        self.state.ctm = self.state.ctm.mul(&m);
        Ok(())
    }

    fn directive(&mut self, file: &Path, d: Directive, depth: usize) -> Result<(), SceneError> {
        let n = d.num_args();
        match d.name.as_str() {
            "Identity" => self.state.ctm = Mat4::IDENTITY,
            "Translate" => self.concat(file, &d, Some(Mat4::translate([n[0], n[1], n[2]])))?,
            "Scale" => self.concat(file, &d, Some(Mat4::scale([n[0], n[1], n[2]])))?,
            "Rotate" => self.concat(file, &d, Mat4::rotate(n[0], [n[1], n[2], n[3]]))?,
            "LookAt" => {
                self.concat(file, &d, Mat4::look_at([n[0], n[1], n[2]], [n[3], n[4], n[5]], [n[6], n[7], n[8]]))?
            }
            "ConcatTransform" => self.concat(file, &d, Some(Mat4::from_pbrt_list(&n)))?,
            "Transform" => {
                let m = Mat4::from_pbrt_list(&n);
                if !m.is_finite() {
                    return Err(err(file, d.pos, "Transform: non-finite matrix"));
                }
                self.state.ctm = m;
            }
            "CoordinateSystem" => {
                self.named_coordinate_systems.insert(d.str_arg(0).to_string(), self.state.ctm);
            }
            "CoordSysTransform" => {
                let name = d.str_arg(0);
                match self.named_coordinate_systems.get(name) {
                    Some(m) => self.state.ctm = *m,
                    None => return Err(err(file, d.arg_pos[0], format!("unknown coordinate system \"{name}\""))),
                }
            }
            "ReverseOrientation" => self.state.reverse_orientation = !self.state.reverse_orientation,
            "TransformTimes" => self.warn(file, d.pos, "TransformTimes ignored (no motion blur)"),
            "ActiveTransform" => {
                if d.str_arg(0) != "All" {
                    return Err(err(
                        file,
                        d.arg_pos[0],
                        format!(
                            "ActiveTransform {}: animated transformations (motion blur) are not supported",
                            d.str_arg(0)
                        ),
                    ));
                }
            }
            "AttributeBegin" | "TransformBegin" => {
                let block = if d.name == "AttributeBegin" { Block::Attribute } else { Block::Transform };
                self.stack.push((self.state.clone(), block, file.to_path_buf(), d.pos));
            }
            "AttributeEnd" | "TransformEnd" => {
                let block = if d.name == "AttributeEnd" { Block::Attribute } else { Block::Transform };
                let begin = if block == Block::Attribute { "AttributeBegin" } else { "TransformBegin" };
                match self.stack.pop() {
                    None => return Err(err(file, d.pos, format!("{} without a matching {begin}", d.name))),
                    Some((_, b, f, p)) if b != block => {
                        return Err(err(
                            file,
                            d.pos,
                            format!("{} closes the block opened at {}:{}:{}", d.name, f.display(), p.line, p.column),
                        ));
                    }
                    Some((saved, Block::Attribute, ..)) => self.state = saved,
                    Some((saved, Block::Transform, ..)) => self.state.ctm = saved.ctm,
                }
            }
            "Attribute" => {
                if let Some(p) = d.params.params.first() {
                    return Err(d.params.error(p.pos, "default parameters set with Attribute are not supported"));
                }
            }
            "Option" => {
                let names: Vec<String> = d.params.params.iter().map(|p| p.name.clone()).collect();
                self.warn(file, d.pos, format!("Option {} ignored", names.join(", ")));
            }
            "ColorSpace" => {
                if d.str_arg(0) != "srgb" {
                    return Err(err(
                        file,
                        d.arg_pos[0],
                        format!("color space \"{}\" is not supported (only srgb)", d.str_arg(0)),
                    ));
                }
            }
            "Camera" => {
                self.require_world(file, &d, false)?;
                self.camera_directive(file, &d)?;
                self.media.set_camera(self.state.medium_interface);
            }
            "Film" => {
                self.require_world(file, &d, false)?;
                self.film_directive(&d)?;
            }
            "PixelFilter" => {
                self.require_world(file, &d, false)?;
                self.filter_directive(&d)?;
            }
            "Integrator" => {
                self.require_world(file, &d, false)?;
                let depth = d.params.int("maxdepth", 5)?;
                if depth < 0 {
                    let pos = d.params.find("maxdepth").map_or(d.pos, |p| p.pos);
                    return Err(d.params.error(pos, format!("maxdepth {depth} is negative")));
                }
                self.max_path_length = Some(u32::try_from(depth + 1).unwrap_or(u32::MAX));
                // Integrators that estimate something else than the light transport.
                if let ty @ ("ambientocclusion" | "aov") = d.str_arg(0) {
                    let pos = d.arg_pos[0];
                    self.unsupported(
                        err(file, pos, format!("Integrator \"{ty}\" is not supported")),
                        "rendered with its maxdepth by the chosen algorithm",
                    )?;
                }
                if d.params.bool("regularize", false)? {
                    let pos = d.params.find("regularize").map_or(d.pos, |p| p.pos);
                    self.unsupported(d.params.error(pos, "\"regularize\" true is not supported"), "no regularisation")?;
                }
                self.warn_unused(&d.params);
            }
            "Sampler" => {
                self.require_world(file, &d, false)?;
                // pbrt-v4's default is 16 samples per pixel. The sampler type and its other
                // parameters change the noise, not the expected image.
                let count = d.params.int("pixelsamples", 16)?;
                let count = u32::try_from(count).ok().filter(|&c| c > 0).ok_or_else(|| {
                    let pos = d.params.find("pixelsamples").map_or(d.pos, |p| p.pos);
                    d.params.error(pos, format!("pixelsamples {count} must be ≥ 1"))
                })?;
                self.settings.samples_per_pixel = Some(count);
            }
            "Accelerator" => self.require_world(file, &d, false)?,
            "WorldBegin" => {
                self.require_world(file, &d, false)?;
                self.world = true;
                self.state.ctm = Mat4::IDENTITY;
                self.named_coordinate_systems.insert("world".into(), Mat4::IDENTITY);
            }
            "WorldEnd" => self.warn(file, d.pos, "WorldEnd (pbrt-v3) ignored"),
            "Include" | "Import" => {
                if depth + 1 >= MAX_INCLUDE_DEPTH {
                    return Err(err(
                        file,
                        d.pos,
                        format!("{}s nested deeper than {MAX_INCLUDE_DEPTH} (a cycle?)", d.name),
                    ));
                }
                let target = resolve(file, d.str_arg(0));
                self.run_file(&target, Some((file, d.arg_pos[0])), depth + 1)?;
            }
            "ObjectBegin" => self.object_begin(file, &d)?,
            "ObjectEnd" => self.object_end(file, &d)?,
            "ObjectInstance" => self.object_instance(file, &d)?,
            "MakeNamedMedium" => self.make_named_medium(file, &d)?,
            "MediumInterface" => self.state.medium_interface = self.medium_interface(file, &d)?,
            "Material" => {
                self.require_world(file, &d, true)?;
                let material = self.material(file, &d, d.str_arg(0))?;
                self.warn_unused(&d.params);
                self.materials.push(material);
                self.state.material = Some(self.materials.len() as u32 - 1);
                if d.str_arg(0) == "interface" {
                    self.media.mark_interface(self.materials.len() as u32 - 1);
                }
            }
            "MakeNamedMaterial" => {
                self.require_world(file, &d, true)?;
                let name = d.str_arg(0).to_string();
                if self.named_materials.contains_key(&name) {
                    return Err(err(file, d.arg_pos[0], format!("named material \"{name}\" defined twice")));
                }
                let Some((ty, _)) = d.params.string("type")? else {
                    return Err(err(file, d.pos, format!("MakeNamedMaterial \"{name}\" needs a \"string type\"")));
                };
                let material = self.material(file, &d, &ty)?;
                self.warn_unused(&d.params);
                if ty == "interface" {
                    self.media.name_interface(&name);
                }
                self.named_materials.insert(name, (material, None));
            }
            "NamedMaterial" => {
                self.require_world(file, &d, true)?;
                let name = d.str_arg(0);
                let Some((material, index)) = self.named_materials.get_mut(name) else {
                    return Err(err(file, d.arg_pos[0], format!("unknown named material \"{name}\"")));
                };
                let index = match index {
                    Some(i) => *i,
                    None => {
                        self.materials.push(material.clone());
                        let i = self.materials.len() as u32 - 1;
                        *index = Some(i);
                        i
                    }
                };
                self.state.material = Some(index);
                if self.media.is_interface_name(name) {
                    self.media.mark_interface(index);
                }
            }
            "Texture" => {
                self.require_world(file, &d, true)?;
                self.texture_directive(file, &d)?;
            }
            "Shape" => {
                self.require_world(file, &d, true)?;
                self.shape_directive(file, &d)?;
            }
            "AreaLightSource" => {
                self.require_world(file, &d, true)?;
                self.area_light_directive(file, &d)?;
            }
            "LightSource" => {
                self.require_world(file, &d, true)?;
                self.light_directive(file, &d)?;
            }
            other => return Err(err(file, d.pos, format!("directive '{other}' is not supported"))),
        }
        Ok(())
    }

    fn finish(self, path: &Path) -> Result<SceneDescription, SceneError> {
        let (width, height) = self.resolution;
        let spec = self.camera.clone().unwrap_or(CameraSpec {
            world_from_camera: Mat4::IDENTITY,
            orthographic: false,
            fov_degrees: 90.0,
            lens_radius: 0.0,
            focal_distance: 1e6,
            file: path.to_path_buf(),
            pos: Pos { line: 1, column: 1 },
        });
        let camera = camera_desc(&spec, width, height)?;
        Ok(SceneDescription {
            name: path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned()),
            camera,
            film: FilmDesc { width, height, filter: self.filter },
            materials: self.materials,
            shapes: self.shapes,
            lights: self.lights,
            max_path_length: self.max_path_length,
            warnings: self.warnings,
            emission_spectra: self.emission_spectra,
            objects: self.objects,
            instances: self.instances,
            media: self.media.finish(),
        })
    }

    // ----- camera, film, filter -------------------------------------------------------------

    fn camera_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        let orthographic = match ty {
            "perspective" => false,
            "orthographic" => true,
            "realistic" | "spherical" => {
                return Err(err(file, d.arg_pos[0], format!("camera type \"{ty}\" is not supported")));
            }
            _ => return Err(err(file, d.arg_pos[0], format!("unknown camera type \"{ty}\""))),
        };
        let p = &d.params;
        let fov_degrees = if orthographic { 90.0 } else { p.float("fov", 90.0)? };
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            let pos = p.find("fov").map_or(d.pos, |x| x.pos);
            return Err(p.error(pos, format!("fov {fov_degrees} is outside (0, 180) degrees")));
        }
        let lens_radius = p.float("lensradius", 0.0)?;
        let focal_distance = p.float("focaldistance", 1e6)?;
        for name in ["screenwindow", "frameaspectratio"] {
            if let Some(x) = p.find(name) {
                return Err(p.error(x.pos, format!("parameter '{name}' is not supported")));
            }
        }
        let world_from_camera =
            self.state.ctm.inverse().ok_or_else(|| err(file, d.pos, "the camera transformation is singular"))?;
        self.named_coordinate_systems.insert("camera".into(), world_from_camera);
        self.camera = Some(CameraSpec {
            world_from_camera,
            orthographic,
            fov_degrees,
            lens_radius,
            focal_distance,
            file: file.to_path_buf(),
            pos: d.pos,
        });
        self.warn_unused(&d.params);
        Ok(())
    }

    fn film_directive(&mut self, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        if !matches!(ty, "rgb" | "gbuffer" | "spectral") {
            return Err(err(
                &d.params.file,
                d.arg_pos[0],
                format!("unknown film type \"{ty}\" (expected rgb or gbuffer)"),
            ));
        }
        let p = &d.params;
        let mut res = [0u32; 2];
        for (k, (name, default)) in [("xresolution", 1280), ("yresolution", 720)].into_iter().enumerate() {
            let v = p.int(name, default)?;
            if !(1..=1 << 16).contains(&v) {
                let pos = p.find(name).map_or(d.pos, |x| x.pos);
                return Err(p.error(pos, format!("{name} {v} is outside 1..=65536")));
            }
            res[k] = v as u32;
        }
        self.resolution = (res[0], res[1]);
        // The output file name is the command line's business.
        let _ = p.find("filename");
        self.warn_unused(p);
        Ok(())
    }

    fn filter_directive(&mut self, d: &Directive) -> Result<(), SceneError> {
        let p = &d.params;
        let radius = |default: f32| -> Result<f32, SceneError> {
            let x = p.float("xradius", default)?;
            let y = p.float("yradius", default)?;
            if x != y {
                let pos = p.find("yradius").map_or(d.pos, |q| q.pos);
                return Err(p.error(pos, format!("different xradius ({x}) and yradius ({y}) are not supported")));
            }
            if !(x > 0.0 && x.is_finite()) {
                return Err(p.error(d.pos, format!("filter radius {x} must be positive")));
            }
            Ok(x)
        };
        self.filter = match d.str_arg(0) {
            "box" => {
                let r = radius(0.5)?;
                if r != 0.5 {
                    return Err(p.error(d.pos, format!("box filter radius {r}: only 0.5 is supported")));
                }
                FilterDesc::Box
            }
            "triangle" => FilterDesc::Tent { radius: radius(2.0)? },
            "gaussian" => {
                let stddev = p.float("sigma", 0.5)?;
                if !(stddev > 0.0 && stddev.is_finite()) {
                    return Err(p.error(d.pos, format!("sigma {stddev} must be positive")));
                }
                FilterDesc::Gaussian { stddev, radius: radius(1.5)? }
            }
            ty @ ("mitchell" | "sinc") => {
                return Err(err(&p.file, d.arg_pos[0], format!("pixel filter \"{ty}\" is not supported")));
            }
            ty => return Err(err(&p.file, d.arg_pos[0], format!("unknown pixel filter \"{ty}\""))),
        };
        self.warn_unused(p);
        Ok(())
    }

    // ----- parameters: spectra and textures -------------------------------------------------

    /// A spectrum-valued parameter of a material or texture (`rgb`, `spectrum`, `float`,
    /// `texture`). `albedo` restricts values to [0, 1] and rejects named spectra.
    fn spectrum_texture(&self, p: &ParamSet, name: &str, default: Rgb, albedo: bool) -> Result<Texture, SceneError> {
        let Some(param) = p.find(name) else { return Ok(Texture::Constant(default)) };
        let pos = param.pos;
        let value = match param.ty.as_str() {
            "rgb" => {
                let v = param.numbers();
                if v.len() != 3 {
                    return Err(p.error(pos, format!("parameter '{name}' needs 3 values, got {}", v.len())));
                }
                Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)
            }
            "float" => match param.numbers()[..] {
                [x] => Rgb::splat(x as f32),
                _ => return Err(p.error(pos, format!("parameter '{name}' needs one value"))),
            },
            "spectrum" => match &param.values[..] {
                [Value::Str(s)] => {
                    if albedo {
                        return Err(p.error(pos, format!("named spectrum \"{s}\" cannot be a reflectance")));
                    }
                    color::named_metal(s)
                        .ok_or_else(|| p.error(pos, format!("unknown or unsupported named spectrum \"{s}\"")))?
                }
                [Value::Num(x)] => Rgb::splat(*x as f32),
                _ => {
                    let v = param.numbers();
                    if albedo {
                        return Err(p.error(
                            pos,
                            format!("parameter '{name}': sampled reflectance spectra are not supported (use rgb)"),
                        ));
                    }
                    let s = color::piecewise_linear(&v).filter(|_| v.len() % 2 == 0).ok_or_else(|| {
                        p.error(
                            pos,
                            format!("parameter '{name}': expected wavelength/value pairs with increasing wavelengths"),
                        )
                    })?;
                    let [r, g, b] = color::PRIMARY_WAVELENGTHS.map(|l| s(l) as f32);
                    Rgb::new(r, g, b)
                }
            },
            "texture" => {
                let [Value::Str(t)] = &param.values[..] else {
                    return Err(p.error(pos, format!("parameter '{name}' needs one texture name")));
                };
                return match self.textures.get(t) {
                    Some(tex) => Ok(tex.texture.clone()),
                    None => Err(p.error(pos, format!("unknown texture \"{t}\""))),
                };
            }
            other => {
                return Err(p.error(
                    pos,
                    format!("parameter '{name}' has type '{other}', expected rgb, spectrum, float or texture"),
                ));
            }
        };
        if !value.is_finite() || (albedo && (value.r.min(value.g).min(value.b) < 0.0 || value.max_component() > 1.0)) {
            return Err(p.error(pos, format!("{name} = ({}, {}, {}) is outside [0, 1]", value.r, value.g, value.b)));
        }
        Ok(Texture::Constant(value))
    }

    /// A float parameter that pbrt allows to be a texture; we need a constant.
    fn constant_float(&self, p: &ParamSet, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(param) = p.find(name) else { return Ok(default) };
        match param.ty.as_str() {
            "float" => p.float(name, default),
            "texture" => {
                let [Value::Str(t)] = &param.values[..] else {
                    return Err(p.error(param.pos, format!("parameter '{name}' needs one texture name")));
                };
                match self.textures.get(t).map(|x| &x.texture) {
                    Some(Texture::Constant(c)) => Ok(c.r),
                    Some(_) => {
                        Err(p
                            .error(param.pos, format!("parameter '{name}': only constant textures are supported here")))
                    }
                    None => Err(p.error(param.pos, format!("unknown texture \"{t}\""))),
                }
            }
            other => {
                Err(p.error(param.pos, format!("parameter '{name}' has type '{other}', expected float or texture")))
            }
        }
    }

    /// A light's spectrum as RGB radiance/intensity before `scale` (see [`color`]) and, for
    /// blackbody, sampled and constant spectra, the spectrum itself, normalised like the RGB
    /// value to luminance `Y = ∫ s ȳ dλ / ∫ ȳ dλ = 1` (pbrt-v4's photometric normalisation; its
    /// blackbody is normalised to peak 1 first, which this cancels).
    fn light_emission(&self, p: &ParamSet, name: &str) -> Result<(Rgb, Option<EmissionSpectrum>), SceneError> {
        let Some(param) = p.find(name) else { return Ok((Rgb::WHITE, None)) };
        let pos = param.pos;
        let nums = param.numbers();
        let normalised = |s: &dyn Fn(f64) -> f64| {
            color::emission_rgb(s).ok_or_else(|| p.error(pos, format!("parameter '{name}': spectrum has no luminance")))
        };
        // The spectrum scaled to Y = 1 (None when it has no luminance: the RGB path reports it).
        let unit = |s: EmissionSpectrum| -> Result<Option<EmissionSpectrum>, SceneError> {
            let y = s.xyz()[1];
            if !(y > 0.0 && y.is_finite()) {
                return Ok(None);
            }
            let s = s.scaled((1.0 / y) as f32).map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
            s.validate().map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
            Ok(Some(s))
        };
        let flat = || -> Result<Option<EmissionSpectrum>, SceneError> {
            let t = Tabulated::new(&[(360.0, 1.0), (830.0, 1.0)]).map_err(|e| p.error(pos, e))?;
            unit(EmissionSpectrum::Tabulated(Arc::new(t)))
        };
        let mut spectrum = None;
        let rgb = match param.ty.as_str() {
            "rgb" => match nums[..] {
                [r, g, b] => Rgb::new(r as f32, g as f32, b as f32),
                _ => return Err(p.error(pos, format!("parameter '{name}' needs 3 values, got {}", nums.len()))),
            },
            "blackbody" => match nums[..] {
                [t] if t > 0.0 => {
                    spectrum = unit(EmissionSpectrum::Blackbody { kelvin: t as f32, scale: 1.0 })?;
                    normalised(&|l| color::planck(l, t))?
                }
                _ => return Err(p.error(pos, format!("parameter '{name}' needs one positive temperature in kelvin"))),
            },
            "spectrum" => match &param.values[..] {
                [Value::Str(s)] if s == "stdillum-D65" => Rgb::WHITE,
                [Value::Str(s)] => {
                    return Err(p.error(pos, format!("named spectrum \"{s}\" is not supported for lights (stdillum-D65, blackbody, rgb or sampled spectra are)")));
                }
                [Value::Num(_)] => {
                    spectrum = flat()?;
                    normalised(&|_| 1.0)?
                }
                _ => {
                    let s = color::piecewise_linear(&nums).filter(|_| nums.len() % 2 == 0).ok_or_else(|| {
                        p.error(
                            pos,
                            format!("parameter '{name}': expected wavelength/value pairs with increasing wavelengths"),
                        )
                    })?;
                    let points: Vec<(f32, f32)> = nums.chunks_exact(2).map(|c| (c[0] as f32, c[1] as f32)).collect();
                    let table =
                        Tabulated::new(&points).map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
                    spectrum = unit(EmissionSpectrum::Tabulated(Arc::new(table)))?;
                    normalised(&s)?
                }
            },
            "float" => {
                spectrum = flat()?;
                normalised(&|_| 1.0)?
            }
            other => {
                return Err(p.error(
                    pos,
                    format!("parameter '{name}' has type '{other}', expected rgb, spectrum or blackbody"),
                ));
            }
        };
        if !rgb.is_finite() {
            return Err(p.error(pos, format!("parameter '{name}' is not finite")));
        }
        Ok((rgb, spectrum))
    }

    fn texture_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let name = d.str_arg(0).to_string();
        let kind = d.str_arg(1);
        let class = d.str_arg(2);
        let p = &d.params;
        if kind != "spectrum" && kind != "float" {
            return Err(err(file, d.arg_pos[1], format!("texture type \"{kind}\" (expected spectrum or float)")));
        }
        if self.textures.contains_key(&name) {
            return Err(err(file, d.arg_pos[0], format!("texture \"{name}\" defined twice")));
        }
        let uv = |p: &ParamSet| -> Result<(f32, f32, f32, f32), SceneError> {
            if let Some((m, pos)) = p.string("mapping")?
                && m != "uv"
            {
                return Err(p.error(pos, format!("texture mapping \"{m}\" is not supported (only uv)")));
            }
            Ok((p.float("uscale", 1.0)?, p.float("vscale", 1.0)?, p.float("udelta", 0.0)?, p.float("vdelta", 0.0)?))
        };
        let texture = match class {
            "constant" => {
                if kind == "float" {
                    Texture::Constant(Rgb::splat(p.float("value", 1.0)?))
                } else {
                    self.spectrum_texture(p, "value", Rgb::WHITE, false)?
                }
            }
            "checkerboard" => {
                let dimension = p.int("dimension", 2)?;
                if dimension != 2 {
                    return Err(err(file, d.pos, "3D checkerboard textures are not supported"));
                }
                let (su, sv, du, dv) = uv(p)?;
                let constant = |name: &str, default: f32| -> Result<Rgb, SceneError> {
                    match self.spectrum_texture(p, name, Rgb::splat(default), false)? {
                        Texture::Constant(c) => Ok(c),
                        _ => Err(p.error(d.pos, format!("checkerboard: '{name}' must be a constant, not a texture"))),
                    }
                };
                // pbrt: tex1 where floor(s) + floor(t) is even, with (s, t) = (su·u + du, sv·v + dv).
                // Ours: colour0 where frac(s') and frac(t') lie on the same side of ½; with
                // (s', t') = (s, t) / 2 the two agree.
                Texture::Checkerboard {
                    color0: constant("tex1", 1.0)?,
                    color1: constant("tex2", 0.0)?,
                    to_uv: UvTransform {
                        columns: [Vec2::new(su * 0.5, 0.0), Vec2::new(0.0, sv * 0.5)],
                        translation: Vec2::new(du * 0.5, dv * 0.5),
                    },
                }
            }
            "imagemap" => {
                let Some((filename, fpos)) = p.string("filename")? else {
                    return Err(err(file, d.pos, "imagemap texture needs a \"string filename\""));
                };
                let path = resolve(file, &filename);
                let stored =
                    crate::read_texture_file(&path).map_err(|e| p.error(fpos, format!("cannot read image: {e}")))?;
                // pbrt-v4: `encoding` applies to 8-bit (here: every integer) images, default sRGB;
                // float images are linear.
                let encoding = match p.string("encoding")? {
                    None => crate::TextureEncoding::Srgb,
                    Some((e, _)) if e == "sRGB" => crate::TextureEncoding::Srgb,
                    Some((e, _)) if e == "linear" => crate::TextureEncoding::Linear,
                    Some((e, epos)) => match e.strip_prefix("gamma ").map(|g| g.trim().parse::<f32>()) {
                        Some(Ok(g)) if g.is_finite() && g > 0.0 => crate::TextureEncoding::Gamma(g),
                        _ => {
                            return Err(p.error(
                                epos,
                                format!("encoding \"{e}\" is not one of \"sRGB\", \"linear\", \"gamma <g>\" (g > 0)"),
                            ));
                        }
                    },
                };
                let image = stored.linear(encoding);
                let filter = match p.string("filter")? {
                    None => FilterMode::Bilinear,
                    Some((f, _)) if f == "bilinear" => FilterMode::Bilinear,
                    Some((f, _)) if f == "point" => FilterMode::Nearest,
                    Some((f, fpos)) if f == "trilinear" || f == "ewa" || f == "EWA" => {
                        self.unsupported(
                            p.error(fpos, format!("imagemap filter \"{f}\" (MIP-mapping) is not supported")),
                            "bilinear filtering used",
                        )?;
                        FilterMode::Bilinear
                    }
                    Some((f, fpos)) => {
                        return Err(p.error(fpos, format!("unknown imagemap filter \"{f}\"")));
                    }
                };
                let wrap = match p.string("wrap")? {
                    None => WrapMode::Repeat,
                    Some((w, _)) if w == "repeat" => WrapMode::Repeat,
                    Some((w, _)) if w == "clamp" => WrapMode::Clamp,
                    Some((w, _)) if w == "black" => WrapMode::Black,
                    Some((w, wpos)) => {
                        return Err(p.error(wpos, format!("imagemap wrap \"{w}\" is not one of repeat, clamp, black")));
                    }
                };
                p.float("maxanisotropy", 8.0)?;
                let scale = p.float("scale", 1.0)?;
                let invert = p.bool("invert", false)?;
                let (su, sv, du, dv) = uv(p)?;
                let pixels = image
                    .pixels
                    .iter()
                    .map(|px| {
                        let mut c = *px;
                        if kind == "float" {
                            c = [c[0]; 3];
                        }
                        let c = c.map(|v| {
                            let v = v * scale;
                            if invert { (1.0 - v).max(0.0) } else { v }
                        });
                        Rgb::from_array(c)
                    })
                    .collect();
                let image = Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels });
                // pbrt looks up (s, 1 − t): t = 0 is the bottom row; our v' runs from the top.
                let to_uv = UvTransform {
                    columns: [Vec2::new(su, 0.0), Vec2::new(0.0, -sv)],
                    translation: Vec2::new(du, 1.0 - dv),
                };
                Texture::bitmap(image, to_uv, Sampling { wrap, filter })
            }
            "scale" => {
                let texture = self.spectrum_texture(p, "tex", Rgb::WHITE, false)?;
                let scale = self.spectrum_texture(p, "scale", Rgb::WHITE, false)?;
                match (texture.as_constant(), scale.as_constant()) {
                    (Some(a), Some(b)) => Texture::Constant(a * b),
                    _ => Texture::Scale { texture: Arc::new(texture), scale: Arc::new(scale) },
                }
            }
            "mix" => {
                let tex1 = self.spectrum_texture(p, "tex1", Rgb::BLACK, false)?;
                let tex2 = self.spectrum_texture(p, "tex2", Rgb::WHITE, false)?;
                let amount = self.spectrum_texture(p, "amount", Rgb::splat(0.5), false)?;
                if let Some(a) = amount.as_constant()
                    && !(0.0..=1.0).contains(&a.r)
                {
                    let pos = p.find("amount").map_or(d.pos, |x| x.pos);
                    return Err(p.error(pos, format!("mix amount {} outside [0, 1] is not supported", a.r)));
                }
                match (tex1.as_constant(), tex2.as_constant(), amount.as_constant()) {
                    (Some(a), Some(b), Some(t)) => Texture::Constant(a * (1.0 - t.r) + b * t.r),
                    _ => Texture::Mix { tex1: Arc::new(tex1), tex2: Arc::new(tex2), amount: Arc::new(amount) },
                }
            }
            other @ ("directionmix" | "bilerp" | "dots" | "fbm" | "wrinkled" | "windy" | "marble" | "ptex") => {
                return Err(err(file, d.arg_pos[2], format!("texture class \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.arg_pos[2], format!("unknown texture class \"{other}\""))),
        };
        self.warn_unused(p);
        self.textures.insert(name, NamedTexture { texture });
        Ok(())
    }

    // ----- materials ------------------------------------------------------------------------

    /// Textured roughness: `Some((α_u, α_v textures, remap))` when `roughness`, `uroughness`
    /// or `vroughness` names a non-constant texture (the others are taken as constants).
    fn roughness_textures(&self, p: &ParamSet) -> Result<Option<(Texture, Texture, bool)>, SceneError> {
        let textured = |name: &str| {
            p.find(name).is_some_and(|x| {
                x.ty == "texture"
                    && matches!(&x.values[..], [Value::Str(t)]
                        if self.textures.get(t).is_some_and(|n| n.texture.as_constant().is_none()))
            })
        };
        if !["roughness", "uroughness", "vroughness"].iter().any(|n| textured(n)) {
            return Ok(None);
        }
        let r = self.spectrum_texture(p, "roughness", Rgb::BLACK, false)?;
        let u = if p.find("uroughness").is_some() {
            self.spectrum_texture(p, "uroughness", Rgb::BLACK, false)?
        } else {
            r.clone()
        };
        let v =
            if p.find("vroughness").is_some() { self.spectrum_texture(p, "vroughness", Rgb::BLACK, false)? } else { r };
        Ok(Some((u, v, p.bool("remaproughness", true)?)))
    }

    /// `material(α_u, α_v)` with constant roughness, or wrapped in
    /// [`Material::TexturedRoughness`] with textured roughness; `smooth` is the material for
    /// constant α below [`SMOOTH_ALPHA`].
    fn rough(
        &self,
        p: &ParamSet,
        smooth: impl FnOnce() -> Material,
        make: impl FnOnce(f32, f32) -> Material,
    ) -> Result<Material, SceneError> {
        if let Some((alpha_u, alpha_v, remap)) = self.roughness_textures(p)? {
            return Ok(Material::TexturedRoughness { alpha_u, alpha_v, remap, nested: Box::new(make(0.1, 0.1)) });
        }
        let (alpha_u, alpha_v) = self.roughness(p)?;
        Ok(if alpha_u.max(alpha_v) < SMOOTH_ALPHA { smooth() } else { make(alpha_u, alpha_v) })
    }

    fn roughness(&self, p: &ParamSet) -> Result<(f32, f32), SceneError> {
        let r = self.constant_float(p, "roughness", 0.0)?;
        let u = if p.find("uroughness").is_some() { self.constant_float(p, "uroughness", r)? } else { r };
        let v = if p.find("vroughness").is_some() { self.constant_float(p, "vroughness", r)? } else { r };
        if !(u >= 0.0 && v >= 0.0 && u.is_finite() && v.is_finite()) {
            return Err(
                p.error(p.params.first().map_or(Pos { line: 0, column: 0 }, |x| x.pos), "roughness must be ≥ 0")
            );
        }
        let remap = p.bool("remaproughness", true)?;
        Ok(if remap { (u.sqrt(), v.sqrt()) } else { (u, v) })
    }

    fn material(&self, file: &Path, d: &Directive, ty: &str) -> Result<Material, SceneError> {
        let material = self.base_material(file, d, ty)?;
        if ty == "mix" { Ok(material) } else { self.perturbation(file, d, material) }
    }

    /// pbrt-v4's `string normalmap` (an image of tangent-space normals, read linear, looked up
    /// at (u, 1 − v) with repeat and bilinear filtering) or `float texture displacement` (a
    /// bump map: the gradient of the displacement tilts the shading normal; pbrt's finite
    /// difference is replaced by the exact gradient and its `displace · ∂n/∂u` term is
    /// omitted) around `material`.
    fn perturbation(&self, file: &Path, d: &Directive, material: Material) -> Result<Material, SceneError> {
        let p = &d.params;
        let normal_map = p.string("normalmap")?;
        let displacement = p.find("displacement").map(|x| x.pos);
        let nested = Box::new(material.clone());
        let wrapped = match (normal_map, displacement) {
            (None, None) => return Ok(material),
            (Some((_, pos)), Some(_)) => {
                return Err(p.error(pos, "give either \"normalmap\" or \"displacement\", not both"));
            }
            (Some((filename, pos)), None) => {
                let path = resolve(file, &filename);
                let stored = crate::read_texture_file(&path)
                    .map_err(|e| p.error(pos, format!("cannot read normal map: {e}")))?;
                let image = stored.linear(crate::TextureEncoding::Linear);
                let pixels = image.pixels.iter().map(|&c| Rgb::from_array(c)).collect();
                let image = Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels });
                // (u, 1 − v): v = 0 is the bottom row; our v' runs from the top.
                let to_uv = UvTransform {
                    columns: [Vec2::new(1.0, 0.0), Vec2::new(0.0, -1.0)],
                    translation: Vec2::new(0.0, 1.0),
                };
                let normals =
                    Texture::bitmap(image, to_uv, Sampling { wrap: WrapMode::Repeat, filter: FilterMode::Bilinear });
                Material::NormalMap { normals, nested, options: scene::material::MapOptions::NONE }
            }
            (None, Some(_)) => {
                let height = self.spectrum_texture(p, "displacement", Rgb::BLACK, false)?;
                Material::BumpMap { height, scale: 1.0, nested, options: scene::material::MapOptions::NONE }
            }
        };
        let pos = p.params.first().map_or(d.pos, |x| x.pos);
        wrapped.validate().map_err(|e| p.error(pos, e))?;
        Ok(wrapped)
    }

    fn base_material(&self, file: &Path, d: &Directive, ty: &str) -> Result<Material, SceneError> {
        let p = &d.params;
        let two_sided = |m: Material| Material::TwoSided { front: Box::new(m), back: None };
        Ok(match ty {
            "diffuse" => two_sided(Material::Diffuse {
                reflectance: self.spectrum_texture(p, "reflectance", Rgb::splat(0.5), true)?,
            }),
            "conductor" => {
                let (eta, k, specular_reflectance) = if p.find("reflectance").is_some() {
                    for name in ["eta", "k"] {
                        if let Some(x) = p.find(name) {
                            return Err(p.error(x.pos, format!("'{name}' and 'reflectance' exclude each other")));
                        }
                    }
                    match self.spectrum_texture(p, "reflectance", Rgb::WHITE, true)? {
                        // pbrt: η = 1, k = 2√r / √(1 − r), whose normal-incidence Fresnel is r.
                        Texture::Constant(r) => {
                            let k = r.map(|r| {
                                let r = r.min(0.9999);
                                2.0 * r.sqrt() / (1.0 - r).sqrt()
                            });
                            (Rgb::WHITE, k, Texture::Constant(Rgb::WHITE))
                        }
                        textured => (Rgb::BLACK, Rgb::BLACK, textured),
                    }
                } else {
                    let eta = self.unbounded(p, "eta", "metal-Cu-eta")?;
                    let k = self.unbounded(p, "k", "metal-Cu-k")?;
                    (eta, k, Texture::Constant(Rgb::WHITE))
                };
                let smooth_reflectance = specular_reflectance.clone();
                let m = self.rough(
                    p,
                    || Material::Conductor { eta, k, specular_reflectance: smooth_reflectance },
                    |alpha_u, alpha_v| Material::RoughConductor {
                        distribution: Distribution::Ggx,
                        alpha_u,
                        alpha_v,
                        eta,
                        k,
                        specular_reflectance,
                    },
                )?;
                two_sided(m)
            }
            "diffusetransmission" => {
                // pbrt-v4: reflectance and transmittance (default 0.25 each), both times `scale`.
                let scale = p.float("scale", 1.0)?;
                let scaled = |texture: Texture| match texture.as_constant() {
                    Some(c) => Texture::Constant(c * scale),
                    None if scale == 1.0 => texture,
                    None => Texture::Scale {
                        texture: Arc::new(texture),
                        scale: Arc::new(Texture::Constant(Rgb::splat(scale))),
                    },
                };
                Material::DiffuseTransmission {
                    reflectance: scaled(self.spectrum_texture(p, "reflectance", Rgb::splat(0.25), true)?),
                    transmittance: scaled(self.spectrum_texture(p, "transmittance", Rgb::splat(0.25), true)?),
                }
            }
            "dielectric" | "thindielectric" => {
                let eta = self.ior(p)?;
                let white = || Texture::Constant(Rgb::WHITE);
                if ty == "thindielectric" {
                    Material::ThinDielectric {
                        int_ior: eta,
                        ext_ior: 1.0,
                        specular_reflectance: white(),
                        specular_transmittance: white(),
                    }
                } else {
                    self.rough(
                        p,
                        || Material::Dielectric {
                            int_ior: eta,
                            ext_ior: 1.0,
                            specular_reflectance: white(),
                            specular_transmittance: white(),
                            dispersion: None,
                        },
                        |alpha_u, alpha_v| Material::RoughDielectric {
                            distribution: Distribution::Ggx,
                            alpha_u,
                            alpha_v,
                            int_ior: eta,
                            ext_ior: 1.0,
                            specular_reflectance: white(),
                            specular_transmittance: white(),
                        },
                    )?
                }
            }
            "mix" => {
                let Some(param) = p.typed("materials", &["string"])? else {
                    return Err(err(file, d.pos, "mix material needs \"string materials\" [two names]"));
                };
                let names = param.strings();
                if names.len() != 2 {
                    return Err(p.error(param.pos, format!("mix needs 2 materials, got {}", names.len())));
                }
                let lookup = |n: &str| {
                    self.named_materials
                        .get(n)
                        .map(|(m, _)| Box::new(m.clone()))
                        .ok_or_else(|| p.error(param.pos, format!("unknown named material \"{n}\"")))
                };
                let weight = match p.find("amount") {
                    Some(a) if a.ty == "texture" => self.spectrum_texture(p, "amount", Rgb::splat(0.5), false)?,
                    _ => Texture::Constant(Rgb::splat(p.float("amount", 0.5)?)),
                };
                Material::Blend { weight, first: lookup(&names[0])?, second: lookup(&names[1])? }
            }
            // An index-matched boundary: a placeholder the scene marks as such (`medium.rs`).
            "interface" => Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) },
            "coateddiffuse" | "coatedconductor" => self.coated_material(d, ty)?,
            "hair" => Material::Hair(self.hair(p, d.pos)?),
            other @ ("measured" | "subsurface") => {
                return Err(err(file, d.pos, format!("material \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.pos, format!("unknown material type \"{other}\""))),
        })
    }

    /// pbrt-v4's `hair`: the absorption from `sigma_a`, else from `reflectance` (pbrt-v3:
    /// `color`) through Chiang et al.'s mapping, else from `eumelanin`/`pheomelanin` (eumelanin
    /// 1.3 when none is given); `eta` 1.55, `beta_m`, `beta_n` 0.3, `alpha` 2°. Textured
    /// parameters are not supported.
    fn hair(&self, p: &ParamSet, pos: Pos) -> Result<HairParameters, SceneError> {
        let constant = |name: &str, albedo: bool| -> Result<Option<Rgb>, SceneError> {
            let Some(param) = p.find(name) else { return Ok(None) };
            match self.spectrum_texture(p, name, Rgb::BLACK, albedo)? {
                Texture::Constant(c) => Ok(Some(c)),
                _ => Err(p.error(param.pos, format!("hair: a textured '{name}' is not supported"))),
            }
        };
        let mut hair = HairParameters {
            eta: p.float("eta", 1.55)?,
            beta_m: p.float("beta_m", 0.3)?,
            beta_n: p.float("beta_n", 0.3)?,
            alpha: p.float("alpha", 2.0)?,
            ..HairParameters::default()
        };
        let reflectance = match constant("reflectance", true)? {
            Some(c) => Some(c),
            None => constant("color", true)?,
        };
        let (eumelanin, pheomelanin) = (p.float_opt("eumelanin")?, p.float_opt("pheomelanin")?);
        hair.sigma_a = if let Some(s) = constant("sigma_a", false)? {
            s
        } else if let Some(c) = reflectance {
            HairParameters::sigma_a_from_color(c, hair.beta_n)
        } else {
            let eumelanin = if pheomelanin.is_none() { eumelanin.unwrap_or(1.3) } else { eumelanin.unwrap_or(0.0) };
            HairParameters::sigma_a_from_melanin(eumelanin, pheomelanin.unwrap_or(0.0))
        };
        hair.validate().map_err(|e| p.error(pos, e))?;
        Ok(hair)
    }

    /// A conductor's η or k: constant RGB (named spectra via the table in [`color`]).
    fn unbounded(&self, p: &ParamSet, name: &str, default: &str) -> Result<Rgb, SceneError> {
        match self.spectrum_texture(p, name, color::named_metal(default).unwrap_or(Rgb::WHITE), false)? {
            Texture::Constant(c) => Ok(c),
            _ => Err(p.error(
                p.find(name).map_or(Pos { line: 0, column: 0 }, |x| x.pos),
                format!("textured '{name}' is not supported"),
            )),
        }
    }

    /// A dielectric's index of refraction (`float`, a constant or a named glass spectrum).
    fn ior(&self, p: &ParamSet) -> Result<f32, SceneError> {
        let Some(param) = p.find("eta") else { return Ok(1.5) };
        let pos = param.pos;
        let eta = match (param.ty.as_str(), &param.values[..]) {
            ("float" | "spectrum", [Value::Num(x)]) => *x as f32,
            ("spectrum", [Value::Str(s)]) => {
                color::named_glass(s).ok_or_else(|| p.error(pos, format!("unknown named glass spectrum \"{s}\"")))?
            }
            ("texture", _) => self.constant_float(p, "eta", 1.5)?,
            ("spectrum", _) => {
                let nums = param.numbers();
                let s = color::piecewise_linear(&nums)
                    .filter(|_| nums.len() % 2 == 0)
                    .ok_or_else(|| p.error(pos, "eta: expected wavelength/value pairs with increasing wavelengths"))?;
                s(587.6) as f32
            }
            _ => return Err(p.error(pos, "eta needs one float, a named glass spectrum or a sampled spectrum")),
        };
        if !(eta > 0.0 && eta.is_finite()) {
            return Err(p.error(pos, format!("eta {eta} must be positive")));
        }
        Ok(eta)
    }

    // ----- shapes ---------------------------------------------------------------------------

    fn current_material(&mut self) -> u32 {
        if let Some(m) = self.state.material {
            return m;
        }
        if let Some(m) = self.default_material {
            return m;
        }
        self.materials.push(Material::TwoSided {
            front: Box::new(Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }),
            back: None,
        });
        let m = self.materials.len() as u32 - 1;
        self.default_material = Some(m);
        m
    }

    fn shape_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        let p = &d.params;
        let ctm = self.state.ctm;
        if !ctm.is_affine() {
            return Err(err(file, d.pos, "shapes under a projective transformation are not supported"));
        }
        let name = format!(
            "{ty} ({}:{})",
            file.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            d.pos.line
        );
        let geometry = match ty {
            "trianglemesh" | "bilinearmesh" => {
                let quads = ty == "bilinearmesh";
                let corners = if quads { 4 } else { 3 };
                let Some((positions, _)) = p.numbers("P", &["point3"], 3)? else {
                    return Err(err(file, d.pos, format!("{ty} needs \"point3 P\"")));
                };
                let count = positions.len() / 3;
                let indices = match p.ints("indices")? {
                    Some(i) => i,
                    None if count == corners => (0..corners as i64).collect(),
                    None => {
                        return Err(err(
                            file,
                            d.pos,
                            format!("{ty} needs \"integer indices\" (it has {count} vertices)"),
                        ));
                    }
                };
                let ipos = p.find("indices").map_or(d.pos, |x| x.pos);
                if indices.len() % corners != 0 {
                    return Err(p.error(ipos, format!("{} indices is not a multiple of {corners}", indices.len())));
                }
                if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= count) {
                    return Err(p.error(ipos, format!("index {bad} is out of range (there are {count} vertices)")));
                }
                let normals = p.numbers("N", &["normal3"], 3)?;
                let uvs = match p.numbers("uv", &["point2", "float"], 2)? {
                    Some(v) => Some(v),
                    None => p.numbers("st", &["point2", "float"], 2)?,
                };
                for (what, values, per) in [("N", &normals, 3), ("uv", &uvs, 2)] {
                    if let Some((v, pos)) = values
                        && v.len() / per != count
                    {
                        return Err(p.error(*pos, format!("{} values of '{what}' for {count} vertices", v.len() / per)));
                    }
                }
                let mut triangles = Vec::new();
                for c in indices.chunks(corners) {
                    let c: Vec<u32> = c.iter().map(|&i| i as u32).collect();
                    if quads {
                        // Vertices p00, p10, p01, p11: the quad's boundary is p00 p10 p11 p01.
                        triangles.push([c[0], c[1], c[3]]);
                        triangles.push([c[0], c[3], c[2]]);
                    } else {
                        triangles.push([c[0], c[1], c[2]]);
                    }
                }
                let object = MeshData {
                    positions: positions.chunks(3).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect(),
                    normals: normals.map_or_else(Vec::new, |(v, _)| {
                        v.chunks(3).map(|n| Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32)).collect()
                    }),
                    uvs: uvs.map_or_else(Vec::new, |(v, _)| {
                        v.chunks(2).map(|t| Vec2::new(t[0] as f32, t[1] as f32)).collect()
                    }),
                    triangles,
                    attributes: Vec::new(),
                };
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "plymesh" => {
                let Some((filename, fpos)) = p.string("filename")? else {
                    return Err(err(file, d.pos, "plymesh needs a \"string filename\""));
                };
                let path = resolve(file, &filename);
                if !path.is_file() {
                    return Err(p.error(fpos, format!("mesh file '{}' does not exist", path.display())));
                }
                let object = crate::mesh::read_ply(&path)?;
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "sphere" => {
                let radius = p.float("radius", 1.0)?;
                for (param, default) in [("zmin", -radius), ("zmax", radius), ("phimax", 360.0)] {
                    if let Some(x) = p.find(param)
                        && p.float(param, default)? != default
                    {
                        return Err(p.error(x.pos, format!("partial spheres ('{param}') are not supported")));
                    }
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(err(file, d.pos, format!("sphere radius {radius} must be positive")));
                }
                let scale = similarity_scale(&ctm)
                    .ok_or_else(|| err(file, d.pos, "sphere under a non-uniform scale or shear is not supported"))?;
                Geometry::Sphere {
                    center: f32v(ctm.point([0.0; 3])),
                    radius: (f64::from(radius) * scale) as f32,
                    flip_normals: self.state.reverse_orientation,
                }
            }
            "disk" => {
                let height = f64::from(p.float("height", 0.0)?);
                let radius = f64::from(p.float("radius", 1.0)?);
                if p.float("innerradius", 0.0)? != 0.0 || p.float("phimax", 360.0)? != 360.0 {
                    return Err(err(file, d.pos, "partial disks ('innerradius', 'phimax') are not supported"));
                }
                Geometry::Disk {
                    center: f32v(ctm.point([0.0, 0.0, height])),
                    axis_u: f32v(ctm.vector([radius, 0.0, 0.0])),
                    axis_v: f32v(ctm.vector([0.0, radius, 0.0])),
                    flip_normals: self.state.reverse_orientation,
                }
            }
            "cylinder" => {
                let radius = f64::from(p.float("radius", 1.0)?);
                let z_min = f64::from(p.float("zmin", -1.0)?);
                let z_max = f64::from(p.float("zmax", 1.0)?);
                let phi_max = f64::from(p.float("phimax", 360.0)?);
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(err(file, d.pos, format!("cylinder radius {radius} must be positive")));
                }
                if !(z_min.is_finite() && z_max.is_finite() && z_min != z_max) {
                    return Err(err(file, d.pos, format!("cylinder zmin {z_min} and zmax {z_max} must differ")));
                }
                if !(phi_max > 0.0 && phi_max <= 360.0) {
                    return Err(err(file, d.pos, format!("cylinder phimax {phi_max} must be in (0, 360]")));
                }
                // pbrt swaps zmin and zmax when they are reversed.
                let (z0, z1) = (z_min.min(z_max), z_min.max(z_max));
                let object = crate::cylinder::cylinder_mesh(radius, z0, z1, phi_max.to_radians());
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "loopsubdiv" => Geometry::Mesh(self.to_world_mesh(file, d.pos, loop_subdivision_mesh(file, d)?)?),
            "curve" => Geometry::Mesh(self.to_world_mesh(file, d.pos, curve::curve_mesh(p, d.pos)?)?),
            other @ ("cone" | "paraboloid" | "hyperboloid") => {
                return Err(err(file, d.arg_pos[0], format!("shape \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.arg_pos[0], format!("unknown shape type \"{other}\""))),
        };
        let material = self.current_material();
        let alpha = self.shape_alpha(p)?;
        if let (Some(_), Some(spectrum)) = (self.state.area_light, &self.state.area_light_spectrum) {
            self.emission_spectra.shapes.insert(self.shapes.len() as u32, spectrum.clone());
        }
        if let Some(texture) = &self.state.area_light_texture {
            if !matches!(geometry, Geometry::Mesh(_)) {
                return Err(err(file, d.pos, "a diffuse area light with a \"filename\" image needs a triangle mesh"));
            }
            self.emission_spectra.textures.insert(self.shapes.len() as u32, texture.clone());
        }
        let interface = self.state.medium_interface;
        if interface.interior != interface.exterior && self.defining.is_some() {
            return Err(err(file, d.pos, "media on shapes in an object definition are not supported (issue #15)"));
        }
        self.media.shape(self.shapes.len() as u32, interface);
        self.shapes.push(ShapeDesc { name, geometry, material, emission: self.state.area_light, alpha });
        self.warn_unused(p);
        Ok(())
    }

    /// Transforms an object-space mesh to world space and winds its triangles so that the
    /// right-hand-rule normal is pbrt's surface normal (module documentation).
    fn to_world_mesh(&self, file: &Path, pos: Pos, mut mesh: MeshData) -> Result<MeshData, SceneError> {
        let ctm = self.state.ctm;
        mesh.validate().map_err(|e| err(file, pos, e))?;
        let normal_matrix = ctm.inverse().ok_or_else(|| err(file, pos, "the shape's transformation is singular"))?;
        for p in &mut mesh.positions {
            *p = f32v(ctm.point([p.x, p.y, p.z].map(f64::from)));
        }
        for n in &mut mesh.normals {
            // Normals transform with the inverse transpose.
            let m = &normal_matrix.m;
            let v = [n.x, n.y, n.z].map(f64::from);
            let t = [0, 1, 2].map(|c| m[0][c] * v[0] + m[1][c] * v[1] + m[2][c] * v[2]);
            let t = normalize(t).unwrap_or([0.0, 0.0, 1.0]);
            let t = if self.state.reverse_orientation { t.map(|c| -c) } else { t };
            *n = f32v(t);
        }
        let flip = self.state.reverse_orientation ^ (ctm.det3() < 0.0);
        let has_normals = !mesh.normals.is_empty();
        for t in &mut mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let swap = if has_normals {
                let n = mesh.normals[t[0] as usize] + mesh.normals[t[1] as usize] + mesh.normals[t[2] as usize];
                (b - a).cross(c - a).dot(n) < 0.0
            } else {
                flip
            };
            if swap {
                t.swap(1, 2);
            }
        }
        mesh.validate().map_err(|e| err(file, pos, e))?;
        Ok(mesh)
    }

    // ----- lights ---------------------------------------------------------------------------

    /// pbrt-v4's `projection` light: the image (`filename`, looked up nearest-texel, row 0 at
    /// the top) is the intensity `scale·E` (W/sr) over a pinhole frustum along the light's +z
    /// whose shorter image axis spans `fov` degrees; the image's left is the light's −x and its
    /// top the light's +y (pbrt flips y). `power` rescales so that the flux, Σ over texels of
    /// luminance·cos³θ times the frustum's plane area over the texel count, is `power` watts.
    fn projection_light(&self, file: &Path, d: &Directive, scale: f32) -> Result<LightDesc, SceneError> {
        let p = &d.params;
        let (filename, fpos) =
            p.string("filename")?.ok_or_else(|| err(file, d.pos, "projection: \"filename\" is required"))?;
        let fov = p.float("fov", 90.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(err(file, d.pos, format!("projection: fov {fov} is not in (0, 180) degrees")));
        }
        let power = p.float_opt("power")?;
        let image = light_image(&resolve(file, &filename), 1.0).map_err(|e| p.error(fpos, e))?;
        let (width, height) = (image.width as usize, image.height as usize);
        let aspect = width as f32 / height as f32;
        let tan = (0.5 * fov.to_radians()).tan();
        // The screen window is [-a, a]×[-1, 1] for a wide image and [-1, 1]×[-1/a, 1/a] otherwise.
        let (bx, by) = if aspect > 1.0 { (aspect, 1.0) } else { (1.0, 1.0 / aspect) };
        let mut scale = scale;
        if let Some(power) = power.filter(|&power| power > 0.0) {
            let area = 4.0 * tan * tan * bx * by;
            let mut sum = 0.0f64;
            for (i, texel) in image.pixels.iter().enumerate() {
                let x = (2.0 * ((i % width) as f32 + 0.5) / width as f32 - 1.0) * bx * tan;
                let y = (2.0 * ((i / width) as f32 + 0.5) / height as f32 - 1.0) * by * tan;
                let cos3 = (1.0 + x * x + y * y).powf(-1.5);
                sum += f64::from(texel.luminance() * cos3);
            }
            let flux = f64::from(area) * sum / (width * height) as f64;
            if flux <= 0.0 {
                return Err(p.error(fpos, "projection: a black image cannot have a power"));
            }
            scale *= (f64::from(power) / flux) as f32;
        }
        let ctm = self.state.ctm;
        if similarity_scale(&ctm).is_none() {
            return Err(err(file, d.pos, "projection light under a non-uniform scale or shear"));
        }
        let axis =
            |v: V3| normalize(ctm.vector(v)).map(f32v).ok_or_else(|| err(file, d.pos, "singular transformation"));
        let (x, y, z) = (axis([1.0, 0.0, 0.0])?, axis([0.0, 1.0, 0.0])?, axis([0.0, 0.0, 1.0])?);
        let fov_x_degrees = 2.0 * (bx * tan).atan().to_degrees();
        let sampling = Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Nearest };
        Ok(LightDesc::Projector {
            model: scene::desc::ProjectorModel::Intensity,
            position: f32v(ctm.point([0.0; 3])),
            frame: [-x, y, z],
            irradiance: Arc::new(Texture::bitmap(image, UvTransform::IDENTITY, sampling)),
            scale,
            fov_x_degrees,
            aspect,
        })
    }

    fn area_light_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        if d.str_arg(0) != "diffuse" {
            return Err(err(
                file,
                d.arg_pos[0],
                format!("unknown area light type \"{}\" (expected diffuse)", d.str_arg(0)),
            ));
        }
        let p = &d.params;
        if let Some(x) = p.find("power") {
            return Err(p.error(x.pos, "parameter 'power' is not supported"));
        }
        if p.bool("twosided", false)? {
            let pos = p.find("twosided").map_or(d.pos, |x| x.pos);
            return Err(p.error(pos, "two-sided area lights are not supported (our emitters are one-sided)"));
        }
        let scale = p.float("scale", 1.0)?;
        self.state.area_light_texture = None;
        if let Some((filename, fpos)) = p.string("filename")? {
            if let Some(x) = p.find("L") {
                return Err(p.error(x.pos, "'L' and 'filename' exclude each other"));
            }
            let texture = area_light_image(&resolve(file, &filename), scale).map_err(|e| p.error(fpos, e))?;
            self.state.area_light = Some(texture.max_value().max(Rgb::splat(f32::MIN_POSITIVE)));
            self.state.area_light_spectrum = None;
            self.state.area_light_texture = Some(Arc::new(texture));
            self.warn_unused(p);
            return Ok(());
        }
        let (l, spectrum) = self.light_emission(p, "L")?;
        self.state.area_light = Some(l * scale);
        self.state.area_light_spectrum = match spectrum {
            Some(s) => Some(s.scaled(scale).map_err(|e| err(file, d.pos, e))?),
            None => None,
        };
        self.warn_unused(p);
        Ok(())
    }

    fn light_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let p = &d.params;
        let ctm = self.state.ctm;
        let scale = p.float("scale", 1.0)?;
        let point3 = |name: &str, default: V3| -> Result<V3, SceneError> {
            match p.numbers(name, &["point3"], 3)? {
                Some((v, pos)) if v.len() != 3 => Err(p.error(pos, format!("'{name}' needs one point"))),
                Some((v, _)) => Ok([v[0], v[1], v[2]]),
                None => Ok(default),
            }
        };
        let direction = |from: V3, to: V3| -> Result<Vec3, SceneError> {
            normalize(ctm.vector(transform::sub(to, from)))
                .map(f32v)
                .ok_or_else(|| err(file, d.pos, "'from' and 'to' coincide"))
        };
        // The unscaled RGB value and spectrum of a light given spectrally.
        let mut spectrum: Option<(Rgb, EmissionSpectrum)> = None;
        let light = match d.str_arg(0) {
            "point" => {
                let mut intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(power) = p.float_opt("power")? {
                    intensity *= power / (4.0 * std::f32::consts::PI);
                }
                LightDesc::Point { position: f32v(ctm.point(point3("from", [0.0; 3])?)), intensity }
            }
            "spot" => {
                let from = point3("from", [0.0; 3])?;
                let to = point3("to", [0.0, 0.0, 1.0])?;
                let cone = p.float("coneangle", 30.0)?;
                if let Some(old) = p.find("conedelta") {
                    return Err(
                        p.error(old.pos, "spot: pbrt-v4 calls this parameter \"conedeltaangle\", not \"conedelta\"")
                    );
                }
                let delta = p.float("conedeltaangle", 5.0)?;
                if !(cone > 0.0 && cone <= 180.0 && (0.0..=cone).contains(&delta)) {
                    return Err(err(
                        file,
                        d.pos,
                        format!("spot: coneangle {cone} / conedeltaangle {delta} out of range"),
                    ));
                }
                let mut intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(power) = p.float_opt("power")? {
                    let (cos_end, cos_start) = (cone.to_radians().cos(), (cone - delta).to_radians().cos());
                    let k = 2.0 * std::f32::consts::PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                    intensity *= power / k;
                }
                LightDesc::Spot {
                    position: f32v(ctm.point(from)),
                    direction: direction(from, to)?,
                    intensity,
                    cutoff_degrees: cone,
                    beam_width_degrees: cone - delta,
                    texture: None,
                }
            }
            "distant" => {
                let from = point3("from", [0.0; 3])?;
                let to = point3("to", [0.0, 0.0, 1.0])?;
                let mut irradiance = self.light_emission(p, "L").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(e) = p.float_opt("illuminance")? {
                    irradiance *= e;
                }
                LightDesc::Directional { direction: direction(from, to)?, irradiance }
            }
            "infinite" => {
                if self.lights.iter().any(|l| matches!(l, LightDesc::Constant { .. } | LightDesc::EnvMap { .. })) {
                    return Err(err(file, d.pos, "a second infinite light (only one environment is supported)"));
                }
                for name in ["illuminance", "portal"] {
                    if let Some(x) = p.find(name) {
                        return Err(p.error(x.pos, format!("parameter '{name}' is not supported")));
                    }
                }
                match p.string("filename")? {
                    None => LightDesc::Constant {
                        radiance: self.light_emission(p, "L").map(|(c, s)| {
                            spectrum = s.map(|s| (c, s));
                            c
                        })? * scale,
                    },
                    Some((filename, fpos)) => {
                        if let Some(x) = p.find("L") {
                            return Err(p.error(x.pos, "'L' and 'filename' exclude each other"));
                        }
                        let path = resolve(file, &filename);
                        let image =
                            crate::read_image(&path).map_err(|e| p.error(fpos, format!("cannot read image: {e}")))?;
                        if image.width != image.height {
                            return Err(p.error(
                                fpos,
                                format!(
                                    "environment image is {}×{}: pbrt-v4 needs a square equal-area octahedral image",
                                    image.width, image.height
                                ),
                            ));
                        }
                        let to_world = rotation_columns(&ctm)
                            .ok_or_else(|| err(file, d.pos, "infinite light under a non-rotation transformation"))?;
                        LightDesc::EnvMap {
                            image: Arc::new(envmap::octahedral_to_latlong(image.width, &image.pixels)),
                            scale,
                            to_world,
                        }
                    }
                }
            }
            "projection" => self.projection_light(file, d, scale)?,
            "goniometric" => {
                let intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                goniometric::goniometric_light(file, d, &ctm, intensity)?
            }
            other => return Err(err(file, d.arg_pos[0], format!("unknown light type \"{other}\""))),
        };
        if let Some((unscaled, s)) = spectrum {
            // The file's scale, power and illuminance factors multiply every channel alike.
            let value = match &light {
                LightDesc::Point { intensity, .. }
                | LightDesc::Spot { intensity, .. }
                | LightDesc::Goniometric { intensity, .. } => *intensity,
                LightDesc::Directional { irradiance, .. } => *irradiance,
                LightDesc::Constant { radiance } => *radiance,
                LightDesc::EnvMap { .. } | LightDesc::Projector { .. } => Rgb::BLACK,
            };
            let base = scene::LightSpectrum { spectrum: s, base: unscaled };
            let scaled = base.spectrum.scaled(base.factor(value)).map_err(|e| err(file, d.pos, e))?;
            self.emission_spectra.lights.insert(self.lights.len() as u32, scaled);
        }
        self.lights.push(light);
        self.warn_unused(p);
        Ok(())
    }
}

/// pbrt's `loopsubdiv` shape (`integer levels`, default 3; `integer indices`; `point3 P`)
/// refined at load ([`crate::loop_subdivision`]).
fn loop_subdivision_mesh(file: &Path, d: &Directive) -> Result<MeshData, SceneError> {
    let p = &d.params;
    let Some((positions, _)) = p.numbers("P", &["point3"], 3)? else {
        return Err(err(file, d.pos, "loopsubdiv needs \"point3 P\""));
    };
    let Some(indices) = p.ints("indices")? else {
        return Err(err(file, d.pos, "loopsubdiv needs \"integer indices\""));
    };
    let ipos = p.find("indices").map_or(d.pos, |x| x.pos);
    if indices.len() % 3 != 0 {
        return Err(p.error(ipos, format!("{} indices is not a multiple of 3", indices.len())));
    }
    let levels = p.ints("levels")?.map_or(Ok(3), |v| match v.as_slice() {
        [n] if *n >= 0 => Ok(*n as u32),
        _ => Err(err(file, d.pos, "loopsubdiv: \"integer levels\" must be one number >= 0")),
    })?;
    let count = positions.len() / 3;
    if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= count) {
        return Err(p.error(ipos, format!("index {bad} is out of range (there are {count} vertices)")));
    }
    let points: Vec<Vec3> = positions.chunks(3).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let triangles: Vec<[u32; 3]> = indices.chunks(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();
    crate::loop_subdivision::subdivide(&points, &triangles, levels)
        .map_err(|e| err(file, d.pos, format!("loopsubdiv: {e}")))
}

/// The radiance image of a `diffuse` area light (`filename`), times `scale`: 8-bit images
/// sRGB-decoded, float images linear, looked up bilinearly at `(u, 1 − v)` (pbrt-v4's
/// convention for images, as for `imagemap`) with clamped edges.
/// An emitter's image file as linear texels times `scale` (8-bit files decoded from sRGB, as
/// pbrt-v4 reads them); negative or non-finite values are errors.
fn light_image(path: &Path, scale: f32) -> Result<Arc<TextureImage>, String> {
    let stored = crate::read_texture_file(path).map_err(|e| format!("cannot read image: {e}"))?;
    let image = stored.linear(crate::TextureEncoding::Srgb);
    if let Some(v) = image.pixels.iter().flatten().find(|v| !v.is_finite() || **v < 0.0) {
        return Err(format!("image '{}' has a negative or non-finite value {v}", path.display()));
    }
    let pixels = image.pixels.iter().map(|px| Rgb::from_array(px.map(|v| v * scale))).collect();
    Ok(Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels }))
}

fn area_light_image(path: &Path, scale: f32) -> Result<Texture, String> {
    let image = light_image(path, scale)?;
    let to_uv = UvTransform { columns: [Vec2::new(1.0, 0.0), Vec2::new(0.0, -1.0)], translation: Vec2::new(0.0, 1.0) };
    Ok(Texture::bitmap(image, to_uv, Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Bilinear }))
}

/// A path named in `file`, relative to its directory unless absolute.
fn resolve(file: &Path, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() { p.to_path_buf() } else { file.parent().unwrap_or(Path::new(".")).join(p) }
}

/// The uniform scale factor of a rotation × uniform scale (+ translation), else `None`.
fn similarity_scale(m: &Mat4) -> Option<f64> {
    let cols = [0, 1, 2].map(|c| m.vector([0, 1, 2].map(|k| if k == c { 1.0 } else { 0.0 })));
    let s = norm(cols[0]);
    let tol = 1e-4 * s;
    let ok = s > 0.0
        && (norm(cols[1]) - s).abs() <= tol
        && (norm(cols[2]) - s).abs() <= tol
        && dot(cols[0], cols[1]).abs() <= tol * s
        && dot(cols[0], cols[2]).abs() <= tol * s
        && dot(cols[1], cols[2]).abs() <= tol * s;
    ok.then_some(s)
}

/// The normalised columns of the linear part when it is a rotation (or reflection) times a
/// uniform scale.
fn rotation_columns(m: &Mat4) -> Option<[Vec3; 3]> {
    let s = similarity_scale(m)?;
    Some([0, 1, 2].map(|c| f32v(m.vector([0, 1, 2].map(|k| if k == c { 1.0 / s } else { 0.0 })))))
}

/// The world-space camera for a film of `width × height`.
fn camera_desc(spec: &CameraSpec, width: u32, height: u32) -> Result<CameraDesc, SceneError> {
    let w = &spec.world_from_camera;
    let e = |m: &str| err(&spec.file, spec.pos, m.to_string());
    let right = w.vector([1.0, 0.0, 0.0]);
    let up = w.vector([0.0, 1.0, 0.0]);
    let forward = w.vector([0.0, 0.0, 1.0]);
    let (r, u, f) = (
        normalize(right).ok_or_else(|| e("degenerate camera transformation"))?,
        normalize(up).ok_or_else(|| e("degenerate camera transformation"))?,
        normalize(forward).ok_or_else(|| e("degenerate camera transformation"))?,
    );
    if dot(r, u).abs() > 1e-3 || dot(r, f).abs() > 1e-3 || dot(u, f).abs() > 1e-3 {
        return Err(e("the camera transformation shears the camera's axes; not supported"));
    }
    let aspect = f64::from(width) / f64::from(height);
    // pbrt's screen window spans [-1, 1] on the shorter axis.
    let half_width = aspect.max(1.0);
    let projection = if spec.orthographic {
        Projection::Orthographic { width: (2.0 * half_width * norm(right)) as f32 }
    } else {
        let tan_half = (f64::from(spec.fov_degrees).to_radians() * 0.5).tan() * half_width;
        let horizontal_fov_degrees = (2.0 * tan_half.atan()).to_degrees() as f32;
        if spec.lens_radius > 0.0 {
            Projection::ThinLens {
                horizontal_fov_degrees,
                aperture_radius: spec.lens_radius,
                focus_distance: spec.focal_distance,
            }
        } else {
            Projection::Perspective { horizontal_fov_degrees }
        }
    };
    Ok(CameraDesc { position: f32v(w.point([0.0; 3])), forward: f32v(f), up: f32v(u), right: f32v(r), projection })
}
