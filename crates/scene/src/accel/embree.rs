//! An optional Embree 3 backend for the ray queries of triangle-only scenes (cargo feature
//! `embree`, system library `libembree-dev`; see `docs/embree.md`).
//!
//! [`EmbreeAccel`] puts every triangle into one Embree triangle mesh whose primitive id is the
//! triangle's index in the caller's list, commits it, and answers the two queries our own
//! [`super::Bvh`] answers for such scenes: the nearest hit (primitive index and distance) and
//! whether anything blocks a segment. Everything else about a hit (position, normals, uvs) stays
//! the caller's. [`crate::Scene`] uses it when every world primitive is a triangle, no primitive
//! has an alpha mask or a fibre material and there are no instances, unless the environment
//! variable `VCM_ACCEL=bvh` asks for our BVH ([`embree_requested`]).
//!
//! Interval conventions, as ours: the nearest hit accepts `0 < t < t_max`, the blocker test
//! `0 < t < t_max` (Embree accepts `tnear < t ≤ tfar`, so `tfar` is one ulp below `t_max`).
//! Of hits at exactly the same distance Embree may return any; ours returns the smallest index.
//!
//! Lifetimes: the safe binding ties a committed scene to a borrow of the scene and the scene to
//! a borrow of the device, so both are leaked (`Box::leak`): the device once per process, every
//! Embree scene for the rest of the process (the CLI builds one scene per run; tests and
//! benchmarks that build many scenes keep their memory). No `unsafe` code is needed.

use std::sync::OnceLock;

use ::embree::{CommittedScene, Device, Geometry, IntersectContext, RayHit, TriangleMesh};
use math::{Ray, Vec3};

use crate::Primitive;
use crate::material::MaterialFlags;
use crate::shape::Shape;

/// The environment variable that selects the backend: `bvh` forces our BVH; anything else
/// (or unset) lets qualifying scenes use Embree.
pub const ACCEL_ENV: &str = "VCM_ACCEL";

/// Whether the environment lets qualifying scenes use Embree (`VCM_ACCEL` is not `bvh`).
pub fn embree_requested() -> bool {
    std::env::var(ACCEL_ENV).map_or(true, |v| !v.trim().eq_ignore_ascii_case("bvh"))
}

/// The process's Embree device (created on first use, never released).
fn device() -> &'static Device {
    static DEVICE: OnceLock<&'static Device> = OnceLock::new();
    DEVICE.get_or_init(|| Box::leak(Box::new(Device::new())))
}

/// A committed Embree scene over a list of triangles, answering nearest-hit and blocker queries
/// by triangle index. Shared by all threads (Embree's queries are thread-safe and the binding's
/// committed scene is `Sync`).
pub struct EmbreeAccel {
    /// The committed scene (its scene and device are leaked, see the module docs).
    scene: CommittedScene<'static>,
    /// Number of triangles (primitive ids are `0..triangles`).
    triangles: usize,
}

impl std::fmt::Debug for EmbreeAccel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmbreeAccel").field("triangles", &self.triangles).finish()
    }
}

/// Whether a scene with these world primitives, material flags (by material index) and number
/// of instances can use Embree: all triangles, no alpha masks, no fibre materials, no instances.
pub(crate) fn qualifies(primitives: &[Primitive], flags: &[MaterialFlags], instances: usize) -> bool {
    instances == 0
        && !primitives.is_empty()
        && primitives.iter().all(|p| {
            matches!(p.shape, Shape::Triangle(_))
                && p.alpha.is_none()
                && !flags.get(p.material as usize).is_some_and(|f| f.fibre)
        })
}

impl EmbreeAccel {
    /// Builds and commits an Embree scene over `triangles` (vertices `[p0, p1, p2]`, world
    /// units); primitive ids are indices into the slice. Errors when the list is empty or has
    /// more triangles than Embree's 32-bit ids allow. Degenerate triangles and triangles with
    /// non-finite vertices are never hit (Embree skips them).
    pub fn build(triangles: &[[Vec3; 3]]) -> Result<EmbreeAccel, String> {
        if triangles.is_empty() {
            return Err("an Embree scene needs at least one triangle".into());
        }
        if triangles.len() >= (u32::MAX / 3) as usize {
            return Err(format!("{} triangles are too many for one Embree mesh", triangles.len()));
        }
        let device = device();
        let mut mesh = TriangleMesh::unanimated(device, triangles.len(), 3 * triangles.len());
        {
            let mut vertices = mesh.vertex_buffer.map();
            for (i, tri) in triangles.iter().enumerate() {
                for (k, p) in tri.iter().enumerate() {
                    let v = &mut vertices[3 * i + k];
                    v.x = p.x;
                    v.y = p.y;
                    v.z = p.z;
                    v.w = 0.0;
                }
            }
        }
        {
            let mut indices = mesh.index_buffer.map();
            for i in 0..triangles.len() {
                let t = &mut indices[i];
                let first = 3 * i as u32;
                t.x = first;
                t.y = first + 1;
                t.z = first + 2;
            }
        }
        let mut geometry = Geometry::Triangle(mesh);
        geometry.commit();
        let scene: &'static mut ::embree::Scene<'static> = Box::leak(Box::new(::embree::Scene::new(device)));
        scene.attach_geometry(geometry);
        let scene: &'static ::embree::Scene<'static> = scene;
        Ok(EmbreeAccel { scene: scene.commit(), triangles: triangles.len() })
    }

    /// Builds the scene over world primitives that all are triangles (see [`qualifies`]).
    pub(crate) fn from_primitives(primitives: &[Primitive]) -> Result<EmbreeAccel, String> {
        let triangles: Vec<[Vec3; 3]> = primitives
            .iter()
            .map(|p| match p.shape {
                Shape::Triangle(t) => Ok([t.p0, t.p1, t.p2]),
                _ => Err("Embree holds only triangles".to_string()),
            })
            .collect::<Result<_, _>>()?;
        EmbreeAccel::build(&triangles)
    }

    /// Number of triangles in the scene.
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// Whether the scene has no triangles (never: [`EmbreeAccel::build`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.triangles == 0
    }

    /// The Embree ray for `ray` over `(0, tfar]`; `None` for a ray with a non-finite origin
    /// or direction (which our BVH never hits either).
    #[inline(always)]
    fn embree_ray(ray: &Ray, tfar: f32) -> Option<::embree::Ray> {
        let (o, d) = (ray.origin, ray.direction);
        if !(o.is_finite() && d.is_finite()) {
            return None;
        }
        Some(::embree::sys::RTCRay {
            org_x: o.x,
            org_y: o.y,
            org_z: o.z,
            tnear: 0.0,
            dir_x: d.x,
            dir_y: d.y,
            dir_z: d.z,
            time: 0.0,
            tfar,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        })
    }

    /// Nearest hit along `ray` at a distance `0 < t < t_max` (ray parameter units; `t_max`
    /// may be `+∞`): the triangle index and the distance.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
        if t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let mut query = RayHit::new(Self::embree_ray(ray, below(t_max))?);
        self.scene.intersect(&mut IntersectContext::incoherent(), &mut query);
        query.hit.hit().then_some((query.hit.primID, query.ray.tfar))
    }

    /// Whether any triangle intersects `ray` at some `0 < t < t_max` (shadow rays).
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f32) -> bool {
        if t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        let Some(mut query) = Self::embree_ray(ray, below(t_max)) else { return false };
        self.scene.occluded(&mut IntersectContext::incoherent(), &mut query);
        // Embree marks a blocked ray by setting tfar to −∞.
        query.tfar == f32::NEG_INFINITY
    }
}

/// Embree's `tfar` for our open bound `t_max > 0`: Embree accepts `t ≤ tfar`, so the largest
/// `f32` below a finite `t_max` (`+∞` stays `+∞`).
#[inline(always)]
fn below(t_max: f32) -> f32 {
    if t_max.is_finite() { f32::from_bits(t_max.to_bits() - 1) } else { t_max }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Bvh;
    use crate::shape::Triangle;
    use math::{Aabb, Rng, warp};

    /// Both sides are `Sync + Send`, so rayon threads can share the committed scene.
    #[test]
    fn embree_accel_is_shareable() {
        fn shareable<T: Sync + Send>() {}
        shareable::<EmbreeAccel>();
        shareable::<crate::Scene>();
    }

    fn random_point(rng: &mut Rng) -> Vec3 {
        Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - Vec3::ONE
    }

    /// `n` random triangles in `[-1, 1]³` with edges up to ~0.3.
    fn soup(n: usize) -> Vec<Triangle> {
        let mut rng = Rng::for_stream(11, 0, 0);
        (0..n)
            .map(|_| {
                let c = random_point(&mut rng);
                Triangle::new(c, c + 0.15 * random_point(&mut rng), c + 0.15 * random_point(&mut rng))
            })
            .collect()
    }

    /// Compares Embree over `theirs` with our BVH over `tris` on `rays` closest-hit rays and as
    /// many shadow segments between random points; returns (closest mismatches, shadow
    /// mismatches, hits, blocked).
    fn compare(tris: &[Triangle], theirs: &[Triangle], rays: usize) -> (usize, usize, usize, usize) {
        let bounds: Vec<Aabb> = tris.iter().map(|t| Shape::Triangle(*t).bounds()).collect();
        let bvh = Bvh::build(&bounds);
        let verts: Vec<[Vec3; 3]> = theirs.iter().map(|t| [t.p0, t.p1, t.p2]).collect();
        let embree = EmbreeAccel::build(&verts).expect("an Embree scene");
        let shapes: Vec<Shape> = tris.iter().map(|t| Shape::Triangle(*t)).collect();
        let ours = |ray: &Ray, t_max: f32| bvh.closest_hit(ray, t_max, |i, r, t| shapes[i as usize].intersect(r, t));
        let ours_any =
            |ray: &Ray, t_max: f32| bvh.any_hit(ray, t_max, |i, r, t| shapes[i as usize].intersect(r, t).is_some());
        let (mut closest_bad, mut shadow_bad, mut hits, mut blocked) = (0, 0, 0, 0);
        for i in 0..rays {
            let mut rng = Rng::for_stream(12, 0, i as u64);
            let ray = Ray::new(random_point(&mut rng) * 1.2, warp::uniform_sphere(rng.uniform2()));
            let (a, b) = (ours(&ray, f32::INFINITY), embree.closest_hit(&ray, f32::INFINITY));
            hits += a.is_some() as usize;
            let same = match (a, b) {
                (None, None) => true,
                (Some((pa, ta)), Some((pb, tb))) => {
                    // Relative 1e-5, but at least 1e-5 of the coordinates' magnitude (~1): the
                    // rounding error of a distance is ε times the coordinates, not times the
                    // distance, so very short hits (origins next to a triangle) differ by
                    // ~1e-9 absolute. Two triangles at the same distance (a tie or a shared
                    // point) may be returned by either.
                    (ta - tb).abs() <= 1e-5 * ta.max(tb).max(1.0)
                        && (pa == pb || shapes[pb as usize].intersect(&ray, ta * 1.00001).is_some())
                }
                _ => false,
            };
            closest_bad += !same as usize;
            if !same && closest_bad <= 5 {
                eprintln!("closest hits differ on {ray:?}: ours {a:?}, Embree {b:?}");
            }
            let (p, q) = (random_point(&mut rng), random_point(&mut rng));
            let length = (q - p).length();
            let shadow = Ray::new(p, (q - p) / length);
            let blocker = ours_any(&shadow, length);
            blocked += blocker as usize;
            shadow_bad += (blocker != embree.any_hit(&shadow, length)) as usize;
        }
        (closest_bad, shadow_bad, hits, blocked)
    }

    /// 100k random rays on a random triangle soup: the same triangle and distance (relative
    /// 1e-5) and the same blocker answers. Rays that graze an edge can legitimately differ
    /// between two watertight-ish intersectors; we allow none here and report any.
    #[test]
    fn embree_matches_bvh_on_random_soup() {
        let tris = soup(20_000);
        let (closest_bad, shadow_bad, hits, blocked) = compare(&tris, &tris, 100_000);
        assert!(hits > 30_000 && blocked > 30_000, "too few hits to compare: {hits} hits, {blocked} blocked");
        assert_eq!(closest_bad, 0, "closest hits differ on {closest_bad} of 100000 rays");
        assert_eq!(shadow_bad, 0, "blocker answers differ on {shadow_bad} of 100000 segments");
    }

    /// Power check: Embree over the soup moved by 1e-4 along z (a small bias in every hit
    /// distance) fails the comparison above on many rays.
    #[test]
    fn comparison_detects_a_small_shift() {
        let tris = soup(20_000);
        let shift = Vec3::new(0.0, 0.0, 1e-4);
        let moved: Vec<Triangle> =
            tris.iter().map(|t| Triangle::new(t.p0 + shift, t.p1 + shift, t.p2 + shift)).collect();
        let (closest_bad, _, hits, _) = compare(&tris, &moved, 20_000);
        assert!(closest_bad > hits / 4, "a 1e-4 shift went unnoticed: {closest_bad} of {hits} hits differ");
    }

    /// Edge cases: empty input is an error; rays with NaNs, zero or negative `t_max` miss.
    #[test]
    fn bad_input() {
        assert!(EmbreeAccel::build(&[]).is_err());
        let tri = [Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 1.0)];
        let embree = EmbreeAccel::build(&[tri]).expect("an Embree scene");
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(embree.closest_hit(&ray, f32::INFINITY).map(|h| h.0), Some(0));
        assert!((embree.closest_hit(&ray, f32::INFINITY).map_or(0.0, |h| h.1) - 1.0).abs() < 1e-6);
        assert!(embree.closest_hit(&ray, 0.5).is_none());
        assert!(embree.any_hit(&ray, 2.0));
        assert!(!embree.any_hit(&ray, 1.0), "the interval is open at t_max");
        assert!(!embree.any_hit(&ray, 0.0) && embree.closest_hit(&ray, -1.0).is_none());
        assert!(embree.closest_hit(&ray, f32::NAN).is_none());
        let nan = Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z);
        assert!(embree.closest_hit(&nan, f32::INFINITY).is_none() && !embree.any_hit(&nan, 2.0));
    }
}
