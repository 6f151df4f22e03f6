//! The scene container: primitives with their materials and emitters, instanced objects, the
//! lights, the camera, the bounding sphere and the BVH, with the two ray queries every
//! integrator uses.
//!
//! The BVH is two-level when the scene has instances: its leaves are the world primitives
//! (ids `0..primitives.len()`) and the instances (the ids after them), and an instance leaf
//! traces the object-space ray through its object's own BVH (see [`crate::instance`]).

use math::isa::{Isa, Kernel};
use math::{Aabb, Distribution1D, RAY_EPSILON, Ray, Vec2, Vec3};

use crate::accel::Bvh;
use crate::alpha::AlphaMask;
use crate::camera::Camera;
use crate::desc::EmissionSpectrum;
use crate::instance::{Instance, Object};
use crate::light::{BoundingSphere, Light};
use crate::light_selection::light_selection_weights;
use crate::light_tree::LightTree;
use crate::material::{Material, MaterialFlags, ShadingPoint, SurfaceTangents};
use crate::medium::Media;
use crate::shape::Shape;
use crate::tangent;
use spectrum::{Rgb, SpectralMode};

/// A shape with the index of its material and, if it emits, of its light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    /// Geometry.
    pub shape: Shape,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Index into [`Scene::lights`] when the primitive is an area emitter.
    pub light: Option<u32>,
    /// Index into [`Scene::attributes`], or [`NO_ATTRIBUTES`].
    pub attributes: u32,
    /// Index into [`Scene::alpha_masks`] when the surface has an alpha mask (hits where it is
    /// transparent are skipped, see [`crate::alpha`]).
    pub alpha: Option<u32>,
}

impl Primitive {
    /// A primitive without extra surface attributes.
    pub fn new(shape: Shape, material: u32, light: Option<u32>) -> Self {
        Self { shape, material, light, attributes: NO_ATTRIBUTES, alpha: None }
    }
}

/// [`Primitive::attributes`] of a primitive that has none.
pub const NO_ATTRIBUTES: u32 = u32::MAX;

/// Surface attributes beyond the geometry: per-vertex shading normals and texture coordinates
/// of mesh triangles, or the inward orientation of a sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceAttributes {
    /// Vertex attributes of a triangle, in the order of its vertices.
    Triangle {
        /// Unit shading normals at the vertices (interpolated and renormalised at a hit).
        normals: Option<[Vec3; 3]>,
        /// Texture coordinates at the vertices.
        uvs: Option<[Vec2; 3]>,
        /// Values at the vertices of the mesh attribute the triangle's material reads (all
        /// three equal for a face attribute).
        attribute: Option<[Rgb; 3]>,
    },
    /// The geometric normal points inward (a sphere with flipped normals).
    FlippedNormal,
}

/// A ray–surface intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Hit point.
    pub position: Vec3,
    /// Unit geometric normal (as stored: triangles by winding, spheres outward).
    pub normal: Vec3,
    /// Unit shading normal (interpolated vertex normals; the geometric normal otherwise).
    pub shading_normal: Vec3,
    /// Texture coordinates: a mesh's interpolated uvs ((0, 0) on a mesh without them); on a
    /// sphere or a disc its parameterisation when the material reads them
    /// ([`MaterialFlags::reads_uv`]), else (0, 0).
    pub uv: Vec2,
    /// ∂p/∂u (world space, not normalised) when the material is anisotropic
    /// ([`Material::is_anisotropic`]), else zero (see [`ShadingPoint::tangent`]).
    pub tangent: Vec3,
    /// The value of the mesh attribute the material reads (interpolated), black if none.
    pub attribute: Rgb,
    /// Distance along the ray from its origin.
    pub distance: f32,
    /// Index of the primitive hit: into [`Scene::primitives`], or for a hit on an instance into
    /// its object's [`Object::primitives`].
    pub primitive: u32,
    /// Material index.
    pub material: u32,
    /// Light index when the primitive emits.
    pub light: Option<u32>,
}

impl SurfaceHit {
    /// The local geometry a BSDF is built from.
    #[inline]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint {
            geometric_normal: self.normal,
            shading_normal: self.shading_normal,
            uv: self.uv,
            tangent: self.tangent,
            attribute: self.attribute,
        }
    }
}

/// A complete scene ready to render.
#[derive(Debug)]
pub struct Scene {
    /// Human-readable name.
    pub name: String,
    /// Geometry, in scene order (the order only matters for exact ties).
    pub primitives: Vec<Primitive>,
    /// Materials referenced by the primitives. Not to be changed after construction: the
    /// scene's [`MaterialFlags`] are made from them then.
    pub materials: Vec<Material>,
    /// Lights, in selection order.
    pub lights: Vec<Light>,
    /// The camera.
    pub camera: Camera,
    /// Bounding sphere of all primitives (spheres count as their bounding cubes).
    pub bounding_sphere: BoundingSphere,
    /// Index of the environment light, seen by rays that leave the scene.
    pub background: Option<u32>,
    /// Surface attributes referenced by [`Primitive::attributes`] (of world and object
    /// primitives alike).
    pub attributes: Vec<SurfaceAttributes>,
    /// Instanced geometry, each with its own BVH.
    pub objects: Vec<Object>,
    /// Placements of [`Scene::objects`].
    pub instances: Vec<Instance>,
    /// Alpha masks referenced by [`Primitive::alpha`] (of world and object primitives alike).
    pub alpha_masks: Vec<AlphaMask>,
    /// Participating media and index-matched boundaries ([`crate::medium`]); empty for
    /// surface-only scenes.
    pub media: Media,
    /// Emission spectra by light index (missing or `None`: the RGB value is upsampled).
    light_spectra: Vec<Option<LightSpectrum>>,
    /// Light selection ([`light_selection_weights`]; each light its own emitter unless
    /// [`Scene::with_light_groups`] said otherwise).
    light_selection: Option<Distribution1D>,
    /// The light tree ([`Scene::light_tree`]), built on first use.
    light_tree: std::sync::OnceLock<LightTree>,
    /// By material index: what hits need to know of the material ([`Scene::material_flags`]).
    flags: Vec<MaterialFlags>,
    /// By world primitive: its [`Primitive::attributes`], copied into an array of its own so
    /// that a hit can load it at once, beside the primitive's record, instead of after it (the
    /// two loads were dependent cache misses; see `docs/bvh.md`). `primitives` is not changed
    /// after construction.
    world_attributes: Vec<u32>,
    /// Our BVH over the world primitives and instances (empty when [`Scene::embree`] answers
    /// the queries).
    bvh: Bvh,
    /// The Embree backend when the scene qualifies for it (feature `embree`, see
    /// `crate::accel::embree`).
    #[cfg(feature = "embree")]
    embree: Option<crate::accel::EmbreeAccel>,
}

impl Scene {
    /// Builds the BVH and the bounding sphere. Light indices of primitives must be valid.
    pub fn new(
        name: impl Into<String>,
        primitives: Vec<Primitive>,
        materials: Vec<Material>,
        lights: Vec<Light>,
        camera: Camera,
    ) -> Self {
        Self::with_instances(name, primitives, Vec::new(), Vec::new(), materials, lights, camera)
    }

    /// [`Scene::new`] with instanced objects: the top-level BVH holds the world primitives and
    /// one leaf per instance (its object's box in world space). Object indices of the instances
    /// must be valid.
    pub fn with_instances(
        name: impl Into<String>,
        primitives: Vec<Primitive>,
        objects: Vec<Object>,
        instances: Vec<Instance>,
        materials: Vec<Material>,
        lights: Vec<Light>,
        camera: Camera,
    ) -> Self {
        let object_bounds: Vec<Aabb> = objects.iter().map(Object::bounds).collect();
        let bounds: Vec<Aabb> = primitives
            .iter()
            .map(|p| p.shape.bounds())
            .chain(instances.iter().map(|i| i.world_bounds(object_bounds[i.object as usize])))
            .collect();
        let scene_box = bounds.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let (center, radius) = if scene_box.is_empty() { (Vec3::ZERO, 1.0) } else { scene_box.bounding_sphere() };
        let background = lights.iter().position(Light::is_environment).map(|i| i as u32);
        let flags: Vec<MaterialFlags> = materials.iter().map(MaterialFlags::of).collect();
        let world_attributes = primitives.iter().map(|p| p.attributes).collect();
        // Triangles that need nothing after the geometric test (no alpha mask, not a fibre, see
        // `alpha_keeps`) are tested by the BVH itself, four at a time.
        let plain_triangle = |id: u32| match primitives.get(id as usize) {
            Some(&Primitive { shape: Shape::Triangle(triangle), alpha: None, material, .. })
                if !flags.get(material as usize).is_some_and(|f| f.fibre) =>
            {
                Some(triangle)
            }
            _ => None,
        };
        #[cfg(feature = "embree")]
        let embree = embree_backend(&primitives, &flags, instances.len());
        #[cfg(feature = "embree")]
        let bvh = if embree.is_some() { Bvh::build(&[]) } else { Bvh::build_with_triangles(&bounds, plain_triangle) };
        #[cfg(not(feature = "embree"))]
        let bvh = Bvh::build_with_triangles(&bounds, plain_triangle);
        let bounding_sphere = BoundingSphere { center, radius };
        // One emitter per light (one id per light: cannot fail).
        let own_groups: Vec<u32> = (0..lights.len() as u32).collect();
        let light_selection = light_selection(&lights, &bounding_sphere, &own_groups).unwrap_or(None);
        Self {
            name: name.into(),
            primitives,
            materials,
            lights,
            camera,
            bounding_sphere,
            background,
            attributes: Vec::new(),
            objects,
            instances,
            alpha_masks: Vec::new(),
            media: Media::default(),
            light_spectra: Vec::new(),
            light_selection,
            light_tree: std::sync::OnceLock::new(),
            flags,
            world_attributes,
            bvh,
            #[cfg(feature = "embree")]
            embree,
        }
    }

    /// The acceleration structure that answers [`Scene::intersect`] and [`Scene::occluded`]:
    /// `"embree"` (feature `embree`, triangle-only scenes, see `docs/embree.md`) or `"bvh"`.
    pub fn accel_backend(&self) -> &'static str {
        #[cfg(feature = "embree")]
        if self.embree.is_some() {
            return "embree";
        }
        "bvh"
    }

    /// What hits need to know of material `index` ([`MaterialFlags`], made with the scene;
    /// [`MaterialFlags::UNKNOWN`] for an index that names no material).
    #[inline]
    pub fn material_flags(&self, index: u32) -> MaterialFlags {
        self.flags.get(index as usize).copied().unwrap_or(MaterialFlags::UNKNOWN)
    }

    /// Sets the surface attributes that primitives refer to.
    pub fn with_attributes(mut self, attributes: Vec<SurfaceAttributes>) -> Self {
        self.attributes = attributes;
        self
    }

    /// Groups the lights into the emitters they came from (`groups[i]`: any id of light `i`'s
    /// emitter, e.g. the shape whose triangles it is) for light selection
    /// ([`light_selection_weights`]). Fails when there is not one id per light.
    pub fn with_light_groups(mut self, groups: &[u32]) -> Result<Self, String> {
        self.light_selection = light_selection(&self.lights, &self.bounding_sphere, groups)?;
        self.light_tree = std::sync::OnceLock::new();
        Ok(self)
    }

    /// Sets the alpha masks that primitives refer to.
    pub fn with_alpha_masks(mut self, alpha_masks: Vec<AlphaMask>) -> Self {
        self.alpha_masks = alpha_masks;
        self
    }

    /// Sets the participating media.
    pub fn with_media(mut self, media: Media) -> Self {
        self.media = media;
        self
    }

    /// Sets the emission spectra of the lights, by light index (a shorter list leaves the
    /// remaining lights without a spectrum).
    pub fn with_light_spectra(mut self, spectra: Vec<Option<LightSpectrum>>) -> Self {
        self.light_spectra = spectra;
        self
    }

    /// The emission spectrum of light `index`, if it has one.
    pub fn light_spectrum(&self, index: u32) -> Option<&LightSpectrum> {
        self.light_spectra.get(index as usize).and_then(Option::as_ref)
    }

    /// Nearest intersection of `ray` (any distance > 0). Hits that a primitive's alpha mask
    /// rejects are skipped (see [`crate::alpha`]).
    ///
    /// Runs compiled for the widest instruction set the processor has ([`math::isa`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        math::isa::dispatch(Intersect { scene: self, ray })
    }

    /// [`Scene::intersect`] compiled for the widest instruction set up to `limit` that the
    /// processor has (for A/B measurements, `vcm bench --accel`; the answer is the same).
    pub fn intersect_at(&self, ray: &Ray, limit: Isa) -> Option<SurfaceHit> {
        math::isa::dispatch_at(limit, Intersect { scene: self, ray })
    }

    /// The body of [`Scene::intersect`], inlined into each instruction set's copy.
    #[inline(always)]
    fn intersect_here(&self, ray: &Ray) -> Option<SurfaceHit> {
        let world_primitives = self.primitives.len() as u32;
        // The object primitive of the nearest instance hit so far: the BVH calls the closure
        // with the nearest distance found so far and keeps only strictly nearer hits, so the
        // last instance hit reported is the nearest one whenever an instance wins.
        let mut object_primitive = 0;
        #[cfg(feature = "embree")]
        if let Some(embree) = &self.embree {
            let (index, distance) = embree.closest_hit(ray, f32::INFINITY)?;
            return Some(self.world_hit(ray, index, distance));
        }
        let (index, distance) = self.bvh.closest_hit_inline(ray, f32::INFINITY, |i, r, t_max| {
            if i < world_primitives {
                let primitive = &self.primitives[i as usize];
                return primitive.shape.intersect(r, t_max).filter(|&t| self.alpha_keeps(primitive, r, t));
            }
            let (primitive, t) = self.instance_hit(i - world_primitives, r, t_max)?;
            object_primitive = primitive;
            Some(t)
        })?;
        if index < world_primitives {
            return Some(self.world_hit(ray, index, distance));
        }
        // An instance: the surface in object space, normals back to world space.
        let position = ray.at(distance);
        let instance = &self.instances[(index - world_primitives) as usize];
        let primitive = &self.objects[instance.object as usize].primitives[object_primitive as usize];
        let local_position = instance.to_object_ray(ray).at(distance);
        let attributes = self.attributes.get(primitive.attributes as usize);
        let (normal, shading_normal, uv, attribute) = self.local_surface(primitive, attributes, local_position);
        let tangent = self.tangent(primitive, local_position, normal);
        Some(SurfaceHit {
            position,
            normal: instance.normal_to_world(normal),
            shading_normal: instance.normal_to_world(shading_normal),
            uv,
            tangent: instance.to_world.transform_vector3(tangent),
            attribute,
            distance,
            primitive: object_primitive,
            material: primitive.material,
            light: None,
        })
    }

    /// The hit on world primitive `index` at `distance` along `ray`.
    #[inline]
    fn world_hit(&self, ray: &Ray, index: u32, distance: f32) -> SurfaceHit {
        let position = ray.at(distance);
        let primitive = &self.primitives[index as usize];
        // Read from its own array, the attributes' index does not wait for `primitive`'s record.
        let attributes = self.world_attributes.get(index as usize).and_then(|&a| self.attributes.get(a as usize));
        let (normal, shading_normal, uv, attribute) = self.local_surface(primitive, attributes, position);
        let tangent = self.tangent(primitive, position, normal);
        SurfaceHit {
            position,
            normal,
            shading_normal,
            uv,
            tangent,
            attribute,
            distance,
            primitive: index,
            material: primitive.material,
            light: primitive.light,
        }
    }

    /// Geometric normal, shading normal, texture coordinates and mesh attribute value of
    /// `primitive` at `position`, the normals in the primitive's own space (world or object).
    /// `attributes` are the primitive's own ([`Primitive::attributes`] looked up).
    #[inline(always)]
    fn local_surface(
        &self,
        primitive: &Primitive,
        attributes: Option<&SurfaceAttributes>,
        position: Vec3,
    ) -> (Vec3, Vec3, Vec2, Rgb) {
        let mut normal = primitive.shape.normal_at(position);
        let mut shading_normal = normal;
        let mut uv = Vec2::ZERO;
        let mut attribute_value = Rgb::BLACK;
        match (&primitive.shape, attributes) {
            (Shape::Triangle(t), Some(SurfaceAttributes::Triangle { normals, uvs, attribute })) => {
                let (b1, b2) = t.barycentrics(position);
                let b0 = 1.0 - b1 - b2;
                if let Some(n) = normals {
                    let interpolated = n[0] * b0 + n[1] * b1 + n[2] * b2;
                    if interpolated.length_squared() > 1e-12 {
                        shading_normal = interpolated.normalize();
                    }
                }
                if let Some(t) = uvs {
                    uv = t[0] * b0 + t[1] * b1 + t[2] * b2;
                }
                if let Some(a) = attribute {
                    attribute_value = a[0] * b0 + a[1] * b1 + a[2] * b2;
                }
            }
            // A triangle without attributes has uv (0, 0): computing barycentrics at every hit
            // costs measurable time, and no texture can be placed on it meaningfully anyway.
            (Shape::Triangle(_), _) => {}
            (Shape::Sphere(s), attributes) => {
                if self.material_flags(primitive.material).reads_uv {
                    uv = s.uv_at(position);
                }
                if matches!(attributes, Some(SurfaceAttributes::FlippedNormal)) {
                    normal = -normal;
                    shading_normal = normal;
                }
            }
            (Shape::Disk(d), _) => {
                if self.material_flags(primitive.material).reads_uv {
                    uv = d.uv_at(position);
                }
            }
        }
        // Normal and bump maps replace the shading normal (in the primitive's own space, where
        // its tangents are).
        if let Some(material) = self.materials.get(primitive.material as usize)
            && material.perturbs_shading_normal()
        {
            shading_normal = self.perturbed_normal(material, primitive, position, normal, shading_normal, uv);
        }
        (normal, shading_normal, uv, attribute_value)
    }

    /// The shading normal of a normal- or bump-mapped `material` at a hit (see
    /// `material/perturb.rs`), with the hit's ∂p/∂u and ∂p/∂v from [`crate::tangent`].
    #[inline(never)]
    fn perturbed_normal(
        &self,
        material: &Material,
        primitive: &Primitive,
        position: Vec3,
        geometric_normal: Vec3,
        shading_normal: Vec3,
        uv: Vec2,
    ) -> Vec3 {
        let (dp_du, dp_dv) = self.differentials(primitive, position, geometric_normal);
        material.perturbed_shading_normal(&SurfaceTangents { geometric_normal, shading_normal, uv, dp_du, dp_dv })
    }

    /// ∂p/∂u and ∂p/∂v of `primitive` at `position` (its own space) from [`crate::tangent`].
    #[inline]
    fn differentials(&self, primitive: &Primitive, position: Vec3, geometric_normal: Vec3) -> (Vec3, Vec3) {
        match (&primitive.shape, self.attributes.get(primitive.attributes as usize)) {
            (Shape::Triangle(t), Some(SurfaceAttributes::Triangle { uvs, .. })) => tangent::triangle(t, *uvs),
            (Shape::Triangle(t), _) => tangent::triangle(t, None),
            (Shape::Sphere(s), _) => tangent::sphere(s, position),
            (Shape::Disk(d), _) => tangent::disk(d, position, geometric_normal),
        }
    }

    /// ∂p/∂u of `primitive` at `position` (its own space) when its material is anisotropic,
    /// zero otherwise.
    #[inline]
    fn tangent(&self, primitive: &Primitive, position: Vec3, geometric_normal: Vec3) -> Vec3 {
        if self.material_flags(primitive.material).anisotropic {
            self.differentials(primitive, position, geometric_normal).0
        } else {
            Vec3::ZERO
        }
    }

    /// True when something blocks the segment from `point` along unit `direction` over the
    /// open interval `(ε, distance − ε)`, ε = [`RAY_EPSILON`]. `distance` may be infinite.
    /// Hits that a primitive's alpha mask rejects do not block (see [`crate::alpha`]).
    #[inline]
    pub fn occluded(&self, point: Vec3, direction: Vec3, distance: f32) -> bool {
        let ray = Ray::new(point + RAY_EPSILON * direction, direction);
        let t_max = distance - 2.0 * RAY_EPSILON;
        if t_max <= 0.0 {
            return false;
        }
        #[cfg(feature = "embree")]
        if let Some(embree) = &self.embree {
            return embree.any_hit(&ray, t_max);
        }
        let world_primitives = self.primitives.len() as u32;
        self.bvh.any_hit(&ray, t_max, |i, r, t| {
            if i < world_primitives {
                let primitive = &self.primitives[i as usize];
                return primitive.shape.intersect(r, t).is_some_and(|t| self.alpha_keeps(primitive, r, t));
            }
            self.instance_blocks(i - world_primitives, r, t)
        })
    }

    /// The nearest hit of instance `index` along the world-space `ray` before `t_max`: the
    /// object primitive and the distance. Not inlined into [`Scene::intersect`]: its per-ray
    /// setup (the object-space ray's splats) would be computed for every ray there, also in
    /// scenes without instances.
    #[inline(never)]
    fn instance_hit(&self, index: u32, ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
        let instance = &self.instances[index as usize];
        self.objects[instance.object as usize]
            .closest_hit(&instance.to_object_ray(ray), t_max, |p, r, t| self.alpha_keeps(p, r, t))
    }

    /// Whether instance `index` blocks the world-space `ray` before `t_max` ([`Scene::occluded`];
    /// not inlined, for the same reason as [`Scene::instance_hit`]).
    #[inline(never)]
    fn instance_blocks(&self, index: u32, ray: &Ray, t_max: f32) -> bool {
        let instance = &self.instances[index as usize];
        self.objects[instance.object as usize]
            .any_hit(&instance.to_object_ray(ray), t_max, |p, r, t| self.alpha_keeps(p, r, t))
    }

    /// Picks a light with `u ∈ [0,1)` ([`light_selection_weights`]): its index, the light,
    /// and the probability of picking it.
    #[inline]
    pub fn pick_light(&self, u: f32) -> Option<(u32, &Light, f32)> {
        let selection = self.light_selection.as_ref()?;
        let (index, probability) = selection.sample(u);
        Some((index as u32, &self.lights[index], probability))
    }

    /// Whether any material is fluorescent (spectral mode then draws its wavelengths in
    /// independent pairs, see [`spectrum::Wavelengths4::paired`]).
    pub fn has_fluorescence(&self) -> bool {
        self.materials.iter().any(|m| m.fluorescence().is_some())
    }

    /// Whether any material has a wavelength-dependent index of refraction (spectral mode then
    /// keeps only the hero wavelength after refracting through it).
    pub fn has_dispersion(&self) -> bool {
        self.materials.iter().any(Material::is_dispersive)
    }

    /// Light `index`'s emitted quantity `rgb` (a radiance, intensity or irradiance one of its
    /// queries returned, linear sRGB) in spectral mode `S`. In RGB mode it is `rgb` itself. In
    /// spectral mode, a light without a spectrum gives the upsampled `rgb` times the colour
    /// space's illuminant; a light with a spectrum `s` gives `s(λ) · k` (per nm), where
    /// `k = rgb / base` is the scalar its query applied to its base value (see
    /// [`LightSpectrum::factor`]).
    #[inline]
    pub fn emission<S: SpectralMode>(&self, index: u32, wavelengths: &S::Wavelengths, rgb: Rgb) -> S {
        match self.light_spectrum(index) {
            Some(s) => {
                let k = s.factor(rgb);
                S::from_function(wavelengths, |lambda| k * s.spectrum.eval(lambda), rgb)
            }
            None => S::from_emission(wavelengths, rgb),
        }
    }

    /// The light sampler that conditions on the receiving point ([`LightTree`]), built on the
    /// first call from [`Scene::lights`] and [`Scene::light_pick_probability`] (changes to
    /// the lights after that call are not seen).
    pub fn light_tree(&self) -> &LightTree {
        self.light_tree
            .get_or_init(|| LightTree::build(&self.lights, &self.bounding_sphere, |i| self.light_pick_probability(i)))
    }

    /// Probability with which [`Scene::pick_light`] picks light `index`.
    #[inline]
    pub fn light_pick_probability(&self, index: u32) -> f32 {
        self.light_selection.as_ref().map_or(0.0, |s| s.probability(index as usize))
    }

    /// The environment light, if any.
    pub fn background_light(&self) -> Option<&Light> {
        self.background.map(|i| &self.lights[i as usize])
    }

    /// Whether the environment light's samples can be prefetched ([`Light::has_prefetch`]): the
    /// test that decides whether a renderer issues [`Light::prefetch_direct`] hints in its path
    /// loops and [`Light::prefetch_emission`] hints in its light pass.
    #[inline]
    pub fn has_prefetchable_background(&self) -> bool {
        self.background_light().is_some_and(Light::has_prefetch)
    }

    /// The material of a hit.
    pub fn material(&self, hit: &SurfaceHit) -> &Material {
        &self.materials[hit.material as usize]
    }
}

/// The emission spectrum of a light and the RGB value the light stores for it.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpectrum {
    /// The emitted spectral quantity (per nm).
    pub spectrum: EmissionSpectrum,
    /// The light's own RGB value (radiance, intensity or irradiance as the light stores it):
    /// every query of the light returns `base` times a non-negative scalar (the spot falloff,
    /// the cosine of an emission sample, 1 otherwise).
    pub base: Rgb,
}

impl LightSpectrum {
    /// The scalar `k` with `rgb = k · base`, recovered from the largest channel of `base`
    /// (any positive channel gives the same ratio, up to rounding, since a query scales all
    /// channels alike; the largest one rounds least). A black `base` gives 0: such a light
    /// emits nothing in RGB mode, and a non-negative spectrum whose colour clamps to black has no
    /// luminance either.
    #[inline]
    pub fn factor(&self, rgb: Rgb) -> f32 {
        let (b, q) = (self.base, rgb);
        let (base, value) = if b.r >= b.g && b.r >= b.b {
            (b.r, q.r)
        } else if b.g >= b.b {
            (b.g, q.g)
        } else {
            (b.b, q.b)
        };
        if base > 0.0 { value / base } else { 0.0 }
    }
}

/// [`Scene::intersect`] as a kernel of [`math::isa::dispatch`].
struct Intersect<'a> {
    scene: &'a Scene,
    ray: &'a Ray,
}

impl Kernel for Intersect<'_> {
    type Output = Option<SurfaceHit>;
    #[inline(always)]
    fn run(self) -> Option<SurfaceHit> {
        self.scene.intersect_here(self.ray)
    }
}

/// The Embree backend for a scene with these world primitives, material flags and number of
/// instances, when it qualifies ([`crate::accel::embree`]) and `VCM_ACCEL=bvh` does not force
/// our BVH. A scene Embree cannot build keeps our BVH.
#[cfg(feature = "embree")]
fn embree_backend(
    primitives: &[Primitive],
    flags: &[MaterialFlags],
    instances: usize,
) -> Option<crate::accel::EmbreeAccel> {
    use crate::accel::embree;
    if !embree::embree_requested() || !embree::qualifies(primitives, flags, instances) {
        return None;
    }
    crate::accel::EmbreeAccel::from_primitives(primitives).ok()
}

/// The light selection distribution over `lights` ([`light_selection_weights`]) with the
/// emitter id `groups[i]` of each light.
fn light_selection(
    lights: &[Light],
    sphere: &BoundingSphere,
    groups: &[u32],
) -> Result<Option<Distribution1D>, String> {
    let powers: Vec<f32> = lights.iter().map(|l| l.power(sphere)).collect();
    Ok(Distribution1D::new(&light_selection_weights(&powers, groups)?))
}
