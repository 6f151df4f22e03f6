//! pbrt-v4 scene loader: our own tokenizer and parser (the `pbrt4` crate is unusable, see
//! `DEPENDENCIES.md`) and the conversion to a [`SceneDescription`].
//!
//! # Conventions and conversions
//!
//! - **Coordinates.** pbrt's numbers are used as they are; its "left-handed" system only
//!   changes how a picture is drawn, not a formula. The camera looks along its +z with +y up
//!   and +x to the right of the image. The transformation at `Camera` is camera-from-world;
//!   the [`CameraDesc`](scene::desc::CameraDesc) gets the world-space images of the camera's
//!   origin and axes (so a `LookAt` without `Scale -1 1 1` gives the mirror image of the same
//!   `lookat` in Mitsuba, exactly as in the two renderers).
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
//!   the layered `coateddiffuse` and `coatedconductor` are in `coated.rs`; `hair` is in
//!   `materials.rs` and `curve` shapes (tessellated into tubes) in `curve.rs`;
//!   unsupported optional parameters are warnings in [`SceneDescription::warnings`].
//!
//! # Files
//!
//! This file holds the builder's state, the directive dispatch and the world's bookkeeping
//! (graphics state, blocks, includes); the directives' conversions are split by subject:
//! `camera.rs` (camera, film, filter), `textures.rs`, `materials.rs`, `shapes.rs`, `lights.rs`,
//! beside the older `coated.rs`, `curve.rs`, `medium.rs`, `instancing.rs` and the others.

mod alpha;
mod camera;
mod coated;
pub mod color;
mod curve;
pub mod envmap;
mod goniometric;
mod grid_medium;
mod instancing;
mod lights;
mod materials;
mod medium;
mod nanovdb_medium;
mod parser;
mod shapes;
mod textures;
pub mod tokenizer;
mod transform;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use math::Vec3;
use scene::desc::{EmissionSpectra, EmissionSpectrum, FilmDesc, FilterDesc, LightDesc, SceneDescription, ShapeDesc};
use scene::material::Material;
use scene::texture::Texture;
use spectrum::Rgb;

use crate::options::{LoadOptions, LoadedScene, RenderSettings};
use crate::pbrt::parser::{Directive, ParamSet, Parser};
use crate::pbrt::tokenizer::Pos;
use crate::pbrt::transform::{Mat4, V3, dot, norm};
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
        let camera = camera::camera_desc(&spec, width, height)?;
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
