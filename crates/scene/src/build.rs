//! Turning a [`SceneDescription`] (what a file loader produces) into a renderable [`Scene`].

use crate::alpha::AlphaMask;
use crate::camera::Camera;
use crate::desc::{
    EmissionSpectrum, Geometry, LightDesc, MeshAttribute, MeshData, SceneDescription, ShapeDesc, SpotTexture,
};
use crate::filter::Filter;
use crate::instance::{Instance, Object};
use crate::light::{AreaLight, Light, TexturedTriangleLight};
use crate::material::Material;
use crate::scene::{LightSpectrum, Primitive, Scene, SurfaceAttributes};
use crate::shape::{Disk, Shape, Sphere, Triangle};
use crate::texture::Texture;
use std::sync::Arc;

/// What [`Scene::from_description`] built, for the user's summary line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildReport {
    /// Triangles in the scene.
    pub triangles: usize,
    /// Analytic spheres and discs.
    pub analytic_shapes: usize,
    /// Degenerate triangles (zero area or non-finite) that were dropped.
    pub degenerate_triangles: usize,
    /// Lights, area emitters counted per triangle.
    pub lights: usize,
}

impl Scene {
    /// Builds the scene of a description, rendered at `resolution` (width, height) when given,
    /// at the film's resolution otherwise. Errors name the shape or light at fault. Emission
    /// spectra of [`SceneDescription::emission_spectra`] go to every light built from their
    /// shape or light; fluorescent materials must not re-absorb fluorescent emission
    /// ([`check_fluorescent_bands`]).
    pub fn from_description(
        desc: &SceneDescription,
        resolution: Option<(u32, u32)>,
    ) -> Result<(Scene, BuildReport), String> {
        let (width, height) = resolution.unwrap_or((desc.film.width, desc.film.height));
        if width == 0 || height == 0 {
            return Err(format!("the film has no pixels ({width}×{height})"));
        }
        let mut parts = Parts::default();
        for (index, material) in desc.materials.iter().enumerate() {
            material.validate().map_err(|e| format!("material {index}: {e}"))?;
            let attribute = material.mesh_attribute().map_err(|e| format!("material {index}: {e}"))?;
            parts.material_attributes.push(attribute.map(str::to_owned));
        }
        check_fluorescent_bands(&desc.materials)?;
        let spectra = &desc.emission_spectra;
        if let Some(&index) = spectra.shapes.keys().find(|&&i| i as usize >= desc.shapes.len()) {
            return Err(format!("an emission spectrum refers to shape {index} of {}", desc.shapes.len()));
        }
        if let Some(&index) = spectra.lights.keys().find(|&&i| i as usize >= desc.lights.len()) {
            return Err(format!("an emission spectrum refers to light {index} of {}", desc.lights.len()));
        }
        // The primitives in one allocation made up front (at most one per triangle, sphere or
        // disc). Grown by pushes, about half of a 1M-triangle mesh's records lay on 4 KiB pages
        // although the heap asks for huge ones (docs/bvh.md, "Primitive records in one
        // allocation").
        let most_primitives = desc.shapes.iter().map(|s| match &s.geometry {
            Geometry::Mesh(mesh) => mesh.triangles.len(),
            Geometry::Sphere { .. } | Geometry::Disk { .. } => 1,
        });
        parts.primitives = Vec::with_capacity(most_primitives.sum());
        let mut shape_primitives = Vec::with_capacity(desc.shapes.len());
        for (shape_index, shape) in desc.shapes.iter().enumerate() {
            let index = shape_index as u32;
            let first = parts.primitives.len();
            parts.add_shape(shape, spectra.shapes.get(&index), spectra.textures.get(&index), desc.materials.len())?;
            shape_primitives.push(first..parts.primitives.len());
        }
        let primitives = std::mem::take(&mut parts.primitives);
        let (objects, instances) = build_instances(desc, &mut parts)?;
        let media = crate::medium::build::media(&desc.media, &shape_primitives, primitives.len(), desc)?;
        let Parts { attributes, alpha_masks, mut lights, mut light_spectra, mut light_groups, mut report, .. } = parts;
        let mut environments = 0;
        for (index, light) in desc.lights.iter().enumerate() {
            if let LightDesc::Spot { texture: Some(SpotTexture { texture: t, .. }), .. }
            | LightDesc::Projector { irradiance: t, .. } = light
                && let Some(name) = t.mesh_attribute()
            {
                return Err(format!("light {index}: a light's texture cannot read the mesh attribute `{name}`"));
            }
            if matches!(light, LightDesc::Constant { .. } | LightDesc::EnvMap { .. }) {
                environments += 1;
            }
            light_groups.push(lights.len() as u32);
            lights.push(Light::from_desc(light).map_err(|e| format!("light {index}: {e}"))?);
            light_spectra.push(match spectra.lights.get(&(index as u32)) {
                Some(s) => Some(light_spectrum(light, s).map_err(|e| format!("light {index}: {e}"))?),
                None => None,
            });
        }
        if environments > 1 {
            return Err(format!("{environments} environment lights; at most one is supported"));
        }
        report.lights = lights.len();
        let filter = Filter::from_desc(&desc.film.filter)?;
        // Scene files name a reconstruction filter (Mitsuba's hdrfilm defaults to a gaussian):
        // their pixels splat like Mitsuba's and pbrt's films (`--film` overrides it).
        let camera = Camera::from_desc(&desc.camera, width, height)?
            .with_filter(filter)
            .with_film(crate::filter::FilmMode::Splat);
        let scene = Scene::with_instances(
            desc.name.clone(),
            primitives,
            objects,
            instances,
            desc.materials.clone(),
            lights,
            camera,
        )
        .with_attributes(attributes)
        .with_alpha_masks(alpha_masks)
        .with_media(media)
        .with_light_spectra(if light_spectra.iter().any(Option::is_some) { light_spectra } else { Vec::new() })
        .with_light_groups(&light_groups)?;
        Ok((scene, report))
    }
}

/// The objects of a description (each with its own BVH) and their instances. Object shapes
/// must not emit (Mitsuba 3 refuses emitters in a `shapegroup`, pbrt-v4 area lights in an
/// object); their attributes go to `parts`, and their triangles count in its report once per
/// object, not per instance.
fn build_instances(desc: &SceneDescription, parts: &mut Parts) -> Result<(Vec<Object>, Vec<Instance>), String> {
    let mut objects = Vec::with_capacity(desc.objects.len());
    for object in &desc.objects {
        for shape in &object.shapes {
            if shape.emission.is_some_and(|e| !e.is_black()) {
                return Err(format!(
                    "shape '{}' in object '{}' emits light: instanced emitters are not supported (Mitsuba 3 \
                     does not allow emitters in a shapegroup either)",
                    shape.name, object.name
                ));
            }
            parts.add_shape(shape, None, None, desc.materials.len())?;
        }
        let primitives = std::mem::take(&mut parts.primitives);
        objects.push(Object::new(object.name.clone(), primitives)?);
    }
    let instances = desc
        .instances
        .iter()
        .map(|instance| {
            if instance.object as usize >= objects.len() {
                return Err(format!(
                    "instance '{}' refers to object {} of {}",
                    instance.name,
                    instance.object,
                    objects.len()
                ));
            }
            Instance::new(instance.object, instance.to_world)
                .ok_or_else(|| format!("instance '{}': the transform is singular or not finite", instance.name))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok((objects, instances))
}

/// What the shapes of a description turn into: primitives (of the world or of one object),
/// their attributes, and the area lights.
#[derive(Default)]
struct Parts {
    primitives: Vec<Primitive>,
    attributes: Vec<SurfaceAttributes>,
    alpha_masks: Vec<AlphaMask>,
    lights: Vec<Light>,
    light_spectra: Vec<Option<LightSpectrum>>,
    /// By light: the emitter it belongs to (the index of that emitter's first light), for
    /// light selection ([`Scene::with_light_groups`]).
    light_groups: Vec<u32>,
    report: BuildReport,
    /// The mesh attribute each material reads, by material index.
    material_attributes: Vec<Option<String>>,
}

impl Parts {
    /// Adds the primitives of `shape` (and its area lights, with emission `spectrum`), checking
    /// its material index against `material_count`.
    fn add_shape(
        &mut self,
        shape: &ShapeDesc,
        spectrum: Option<&EmissionSpectrum>,
        texture: Option<&Arc<Texture>>,
        material_count: usize,
    ) -> Result<(), String> {
        if shape.material as usize >= material_count {
            return Err(format!("shape '{}' refers to material {} of {}", shape.name, shape.material, material_count));
        }
        let emission = shape.emission.filter(|e| !e.is_black());
        if let Some(e) = emission
            && (!e.is_finite() || e.r < 0.0 || e.g < 0.0 || e.b < 0.0)
        {
            return Err(format!("shape '{}' emits an invalid radiance {:?}", shape.name, e.to_array()));
        }
        if let Some(s) = spectrum {
            s.validate().map_err(|e| format!("shape '{}': {e}", shape.name))?;
        }
        let spectrum = emission.zip(spectrum).map(|(base, s)| LightSpectrum { spectrum: s.clone(), base });
        if let Some(texture) = texture {
            if spectrum.is_some() {
                return Err(format!("shape '{}': a textured emitter cannot have an emission spectrum", shape.name));
            }
            if shape.emission.is_none() {
                return Err(format!("shape '{}' has an emission texture but does not emit", shape.name));
            }
            if !matches!(shape.geometry, Geometry::Mesh(_)) {
                return Err(format!("shape '{}': textured emission is supported on triangle meshes only", shape.name));
            }
            if let Some(name) = texture.mesh_attribute() {
                return Err(format!(
                    "shape '{}': an emission texture cannot read the mesh attribute `{name}`",
                    shape.name
                ));
            }
            if !texture.max_value().is_finite() {
                return Err(format!("shape '{}': the emission texture has non-finite values", shape.name));
            }
        }
        let alpha = self.alpha_mask(shape, spectrum.is_some())?;
        // The mask an emitting mesh samples its points by (masked emitters).
        let emission_mask =
            alpha.filter(|_| emission.is_some()).map(|i| Arc::new(self.alpha_masks[i as usize].clone()));
        let constant_emission = emission.map(|radiance| Arc::new(Texture::Constant(radiance)));
        let first_primitive = self.primitives.len();
        let first_light = self.lights.len() as u32;
        let attribute_name = self.material_attributes.get(shape.material as usize).and_then(Option::as_deref);
        match &shape.geometry {
            Geometry::Mesh(mesh) => {
                mesh.validate().map_err(|e| format!("mesh '{}': {e}", shape.name))?;
                let attribute = match attribute_name {
                    Some(name) => Some(find_attribute(mesh, name).map_err(|e| format!("shape '{}': {e}", shape.name))?),
                    None => None,
                };
                // A constant emitter on two triangles that tile a parallelogram (Mitsuba's
                // `rectangle`) is one light: its points are sampled on the whole parallelogram,
                // so light selection has one light fewer to choose from.
                let parallelogram = match (emission, texture, &emission_mask) {
                    (Some(radiance), None, None) if mesh.triangles.len() == 2 => {
                        let pair: Vec<Option<Triangle>> = mesh_triangles(mesh, None).map(|(t, _)| t).collect();
                        pair[0]
                            .zip(pair[1])
                            .and_then(|(a, b)| AreaLight::parallelogram_of(&a, &b))
                            .and_then(|(origin, u, v, n)| AreaLight::parallelogram(origin, u, v, n, radiance).ok())
                    }
                    _ => None,
                };
                let parallelogram = parallelogram.map(|light| self.push_light(Light::Area(light), spectrum.clone()));
                for (triangle, extra) in mesh_triangles(mesh, attribute) {
                    let Some(triangle) = triangle else {
                        self.report.degenerate_triangles += 1;
                        continue;
                    };
                    let uvs = match &extra {
                        Some(SurfaceAttributes::Triangle { uvs: Some(uvs), .. }) => *uvs,
                        _ => [math::Vec2::ZERO; 3],
                    };
                    let light = match (texture.or(constant_emission.as_ref()), &emission_mask) {
                        // A masked triangle emits where its mask is on (nothing if it is off everywhere).
                        (Some(texture), Some(mask)) => {
                            TexturedTriangleLight::masked(triangle, uvs, texture.clone(), mask.clone())
                                .map(|light| self.push_light(Light::TexturedTriangle(light), None))
                        }
                        _ => match texture {
                            // A textured triangle that is black everywhere does not emit.
                            Some(texture) => TexturedTriangleLight::new(triangle, uvs, texture.clone())
                                .map(|light| self.push_light(Light::TexturedTriangle(light), None)),
                            None if parallelogram.is_some() => parallelogram,
                            None => emission.map(|radiance| {
                                self.push_light(Light::Area(AreaLight::new(triangle, radiance)), spectrum.clone())
                            }),
                        },
                    };
                    let mut primitive = Primitive::new(Shape::Triangle(triangle), shape.material, light);
                    if let Some(extra) = extra {
                        primitive.attributes = self.attributes.len() as u32;
                        self.attributes.push(extra);
                    }
                    self.primitives.push(primitive);
                    self.report.triangles += 1;
                }
            }
            _ if attribute_name.is_some() => {
                return Err(format!(
                    "shape '{}' is not a triangle mesh, but its material reads the mesh attribute `{}`",
                    shape.name,
                    attribute_name.unwrap_or_default()
                ));
            }
            Geometry::Sphere { center, radius, flip_normals } => {
                if !(*radius > 0.0 && radius.is_finite() && center.is_finite()) {
                    return Err(format!("sphere '{}' has radius {radius} at {center}", shape.name));
                }
                let light = match emission {
                    Some(radiance) => {
                        let light = AreaLight::sphere(*center, *radius, *flip_normals, radiance)
                            .map_err(|e| format!("sphere '{}': {e}", shape.name))?;
                        Some(self.push_light(Light::Area(light), spectrum.clone()))
                    }
                    None => None,
                };
                let mut primitive =
                    Primitive::new(Shape::Sphere(Sphere { center: *center, radius: *radius }), shape.material, light);
                if *flip_normals {
                    primitive.attributes = self.attributes.len() as u32;
                    self.attributes.push(SurfaceAttributes::FlippedNormal);
                }
                self.primitives.push(primitive);
                self.report.analytic_shapes += 1;
            }
            Geometry::Disk { center, axis_u, axis_v, flip_normals } => {
                let disk = Disk::new(*center, *axis_u, *axis_v, *flip_normals)
                    .ok_or_else(|| format!("disk '{}' is degenerate", shape.name))?;
                let light = match emission {
                    Some(radiance) => {
                        let light = AreaLight::disc(*center, *axis_u, *axis_v, *flip_normals, radiance)
                            .map_err(|e| format!("disk '{}': {e}", shape.name))?;
                        Some(self.push_light(Light::Area(light), spectrum.clone()))
                    }
                    None => None,
                };
                self.primitives.push(Primitive::new(Shape::Disk(disk), shape.material, light));
                self.report.analytic_shapes += 1;
            }
        }
        for primitive in &mut self.primitives[first_primitive..] {
            primitive.alpha = alpha;
        }
        // All lights of this shape form one emitter.
        self.light_groups.resize(self.lights.len(), first_light);
        Ok(())
    }

    /// Adds `light` with its emission spectrum (`None`: its RGB value) and returns its index.
    fn push_light(&mut self, light: Light, spectrum: Option<LightSpectrum>) -> u32 {
        self.lights.push(light);
        self.light_spectra.push(spectrum);
        self.lights.len() as u32 - 1
    }

    /// The index of the alpha mask of `shape` in `alpha_masks` (added there), or `None` when
    /// the shape has none or its opacity is 1 everywhere. Errors when the texture has
    /// non-finite values, or the shape emits (with emission `spectrum`, when `true`) and is not
    /// a triangle mesh or has an emission spectrum: masked emitters are masked textured
    /// triangles ([`TexturedTriangleLight::masked`]).
    fn alpha_mask(&mut self, shape: &ShapeDesc, spectrum: bool) -> Result<Option<u32>, String> {
        let Some(texture) = &shape.alpha else { return Ok(None) };
        let max = texture.max_value();
        if !(max.r.is_finite() && max.g.is_finite() && max.b.is_finite()) {
            return Err(format!("shape '{}': the alpha texture has non-finite values", shape.name));
        }
        let mask = AlphaMask::new(texture.clone());
        if mask.constant_opacity() == Some(1.0) {
            return Ok(None);
        }
        if shape.emission.is_some_and(|e| !e.is_black()) {
            if !matches!(shape.geometry, Geometry::Mesh(_)) {
                return Err(format!(
                    "shape '{}' emits light and has an alpha mask: masked emitters are supported on \
                     triangle meshes only",
                    shape.name
                ));
            }
            if spectrum {
                return Err(format!(
                    "shape '{}' emits light and has an alpha mask: a masked emitter cannot have an emission \
                     spectrum",
                    shape.name
                ));
            }
        }
        self.alpha_masks.push(mask);
        Ok(Some(self.alpha_masks.len() as u32 - 1))
    }
}

/// The spectrum of a light that is not attached to a shape, with the light's RGB value as its
/// base. Image environments vary over directions and cannot carry one spectrum.
fn light_spectrum(light: &LightDesc, spectrum: &EmissionSpectrum) -> Result<LightSpectrum, String> {
    spectrum.validate()?;
    let base = match light {
        LightDesc::Spot { texture: Some(_), .. } => {
            return Err("a textured spot light cannot have an emission spectrum".into());
        }
        LightDesc::Point { intensity, .. }
        | LightDesc::Spot { intensity, .. }
        | LightDesc::Goniometric { intensity, .. } => *intensity,
        LightDesc::Projector { .. } => return Err("a projector cannot have an emission spectrum".into()),
        LightDesc::Directional { irradiance, .. } => *irradiance,
        LightDesc::Constant { radiance } => *radiance,
        LightDesc::EnvMap { .. } => return Err("an image environment cannot have an emission spectrum".into()),
    };
    Ok(LightSpectrum { spectrum: spectrum.clone(), base })
}

/// Fails when the emission band of a fluorescent material overlaps the absorption band of a
/// fluorescent material (itself or another): light re-emitted by one could then be shifted
/// again, which the integrators do not handle (a path has at most one wavelength shift).
pub fn check_fluorescent_bands(materials: &[Material]) -> Result<(), String> {
    let fluorescent: Vec<(usize, &spectrum::fluorescence::Fluorescence)> =
        materials.iter().enumerate().filter_map(|(i, m)| m.fluorescence().map(|f| (i, f))).collect();
    for &(i, emitter) in &fluorescent {
        for &(j, absorber) in &fluorescent {
            if emitter.emission.overlaps(&absorber.absorption) {
                let (e0, e1) = emitter.emission.support();
                let (a0, a1) = absorber.absorption.support();
                return Err(format!(
                    "material {i} re-emits at {e0:.0}–{e1:.0} nm, which overlaps the absorption band \
                     {a0:.0}–{a1:.0} nm of fluorescent material {j}: light would be shifted twice"
                ));
            }
        }
    }
    Ok(())
}

/// The mesh attribute `name` of `mesh`; the error lists the attributes the mesh has.
fn find_attribute<'m>(mesh: &'m MeshData, name: &str) -> Result<&'m MeshAttribute, String> {
    mesh.attributes.iter().find(|a| a.name == name).ok_or_else(|| {
        let names: Vec<String> = mesh.attributes.iter().map(|a| format!("`{}`", a.name)).collect();
        format!(
            "its material reads the mesh attribute `{name}`, but the mesh has {}",
            if names.is_empty() { "no attributes".to_owned() } else { format!("only {}", names.join(", ")) }
        )
    })
}

/// The triangles of a mesh (`None` for degenerate ones) with their vertex attributes (and the
/// values of the mesh attribute `attribute`, if given). When the mesh has shading normals, a
/// triangle whose winding disagrees with them is turned around, so that its geometric normal
/// (which decides the emitting side and one-sided materials) lies on the side of its shading
/// normals, as Mitsuba orients it.
fn mesh_triangles<'m>(
    mesh: &'m MeshData,
    attribute: Option<&'m MeshAttribute>,
) -> impl Iterator<Item = (Option<Triangle>, Option<SurfaceAttributes>)> + 'm {
    mesh.triangles.iter().enumerate().map(move |(face, &[a, b, c])| {
        let mut index = [a as usize, b as usize, c as usize];
        let p = |i: usize| mesh.positions[i];
        let mut triangle = Triangle::new(p(index[0]), p(index[1]), p(index[2]));
        if triangle.area().is_nan() || triangle.area() <= 0.0 || !triangle.normal.is_finite() {
            return (None, None);
        }
        let normals = (!mesh.normals.is_empty()).then(|| index.map(|i| mesh.normals[i]));
        if let Some(n) = normals
            && (n[0] + n[1] + n[2]).dot(triangle.normal) < 0.0
        {
            index.swap(1, 2);
            triangle = Triangle::new(p(index[0]), p(index[1]), p(index[2]));
        }
        let normals = (!mesh.normals.is_empty()).then(|| index.map(|i| mesh.normals[i]));
        let uvs = (!mesh.uvs.is_empty()).then(|| index.map(|i| mesh.uvs[i]));
        let attribute = attribute.map(|a| if a.per_face() { [a.values[face]; 3] } else { index.map(|i| a.values[i]) });
        let extra = (normals.is_some() || uvs.is_some() || attribute.is_some())
            .then_some(SurfaceAttributes::Triangle { normals, uvs, attribute });
        (Some(triangle), extra)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::{CameraDesc, FilmDesc, FilterDesc, Projection, ShapeDesc};
    use crate::material::Material;
    use crate::texture::Texture;
    use math::{Vec2, Vec3};
    use spectrum::Rgb;

    fn description(materials: Vec<Material>, shapes: Vec<ShapeDesc>) -> SceneDescription {
        SceneDescription {
            name: "test".into(),
            camera: CameraDesc {
                position: Vec3::new(0.0, 0.0, 5.0),
                forward: -Vec3::Z,
                up: Vec3::Y,
                right: Vec3::X,
                projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
            },
            film: FilmDesc { width: 8, height: 6, filter: FilterDesc::Box },
            materials,
            shapes,
            lights: Vec::new(),
            max_path_length: Some(5),
            warnings: Vec::new(),
            emission_spectra: Default::default(),
            objects: Vec::new(),
            instances: Vec::new(),
            media: Default::default(),
        }
    }

    fn diffuse() -> Material {
        Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }
    }

    #[test]
    fn meshes_lights_and_attributes() {
        // A quad whose winding points down (−z) but whose vertex normals point up (+z): it is
        // turned around, and it emits upwards.
        let mesh = MeshData {
            positions: vec![
                Vec3::new(-1., -1., 0.),
                Vec3::new(1., -1., 0.),
                Vec3::new(1., 1., 0.),
                Vec3::new(-1., 1., 0.),
            ],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::new(0., 0.), Vec2::new(1., 0.), Vec2::new(1., 1.), Vec2::new(0., 1.)],
            triangles: vec![[0, 2, 1], [0, 3, 2], [0, 0, 1]],
            attributes: Vec::new(),
        };
        let shapes = vec![ShapeDesc {
            name: "quad".into(),
            geometry: Geometry::Mesh(mesh),
            material: 0,
            emission: Some(Rgb::splat(2.0)),
            alpha: None,
        }];
        let (scene, report) = Scene::from_description(&description(vec![diffuse()], shapes), None).unwrap();
        assert_eq!((report.triangles, report.degenerate_triangles, report.lights), (2, 1, 2));
        assert_eq!((scene.camera.width, scene.camera.height), (8, 6));
        let ray = math::Ray::new(Vec3::new(0.3, 0.2, 1.0), -Vec3::Z);
        let hit = scene.intersect(&ray).unwrap();
        assert!((hit.normal - Vec3::Z).length() < 1e-6, "turned to the vertex normals: {}", hit.normal);
        assert!((hit.uv - Vec2::new(0.65, 0.6)).length() < 1e-5, "interpolated uv {}", hit.uv);
        let light = &scene.lights[hit.light.unwrap() as usize];
        assert!(
            light.radiance_on_hit(ray.direction, hit.position, hit.normal, &scene.bounding_sphere).is_some(),
            "emits upwards"
        );
        // Equal areas: equal power, equal selection probability.
        assert!((scene.light_pick_probability(0) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn a_rectangle_emits_as_one_parallelogram_light() {
        // Mitsuba's rectangle: corners (±1, ±1, 0), triangles (0, 1, 2) and (2, 3, 0), facing +z.
        let positions =
            vec![Vec3::new(-1., -1., 0.), Vec3::new(1., -1., 0.), Vec3::new(1., 1., 0.), Vec3::new(-1., 1., 0.)];
        let quad = |triangles: Vec<[u32; 3]>, positions: Vec<Vec3>| ShapeDesc {
            name: "quad".into(),
            geometry: Geometry::Mesh(MeshData {
                positions,
                normals: Vec::new(),
                uvs: Vec::new(),
                triangles,
                attributes: Vec::new(),
            }),
            material: 0,
            emission: Some(Rgb::splat(2.0)),
            alpha: None,
        };
        let shapes = vec![quad(vec![[0, 1, 2], [2, 3, 0]], positions.clone())];
        let (scene, report) = Scene::from_description(&description(vec![diffuse()], shapes), None).unwrap();
        assert_eq!((report.triangles, report.lights), (2, 1));
        let Light::Area(light) = &scene.lights[0] else { panic!("an area light") };
        assert!((light.area() - 4.0).abs() < 1e-5 && light.triangle().is_none());
        // Both triangles are that light.
        for x in [-0.5, 0.5] {
            let ray = math::Ray::new(Vec3::new(x, 0.4 * x, 1.0), -Vec3::Z);
            let hit = scene.intersect(&ray).unwrap();
            assert_eq!(hit.light, Some(0));
            let seen = scene.lights[0].radiance_on_hit(ray.direction, hit.position, hit.normal, &scene.bounding_sphere);
            assert!((seen.unwrap().direct_pdf.0 - 0.25).abs() < 1e-6, "1/area of the whole rectangle");
        }
        // A kite (the fourth corner moved) keeps one light per triangle.
        let mut kite = positions;
        kite[3] = Vec3::new(-1.5, 1.2, 0.);
        let shapes = vec![quad(vec![[0, 1, 2], [2, 3, 0]], kite)];
        let (_, report) = Scene::from_description(&description(vec![diffuse()], shapes), None).unwrap();
        assert_eq!((report.triangles, report.lights), (2, 2));
    }

    #[test]
    fn bad_descriptions_are_errors() {
        let sphere = |radius: f32, material: u32| ShapeDesc {
            name: "ball".into(),
            geometry: Geometry::Sphere { center: Vec3::ZERO, radius, flip_normals: false },
            material,
            emission: None,
            alpha: None,
        };
        let err = |d: SceneDescription| Scene::from_description(&d, None).err().unwrap();
        assert!(err(description(vec![diffuse()], vec![sphere(-1.0, 0)])).contains("ball"));
        assert!(err(description(vec![diffuse()], vec![sphere(1.0, 3)])).contains("material 3"));
        let blend = |a: Material, b: Material| Material::Blend {
            weight: Texture::Constant(Rgb::splat(0.5)),
            first: Box::new(a),
            second: Box::new(b),
        };
        let four = blend(blend(diffuse(), diffuse()), blend(diffuse(), diffuse()));
        assert!(Scene::from_description(&description(vec![four.clone()], vec![sphere(1.0, 0)]), None).is_ok());
        let five = blend(four, diffuse());
        assert!(err(description(vec![five], vec![sphere(1.0, 0)])).contains("at most 4"));
        let mut no_pixels = description(vec![diffuse()], vec![]);
        no_pixels.film.width = 0;
        assert!(err(no_pixels).contains("no pixels"));
    }
}
