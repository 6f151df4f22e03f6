//! The four reference Cornell boxes of the VCM literature, built from a bit mask exactly as
//! `shared/scenes/cornell.md` specifies (float32 geometry, materials, lights, camera).

use math::Vec3;
use spectrum::Rgb;

use crate::camera::Camera;
use crate::light::{AreaLight, BackgroundLight, DirectionalLight, Light, PointLight};
use crate::material::{Material, ReferenceMaterial};
use crate::scene::{Primitive, Scene};
use crate::shape::{Shape, Sphere, Triangle};

/// Mask bit: the light box's bottom face emits (or, with [`POINT_LIGHT`], the whole ceiling).
pub const CEILING_LIGHT: u32 = 1;
/// Mask bit: directional "sun".
pub const SUN: u32 = 2;
/// Mask bit: point light (removes the light box).
pub const POINT_LIGHT: u32 = 4;
/// Mask bit: constant environment light.
pub const BACKGROUND: u32 = 8;
/// Mask bit: large mirror sphere.
pub const LARGE_MIRROR_SPHERE: u32 = 16;
/// Mask bit: large glass sphere (ignored when the large mirror is requested too).
pub const LARGE_GLASS_SPHERE: u32 = 32;
/// Mask bit: small mirror sphere on the left.
pub const SMALL_MIRROR_SPHERE: u32 = 64;
/// Mask bit: small glass sphere on the right.
pub const SMALL_GLASS_SPHERE: u32 = 128;
/// Mask bit: glossy floor and blue back wall (otherwise both white).
pub const GLOSSY_FLOOR: u32 = 256;
/// Mask bit (not in the specification): the large sphere is fluorescent (absorbs violet and
/// blue, 370–490 nm, and glows green-yellow, 510–610 nm; see [`fluorescent_sphere`]) and the
/// light box emits a blue-ish white.
pub const FLUORESCENT: u32 = 512;

/// A built-in scene reachable by id and name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuiltinScene {
    /// Numeric id (0–3).
    pub id: u32,
    /// Name accepted by `--scene`.
    pub name: &'static str,
    /// The mask it is built from.
    pub mask: u32,
    /// One-line description.
    pub description: &'static str,
}

/// The four reference scenes, in id order.
pub const BUILTIN_SCENES: [BuiltinScene; 4] = [
    BuiltinScene {
        id: 0,
        name: "cornell-sun",
        mask: 450,
        description: "glossy floor, mirror and glass spheres, directional sun through the open front",
    },
    BuiltinScene {
        id: 1,
        name: "cornell-area-mirror",
        mask: 273,
        description: "glossy floor, large mirror sphere, area light under the ceiling",
    },
    BuiltinScene {
        id: 2,
        name: "cornell-point",
        mask: 452,
        description: "glossy floor, mirror and glass spheres, point light",
    },
    BuiltinScene {
        id: 3,
        name: "cornell-env",
        mask: 456,
        description: "glossy floor, mirror and glass spheres, constant sky-blue environment",
    },
];

/// Scenes beyond the four references, reachable by id and name.
pub const EXTRA_SCENES: [BuiltinScene; 1] = [BuiltinScene {
    id: 4,
    name: "cornell-fluorescent",
    mask: FLUORESCENT | CEILING_LIGHT,
    description: "fluorescent sphere under a blue-ish area light (fluorescence; best with --spectral)",
}];

/// Every built-in scene: the four references, then the extras.
pub fn builtin_scenes() -> impl Iterator<Item = &'static BuiltinScene> {
    BUILTIN_SCENES.iter().chain(EXTRA_SCENES.iter())
}

/// The fluorescent material of [`FLUORESCENT`]: diagonal reflectance 0.25, 90 % absorption at
/// 430 nm (raised-cosine band 370–490 nm), 70 % of the absorbed energy re-emitted around
/// 560 nm (510–610 nm). A kernel column sums to at most 0.25 + 0.7·0.9 = 0.88.
pub fn fluorescent_sphere() -> Material {
    use spectrum::fluorescence::{Band, Fluorescence};
    let fluorescence = Fluorescence::new(
        0.9,
        Band { center_nm: 430.0, half_width_nm: 60.0 },
        Band { center_nm: 560.0, half_width_nm: 50.0 },
        0.7,
    )
    .expect("valid built-in fluorescence");
    Material::Fluorescent { reflectance: crate::texture::Texture::Constant(Rgb::splat(0.25)), fluorescence }
}

/// Blue-ish white of the light box in the fluorescent scene (times its radiance).
const FLUORESCENT_LIGHT_TINT: Rgb = Rgb::new(0.45, 0.6, 1.0);

/// Largest valid mask value (all bits set).
pub const MAX_MASK: u32 = 1023;

/// Radiance of the light-box emitter (scene 1): 25.03329895614464 in every channel.
pub const LIGHT_BOX_RADIANCE: f32 = f32::from_bits(0x41c8_4432); // 0x1.908864p+4 = 25.0332985

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Builds the Cornell box for a scene `mask` (see the constants) at the given resolution.
/// Returns `None` for a mask outside `0..=1023`.
pub fn build(mask: u32, width: u32, height: u32) -> Option<Scene> {
    if mask > MAX_MASK {
        return None;
    }
    let has = |bit: u32| mask & bit != 0;

    // Materials M0–M8 (cornell.md §3.5).
    let grey = |x: f32| Rgb::splat(x);
    let materials = vec![
        ReferenceMaterial::BLACK, // M0 emitter triangle 1
        ReferenceMaterial::BLACK, // M1 emitter triangle 2
        ReferenceMaterial { diffuse: grey(0.1), phong: grey(0.7), phong_exponent: 90.0, ..ReferenceMaterial::BLACK }, // M2 glossy floor
        ReferenceMaterial::diffuse(Rgb::new(0.156863, 0.803922, 0.172549)), // M3 green
        ReferenceMaterial::diffuse(Rgb::new(0.803922, 0.152941, 0.152941)), // M4 red
        ReferenceMaterial::diffuse(grey(0.803922)),                         // M5 white
        ReferenceMaterial { mirror: grey(1.0), ..ReferenceMaterial::BLACK }, // M6 mirror
        ReferenceMaterial { mirror: grey(1.0), ior: 1.6, ..ReferenceMaterial::BLACK }, // M7 glass
        ReferenceMaterial::diffuse(Rgb::new(0.156863, 0.172549, 0.803922)), // M8 blue
    ];
    const M0: u32 = 0;
    const M1: u32 = 1;
    const GLOSSY: u32 = 2;
    const GREEN: u32 = 3;
    const RED: u32 = 4;
    const WHITE: u32 = 5;
    const MIRROR: u32 = 6;
    const GLASS: u32 = 7;
    const BLUE: u32 = 8;
    const FLUORESCENT_SPHERE: u32 = 9;

    // Box corners (§3.2).
    let c = [
        v(-1.27029, 1.30455, -1.28002),
        v(1.28975, 1.30455, -1.28002),
        v(1.28975, 1.30455, 1.28002),
        v(-1.27029, 1.30455, 1.28002),
        v(-1.27029, -1.25549, -1.28002),
        v(1.28975, -1.25549, -1.28002),
        v(1.28975, -1.25549, 1.28002),
        v(-1.27029, -1.25549, 1.28002),
    ];
    let glossy = has(GLOSSY_FLOOR);
    let floor_material = if glossy { GLOSSY } else { WHITE };
    let back_material = if glossy { BLUE } else { WHITE };
    let whole_ceiling_emits = has(CEILING_LIGHT) && has(POINT_LIGHT);

    let mut primitives = Vec::new();
    let mut lights = Vec::new();
    let triangle = |p0: Vec3, p1: Vec3, p2: Vec3, material: u32| {
        Primitive::new(Shape::Triangle(Triangle::new(p0, p1, p2)), material, None)
    };

    primitives.push(triangle(c[0], c[4], c[5], floor_material));
    primitives.push(triangle(c[5], c[1], c[0], floor_material));
    primitives.push(triangle(c[0], c[1], c[2], back_material));
    primitives.push(triangle(c[2], c[3], c[0], back_material));
    if whole_ceiling_emits {
        primitives.push(triangle(c[2], c[6], c[7], M0));
        primitives.push(triangle(c[7], c[3], c[2], M1));
    } else {
        primitives.push(triangle(c[2], c[6], c[7], WHITE));
        primitives.push(triangle(c[7], c[3], c[2], WHITE));
    }
    primitives.push(triangle(c[3], c[7], c[4], GREEN));
    primitives.push(triangle(c[4], c[0], c[3], GREEN));
    primitives.push(triangle(c[1], c[5], c[6], RED));
    primitives.push(triangle(c[6], c[2], c[1], RED));

    // Spheres (§3.3), derived from the corners in float32.
    let left_x = c[0].x;
    let right_x = c[1].x;
    let floor_z = c[0].z;
    let width_x = right_x - left_x;
    let mid_y = (c[0].y + c[4].y) * 0.5;
    let small_radius = 0.5f32;
    let large_radius = 0.8f32;
    let small_z = floor_z + small_radius;
    let floor_mean = (c[0] + c[4] + c[5] + c[1]) * 0.25;
    let large_center = v(floor_mean.x, floor_mean.y, floor_z + large_radius);
    let sphere = |center: Vec3, radius: f32, material: u32| {
        Primitive::new(Shape::Sphere(Sphere { center, radius }), material, None)
    };
    if has(FLUORESCENT) {
        primitives.push(sphere(large_center, large_radius, FLUORESCENT_SPHERE));
    } else if has(LARGE_MIRROR_SPHERE) {
        primitives.push(sphere(large_center, large_radius, MIRROR));
    } else if has(LARGE_GLASS_SPHERE) {
        primitives.push(sphere(large_center, large_radius, GLASS));
    }
    if has(SMALL_MIRROR_SPHERE) {
        primitives.push(sphere(v(left_x + 2.0 * width_x / 7.0, mid_y, small_z), small_radius, MIRROR));
    }
    if has(SMALL_GLASS_SPHERE) {
        primitives.push(sphere(v(right_x - 2.0 * width_x / 7.0, mid_y, small_z), small_radius, GLASS));
    }

    // Light box (§3.4), absent with the point light.
    let light_box_emits = has(CEILING_LIGHT) && !has(POINT_LIGHT);
    if !has(POINT_LIGHT) {
        let l = [
            v(-0.25, 0.25, 1.26002),
            v(0.25, 0.25, 1.26002),
            v(0.25, 0.25, 1.28002),
            v(-0.25, 0.25, 1.28002),
            v(-0.25, -0.25, 1.26002),
            v(0.25, -0.25, 1.26002),
            v(0.25, -0.25, 1.28002),
            v(-0.25, -0.25, 1.28002),
        ];
        let mut light_box = |p0: Vec3, p1: Vec3, p2: Vec3, material: u32| {
            primitives.push(Primitive::new(Shape::Triangle(Triangle::new(p0, p1, p2)), material, None))
        };
        light_box(l[0], l[2], l[1], WHITE);
        light_box(l[2], l[0], l[3], WHITE);
        light_box(l[3], l[4], l[7], WHITE);
        light_box(l[4], l[3], l[0], WHITE);
        light_box(l[1], l[6], l[5], WHITE);
        light_box(l[6], l[1], l[2], WHITE);
        light_box(l[4], l[5], l[6], WHITE);
        light_box(l[6], l[7], l[4], WHITE);
        if light_box_emits {
            light_box(l[0], l[5], l[4], M0);
            light_box(l[5], l[0], l[1], M1);
        } else {
            light_box(l[0], l[5], l[4], WHITE);
            light_box(l[5], l[0], l[1], WHITE);
        }
    }

    // Lights in the order area(s), sun, point, background (§3.8).
    let emitter_radiance =
        if whole_ceiling_emits { Rgb::splat(3.0 / math::PI) } else { Rgb::splat(LIGHT_BOX_RADIANCE) };
    let emitter_radiance = if has(FLUORESCENT) { emitter_radiance * FLUORESCENT_LIGHT_TINT } else { emitter_radiance };
    if whole_ceiling_emits || light_box_emits {
        let n = primitives.len();
        let emitters = if whole_ceiling_emits { [4, 5] } else { [n - 2, n - 1] };
        for index in emitters {
            let Shape::Triangle(t) = primitives[index].shape else { unreachable!("emitters are triangles") };
            primitives[index].light = Some(lights.len() as u32);
            lights.push(Light::Area(AreaLight::new(t, emitter_radiance)));
        }
    }
    if has(SUN) {
        lights.push(Light::Directional(DirectionalLight::new(v(-1.0, 1.5, -1.0), Rgb::new(0.5, 0.2, 0.0) * 20.0)));
    }
    if has(POINT_LIGHT) {
        lights.push(Light::Point(PointLight {
            position: v(0.0, -0.5, 1.0),
            intensity: Rgb::splat(70.0 * (0.25 * math::INV_PI)),
        }));
    }
    if has(BACKGROUND) {
        lights.push(Light::Background(BackgroundLight { radiance: Rgb::new(135.0, 206.0, 250.0) / 255.0 }));
    }

    // Camera (§3.7).
    let camera = Camera::new(
        v(-0.0439815, -4.12529, 0.222539),
        v(0.00688625, 0.998505, -0.0542161),
        v(3.73896e-4, 0.0542148, 0.998529),
        45.0,
        width,
        height,
    );
    let name = builtin_scenes()
        .find(|s| s.mask == mask)
        .map_or_else(|| format!("cornell-mask-{mask}"), |s| s.name.to_string());
    let mut materials: Vec<Material> = materials.into_iter().map(Material::from).collect();
    if has(FLUORESCENT) {
        materials.push(fluorescent_sphere());
    }
    Some(Scene::new(name, primitives, materials, lights, camera))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::Light;
    use crate::shape::Shape;

    fn bits(v: Vec3) -> [u32; 3] {
        [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]
    }

    fn spheres(scene: &Scene) -> Vec<(Vec3, f32, u32)> {
        scene
            .primitives
            .iter()
            .filter_map(|p| match p.shape {
                Shape::Sphere(s) => Some((s.center, s.radius, p.material)),
                Shape::Triangle(_) | Shape::Disk(_) => None,
            })
            .collect()
    }

    #[test]
    fn sphere_centres_are_bit_exact() {
        // cornell.md §3.3, hex floats.
        let small_mirror =
            Vec3::new(-f32::from_bits(0x3f09_f213), f32::from_bits(0x3cc8_f340), -f32::from_bits(0x3f47_af64));
        let small_glass =
            Vec3::new(f32::from_bits(0x3f0e_ed67), f32::from_bits(0x3cc8_f340), -f32::from_bits(0x3f47_af64));
        let large = Vec3::new(f32::from_bits(0x3c1f_6a80), f32::from_bits(0x3cc8_f340), -f32::from_bits(0x3ef5_c52e));
        let s0 = spheres(&build(450, 8, 8).unwrap());
        assert_eq!(s0.len(), 2);
        assert_eq!(bits(s0[0].0), bits(small_mirror), "{:?}", s0[0].0);
        assert_eq!(bits(s0[1].0), bits(small_glass), "{:?}", s0[1].0);
        let s1 = spheres(&build(273, 8, 8).unwrap());
        assert_eq!(s1.len(), 1);
        assert_eq!(bits(s1[0].0), bits(large), "{:?}", s1[0].0);
        assert_eq!(s1[0].1.to_bits(), 0x3f4c_cccd, "radius 0.8 = 0x1.99999ap-1");
    }

    #[test]
    fn bounding_sphere_is_bit_exact_in_all_scenes() {
        for s in BUILTIN_SCENES {
            let scene = build(s.mask, 8, 8).unwrap();
            let b = scene.bounding_sphere;
            assert_eq!(bits(b.center), [0x3c1f_6a80, 0x3cc8_f340, 0], "{}: {:?}", s.name, b.center);
            assert_eq!(b.radius.to_bits(), 0x400d_e44e, "{}: R = {}", s.name, b.radius);
        }
    }

    #[test]
    fn lights_match_the_specification() {
        let sun = build(450, 8, 8).unwrap();
        assert_eq!(sun.lights.len(), 1);
        let Light::Directional(d) = sun.lights[0] else { panic!("scene 0 has a sun") };
        assert_eq!(bits(d.direction), [0xbef8_5b43, 0x3f3a_4472, 0xbef8_5b43], "{:?}", d.direction);
        assert_eq!(d.irradiance.to_array(), [10.0, 4.0, 0.0]);

        let area = build(273, 8, 8).unwrap();
        assert_eq!(area.lights.len(), 2);
        for light in &area.lights {
            let Light::Area(a) = light else { panic!("scene 1 has area lights") };
            assert_eq!(a.radiance.r.to_bits(), 0x41c8_4432);
            assert!((a.triangle().unwrap().area() - 0.125).abs() < 1e-7);
            assert_eq!(a.triangle().unwrap().normal, -Vec3::Z);
        }

        let point = build(452, 8, 8).unwrap();
        let Light::Point(p) = point.lights[0] else { panic!("scene 2 has a point light") };
        assert_eq!(p.intensity.r.to_bits(), 0x40b2_40e7, "70/(4π) = 0x1.6481cep+2");
        assert!(point.primitives.len() == 12, "no light box with the point light");

        let env = build(456, 8, 8).unwrap();
        let Light::Background(b) = env.lights[0] else { panic!("scene 3 has a background") };
        assert_eq!(bits(Vec3::new(b.radiance.r, b.radiance.g, b.radiance.b)), [0x3f07_8788, 0x3f4e_cecf, 0x3f7a_fafb]);
    }

    #[test]
    fn box_normals_point_inward_and_counts_match() {
        let scene = build(450, 8, 8).unwrap();
        // 10 box triangles, 2 spheres, 10 light-box triangles.
        assert_eq!(scene.primitives.len(), 22);
        let center = Vec3::new(0.00973, 0.02453, 0.0);
        for p in &scene.primitives[..10] {
            let Shape::Triangle(t) = p.shape else { panic!() };
            assert!(t.normal.dot(center - t.p0) > 0.0, "box normals point into the box");
        }
        assert!(build(MAX_MASK + 1, 8, 8).is_none());
        // The fluorescent variant: the large sphere is fluorescent and the only extra material.
        let fluorescent = build(FLUORESCENT | CEILING_LIGHT, 8, 8).unwrap();
        assert!(fluorescent.has_fluorescence() && !scene.has_fluorescence());
        assert_eq!(fluorescent.materials.len(), scene.materials.len() + 1);
        // Ceiling + point: the whole ceiling emits 3/π.
        let both = build(1 | 4, 8, 8).unwrap();
        assert_eq!(both.lights.len(), 3);
        assert_eq!(both.primitives[4].light, Some(0));
        assert_eq!(both.primitives[5].light, Some(1));
    }
}
