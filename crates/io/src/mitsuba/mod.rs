//! Mitsuba 3 XML scene loader.
//!
//! The file is read into an element tree (`xml`): `<include>`s are spliced in (cycles are
//! errors), `<default>` parameters and the `-D` defines are substituted for `$name` in every
//! attribute (defines win over defaults, an undefined parameter is an error), `<path>`
//! directories join the search path. Every file name (includes, meshes, textures) is looked
//! up as Mitsuba 3 does: the `<path>` directories, latest first, then the scene file's
//! directory (see `search`); a file not found is an error listing every path searched. The tree is then
//! walked in document order; objects with an `id` may be referenced (`<ref id=…/>`, also
//! `<ref name="reflectance" id=…/>` for textures) from anywhere in the scene, before or after
//! their definition.
//!
//! Conventions honoured (see the individual modules for details):
//!
//! - transforms compose in document order (`M = op_n ⋯ op_1`); `lookat` builds Mitsuba's
//!   camera frame (`+z` forward, `+y` up, `+x` to the *left* of the image);
//! - meshes are transformed with positions by `to_world` and normals by its inverse transpose;
//!   when `to_world` mirrors (negative determinant) the triangle winding is reversed so that the
//!   geometric normal keeps pointing to the side of the transformed vertex normals (the side
//!   Mitsuba shades and emits from for meshes with normals, and the side its analytic
//!   `rectangle`/`disk` consider the front). For meshes *without* vertex normals Mitsuba itself
//!   takes the normal from the transformed triangle, so there a mirrored emitter would emit to
//!   the other side in Mitsuba;
//! - `max_depth` counts path segments (−1 = unlimited); `rr_depth` (default 5) is kept in
//!   [`RenderSettings::rr_depth`](crate::RenderSettings::rr_depth) for the path tracer's
//!   Russian roulette;
//! - spectra become linear sRGB as in Mitsuba's RGB variants (`colour`); emitters given by a
//!   tabulated, constant or blackbody spectrum also keep it
//!   ([`SceneDescription::emission_spectra`]) for spectral rendering;
//! - `<bsdf type="fluorescent">` is our extension (see `bsdf.rs`);
//!
//! Unknown elements, plugin types, missing required properties, wrong property types, bad
//! numbers, undefined parameters and references, include cycles and missing files are errors
//! with `file:line:column`; unsupported optional properties of known plugins are warnings in
//! [`SceneDescription::warnings`].

mod bsdf;
mod colour;
mod emitter;
mod hair;
mod mask;
mod medium;
mod principled;
mod props;
mod search;
mod sensor;
mod shape;
mod textured;
mod transform;
mod volume;
mod xml;

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use scene::Texture;
use scene::desc::{
    CameraDesc, EmissionSpectra, FilmDesc, InstanceDesc, LightDesc, ObjectDesc, SceneDescription, ShapeDesc,
    TextureImage,
};
use scene::material::Material;
use spectrum::Rgb;

use crate::options::{LoadOptions, LoadedScene, RenderSettings};
use crate::scene_error::SceneError;
use emitter::AreaEmission;
use xml::Node;

pub use colour_api::*;

/// Colour conversions exposed for tests and other loaders.
mod colour_api {
    /// Linear sRGB of a tabulated spectrum (wavelengths in nm, strictly increasing) as
    /// Mitsuba's RGB variants compute it for a reflectance (`emitter = false`: D65-weighted,
    /// a constant spectrum `c` gives the grey `c`, clamped to [0, 1]) or an emitted quantity
    /// (`emitter = true`: equal-energy weighting normalised by `∫ȳ`, clamped to ≥ 0).
    pub fn tabulated_spectrum_to_rgb(spectrum: &[(f64, f64)], emitter: bool) -> [f64; 3] {
        let usage =
            if emitter { super::colour::SpectrumUse::Emission } else { super::colour::SpectrumUse::Reflectance };
        super::colour::spectrum_to_rgb(spectrum, usage).0
    }

    /// Mitsuba's XYZ → linear sRGB matrix applied to `xyz`.
    pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
        super::colour::xyz_to_srgb(xyz)
    }
}

/// Loads a Mitsuba 3 XML scene. `defines` are `name=value` pairs that override the file's
/// `<default>` parameters (the `-D` option of the command line). Strict (see [`load_with`]).
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<SceneDescription, SceneError> {
    load_with(path, defines, &LoadOptions::default()).map(|loaded| loaded.description)
}

/// Loads a Mitsuba 3 XML scene with `options` and returns the file's rendering settings
/// (`<sampler>` `sample_count`, integrator `hide_emitters` and `rr_depth`) too.
pub fn load_with(path: &Path, defines: &[(String, String)], options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let mut warnings = Vec::new();
    let parsed = xml::parse_scene(path, defines, &mut warnings)?;
    let mut loader = Loader::new(parsed.search.clone(), warnings, options.permissive);
    for node in &parsed.elements {
        loader.collect_ids(node)?;
    }
    for node in &parsed.elements {
        loader.top_level(node)?;
    }
    let mut settings = loader.settings;
    // Mitsuba's path integrators start their roulette at bounce 5 unless told otherwise.
    settings.rr_depth.get_or_insert(sensor::MITSUBA_RR_DEPTH);
    Ok(LoadedScene { description: loader.finish(path)?, settings })
}

/// A resolved `<ref>` target.
#[derive(Clone)]
pub(crate) enum Resolved {
    Bsdf(mask::Masked),
    Texture(Texture),
    /// An area emitter's radiance (and spectrum).
    AreaEmitter(AreaEmission),
    /// Any other object (named by its tag) that cannot be referenced here.
    Other(String),
}

impl Resolved {
    pub(crate) fn kind(&self) -> String {
        match self {
            Resolved::Bsdf(_) => "bsdf".into(),
            Resolved::Texture(_) => "texture".into(),
            Resolved::AreaEmitter(_) => "area emitter".into(),
            Resolved::Other(tag) => tag.clone(),
        }
    }
}

pub(crate) struct Loader<'a> {
    search: search::SearchPath,
    pub(crate) warnings: Vec<String>,
    ids: HashMap<String, &'a Node>,
    resolved: HashMap<String, Resolved>,
    resolving: Vec<String>,
    materials: Vec<Material>,
    material_of_id: HashMap<String, u32>,
    /// The opacity of each material index that came from a `mask` (see `mask.rs`).
    material_opacity: HashMap<u32, Texture>,
    default_material: Option<u32>,
    shapes: Vec<ShapeDesc>,
    /// Shape groups (`shapegroup`) built so far, and their indices by id.
    objects: Vec<ObjectDesc>,
    object_of_id: HashMap<String, u32>,
    instances: Vec<InstanceDesc>,
    lights: Vec<LightDesc>,
    emission_spectra: EmissionSpectra,
    attached_emitters: HashSet<String>,
    images: HashMap<(PathBuf, bool), Arc<TextureImage>>,
    camera: Option<(CameraDesc, FilmDesc)>,
    max_path_length: Option<u32>,
    integrator_seen: bool,
    /// The file's sample count and `hide_emitters`.
    pub(crate) settings: RenderSettings,
    /// Unsupported image-changing parameters are warnings instead of errors.
    permissive: bool,
    /// Media, interfaces, the sensor's medium and `null` materials (see `medium.rs`).
    media: scene::medium::MediaDesc,
    medium_of_id: HashMap<String, u32>,
    /// Inside a `shapegroup` (where media are not supported).
    in_shapegroup: bool,
}

impl<'a> Loader<'a> {
    fn new(search: search::SearchPath, warnings: Vec<String>, permissive: bool) -> Self {
        Loader {
            search,
            warnings,
            ids: HashMap::new(),
            resolved: HashMap::new(),
            resolving: Vec::new(),
            materials: Vec::new(),
            material_of_id: HashMap::new(),
            material_opacity: HashMap::new(),
            default_material: None,
            shapes: Vec::new(),
            objects: Vec::new(),
            object_of_id: HashMap::new(),
            instances: Vec::new(),
            lights: Vec::new(),
            emission_spectra: EmissionSpectra::default(),
            attached_emitters: HashSet::new(),
            images: HashMap::new(),
            camera: None,
            max_path_length: None,
            integrator_seen: false,
            settings: RenderSettings::default(),
            permissive,
            media: Default::default(),
            medium_of_id: HashMap::new(),
            in_shapegroup: false,
        }
    }

    /// Something in the file the renderer cannot reproduce: an error, or a warning saying what
    /// is done `instead` when the load is permissive.
    pub(crate) fn unsupported(&mut self, error: SceneError, instead: &str) -> Result<(), SceneError> {
        crate::options::unsupported(self.permissive, &mut self.warnings, error, instead)
    }

    /// Registers every object with an `id`, at any depth.
    fn collect_ids(&mut self, node: &'a Node) -> Result<(), SceneError> {
        if node.tag != "ref"
            && let Some(id) = node.attr("id")
        {
            if let Some(first) = self.ids.get(id) {
                return Err(node.pos.error(format!("id '{id}' is defined twice (first at {})", first.pos.location())));
            }
            self.ids.insert(id.to_string(), node);
        }
        for child in &node.children {
            self.collect_ids(child)?;
        }
        Ok(())
    }

    /// The object with id `id`, referenced from `from`.
    pub(crate) fn resolve(&mut self, id: &str, from: &Node) -> Result<Resolved, SceneError> {
        if let Some(r) = self.resolved.get(id) {
            return Ok(r.clone());
        }
        if self.resolving.iter().any(|r| r == id) {
            return Err(from.pos.error(format!("reference cycle through id '{id}'")));
        }
        let Some(&node) = self.ids.get(id) else {
            return Err(from.pos.error(format!("<ref>: unknown id '{id}'")));
        };
        self.resolving.push(id.to_string());
        let result = match node.tag.as_str() {
            "bsdf" => self.bsdf(node).map(Resolved::Bsdf),
            "texture" => self.texture(node).map(Resolved::Texture),
            "emitter" if node.attr("type") == Some("area") => self.area_emitter(node).map(Resolved::AreaEmitter),
            other => Ok(Resolved::Other(other.to_string())),
        };
        self.resolving.pop();
        let result = result?;
        self.resolved.insert(id.to_string(), result.clone());
        Ok(result)
    }

    /// A file named in the scene, looked up along the [`search::SearchPath`]; not found is an
    /// error at `node` listing every path searched.
    pub(crate) fn resolve_file(&self, filename: &str, node: &Node) -> Result<PathBuf, SceneError> {
        self.search.find(filename, &node.pos.file).map_err(|e| node.pos.error(e))
    }

    /// The material index of the bsdf with id `id`.
    pub(crate) fn material_for_id(&mut self, id: &str, from: &Node) -> Result<u32, SceneError> {
        if let Some(&i) = self.material_of_id.get(id) {
            return Ok(i);
        }
        match self.resolve(id, from)? {
            Resolved::Bsdf(m) => {
                let i = self.push_masked(m);
                self.material_of_id.insert(id.to_string(), i);
                Ok(i)
            }
            other => Err(from.pos.error(format!("id '{id}' is a {}, expected a bsdf", other.kind()))),
        }
    }

    /// The material index of an inline `<bsdf>`.
    pub(crate) fn material_for_node(&mut self, node: &'a Node) -> Result<u32, SceneError> {
        if let Some(id) = node.attr("id") {
            return self.material_for_id(id, node);
        }
        let m = self.bsdf(node)?;
        Ok(self.push_masked(m))
    }

    /// Adds a material, remembering its opacity when it came from a mask.
    fn push_masked(&mut self, m: mask::Masked) -> u32 {
        let i = self.push_material(m.material);
        if let Some(opacity) = m.opacity {
            self.material_opacity.insert(i, opacity);
        }
        i
    }

    /// Mitsuba's default BSDF: diffuse with reflectance 0.5.
    pub(crate) fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        let i = self.push_material(Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) });
        self.default_material = Some(i);
        i
    }

    fn push_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    fn top_level(&mut self, node: &'a Node) -> Result<(), SceneError> {
        match node.tag.as_str() {
            "integrator" => self.integrator(node),
            "sensor" => {
                let camera = self.sensor(node)?;
                if self.camera.is_some() {
                    self.warnings
                        .push(format!("{}: second <sensor> ignored (the first one is used)", node.pos.location()));
                } else {
                    self.camera = Some(camera);
                }
                Ok(())
            }
            "bsdf" if node.attr("type") == Some("null") => Ok(()),
            "bsdf" | "texture" => {
                match node.attr("id") {
                    Some(id) => {
                        self.resolve(id, node)?;
                    }
                    None => {
                        if node.tag == "bsdf" {
                            self.bsdf(node)?;
                        } else {
                            self.texture(node)?;
                        }
                        self.warnings.push(format!(
                            "{}: top-level <{}> without an id is unused",
                            node.pos.location(),
                            node.tag
                        ));
                    }
                }
                Ok(())
            }
            "shape" => self.shape(node),
            "emitter" => {
                if node.required_attr("type")? == "area" {
                    match node.attr("id") {
                        Some(id) => self.resolve(id, node).map(|_| ()),
                        None => Err(node.pos.error("an area emitter must be inside a <shape> or have an id")),
                    }
                } else {
                    self.light(node)
                }
            }
            "ref" => Err(node.pos.error("<ref> is not allowed at the top level")),
            "medium" => self.medium_index(node).map(|_| ()),
            "phase" | "volume" => Err(node.pos.error(format!("<{}> must be inside a <medium>", node.tag))),
            "sampler" => self.sampler(node),
            "film" if node.attr("type") == Some("ldrfilm") => Err(node.pos.error(xml::old_format("film 'ldrfilm'"))),
            "film" | "rfilter" => Err(node.pos.error(format!("<{}> must be inside a <sensor>", node.tag))),
            other => Err(node.pos.error(format!("unknown element <{other}>"))),
        }
    }

    fn finish(mut self, path: &Path) -> Result<SceneDescription, SceneError> {
        let mut unattached: Vec<String> = self
            .ids
            .iter()
            .filter(|(id, node)| {
                node.tag == "emitter" && node.attr("type") == Some("area") && !self.attached_emitters.contains(*id)
            })
            .map(|(id, node)| format!("{}: area emitter '{id}' is not attached to any shape", node.pos.location()))
            .collect();
        unattached.sort();
        self.warnings.extend(unattached);
        let (camera, film) = match self.camera {
            Some(c) => c,
            None => {
                self.warnings.push(format!(
                    "{}: no <sensor>; using Mitsuba's default (perspective, 45° fov, 768×576)",
                    path.display()
                ));
                sensor::default_sensor()
            }
        };
        let mut seen = HashSet::new();
        self.warnings.retain(|w| seen.insert(w.clone()));
        Ok(SceneDescription {
            name: path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            camera,
            film,
            materials: self.materials,
            shapes: self.shapes,
            lights: self.lights,
            max_path_length: self.max_path_length,
            warnings: self.warnings,
            emission_spectra: self.emission_spectra,
            objects: self.objects,
            instances: self.instances,
            media: self.media,
        })
    }
}
